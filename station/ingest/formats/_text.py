"""Shared reading of text measurement files: bounded size, strict UTF-8, instants, error factories."""

from __future__ import annotations

import datetime as dt
import functools
from pathlib import Path

from station.ingest.errors import ImportFileError

#: Largest measurement file read, bytes (a 12-geometry, 81-band file of 1000 samples is ≈ 10 MB).
MAX_FILE_BYTES = 64 << 20


def read_bytes(
    path: Path, error: type[ImportFileError], data: bytes | None = None, limit: int = MAX_FILE_BYTES
) -> bytes:
    """The bytes of *path* (or *data*, already read from it), refusing a missing, unreadable or
    oversized file (more than *limit* bytes) with *error*."""
    if data is not None:
        if len(data) > limit:
            raise error(path.name, "", "file", f"at most {limit} bytes", len(data))
        return data
    try:
        size = path.stat().st_size
        if size > limit:
            raise error(path.name, "", "file", f"at most {limit} bytes", size)
        with path.open("rb") as fh:
            out = fh.read(limit + 1)
    except OSError as exc:
        raise error(path.name, "", "file", "a readable file", str(exc)) from exc
    if len(out) > limit:  # grew since stat
        raise error(path.name, "", "file", f"at most {limit} bytes", len(out))
    return out


def decode_utf8(data: bytes, file: str, error: type[ImportFileError]) -> str:
    """*data* as UTF-8 (a byte-order mark is allowed); else *error* naming the line and byte offset."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise error(
            file, f"line {line}", "encoding", "UTF-8 (or ASCII) text", f"byte 0x{data[exc.start]:02x}"
        ) from exc


def parse_instant(text: str) -> dt.datetime | None:
    """An ISO 8601 instant (naive means UTC) or ``None`` when *text* is not one."""
    t = text.strip()
    if not t:
        return None
    try:
        value = dt.datetime.fromisoformat(t.replace("Z", "+00:00"))
    except ValueError:
        return None
    return value if value.tzinfo is not None else value.replace(tzinfo=dt.UTC)


def factory(error: type[ImportFileError], file: str, where: str) -> functools.partial[ImportFileError]:
    """``(field, accepted, got) -> error`` bound to *file* and *where* (for ``build_measurement``)."""
    return functools.partial(error, file, where)
