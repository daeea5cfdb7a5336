"""Private files and folders: the data folder is 0700, database and outbox files 0600.

A file is created with its final mode (never world-readable for an instant) and an existing one is
tightened. SQLite creates its ``-wal`` and ``-shm`` files with the mode of the database file, so a
database created here stays private with its journals; journals already present are tightened too.
"""

from __future__ import annotations

import os
from pathlib import Path

PRIVATE_DIR_MODE = 0o700
PRIVATE_FILE_MODE = 0o600
SQLITE_SIDE_FILES = ("-wal", "-shm", "-journal")


def private_dir(path: Path | str) -> Path:
    """Create *path* (and missing parents) and make it 0700 (owner only); the path."""
    folder = Path(path)
    folder.mkdir(parents=True, exist_ok=True, mode=PRIVATE_DIR_MODE)
    os.chmod(folder, PRIVATE_DIR_MODE)
    return folder


def private_file(path: Path | str) -> Path:
    """Create *path* empty with mode 0600 when missing, else tighten it to 0600; the path."""
    file = Path(path)
    fd = os.open(file, os.O_WRONLY | os.O_CREAT, PRIVATE_FILE_MODE)
    os.close(fd)
    os.chmod(file, PRIVATE_FILE_MODE)
    return file


def private_sqlite(path: Path | str) -> Path:
    """:func:`private_file` for an SQLite database and the journal files beside it that exist."""
    file = private_file(path)
    for suffix in SQLITE_SIDE_FILES:
        side = file.with_name(file.name + suffix)
        if side.exists():
            os.chmod(side, PRIVATE_FILE_MODE)
    return file


def write_private_text(path: Path | str, text: str) -> Path:
    """Write *text* to *path* with mode 0600 (replacing what was there); the path."""
    file = Path(path)
    fd = os.open(file, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, PRIVATE_FILE_MODE)
    with os.fdopen(fd, "w", encoding="utf-8") as out:
        out.write(text)
    os.chmod(file, PRIVATE_FILE_MODE)
    return file
