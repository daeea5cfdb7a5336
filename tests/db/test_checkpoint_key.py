"""The checkpoint key: made whole before anyone can read it, and never used when it is not a whole key."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from db.chain_audit import CHECKPOINT_KEY_FILE, checkpoint_key


def test_a_new_key_is_32_random_bytes_in_a_private_file(tmp_path: Path) -> None:
    key = checkpoint_key(tmp_path, create=True)
    assert key is not None and len(key) == 32
    assert checkpoint_key(tmp_path, create=False) == key
    assert (tmp_path / CHECKPOINT_KEY_FILE).stat().st_mode & 0o777 == 0o600
    assert [p.name for p in tmp_path.iterdir()] == [CHECKPOINT_KEY_FILE]  # nothing left beside it


@pytest.mark.parametrize("content", [b"", b"\n", b"abcd\n"])
def test_a_key_file_that_is_not_a_whole_key_is_never_used(tmp_path: Path, content: bytes) -> None:
    # what a reader sees of a key file another process has created but not yet written
    path = tmp_path / CHECKPOINT_KEY_FILE
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    os.write(fd, content)
    os.close(fd)
    for create in (True, False):
        with pytest.raises(ValueError, match="checkpoint key"):
            checkpoint_key(tmp_path, create=create)
