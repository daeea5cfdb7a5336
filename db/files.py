"""The product's own files and folders: created private, never touched when they are someone else's.

* A folder the product creates is made 0700 (each missing level); a folder that already exists is
  used as it is, whatever its mode (a warning is logged when others may write to it), and never
  changed: naming ``/tmp`` as the data folder must not make ``/tmp`` private.
* A file the product creates is made with its final mode (0600) in one step, never world-readable for
  an instant and never ``chmod``-ed afterwards. A file that already exists keeps its mode.
* An SQLite database is never opened from Python, only through SQLite. Closing any descriptor of a
  file drops every POSIX lock the process holds on it, including the locks of the process's live
  SQLite connections (https://www.sqlite.org/howtocorrupt.html §2.2), so a missing database is
  created empty under a temporary name, closed, and only then linked to its name; an existing one is
  only looked at with ``lstat``. SQLite creates its ``-wal`` and ``-shm`` files with the mode of the
  database file, so a database created here stays private with its journals.
* A database path that is not a regular file (a symlink, a folder, a FIFO, a device such as
  ``/dev/null``), or whose journal names are taken by one, is refused with
  :class:`NotRegularFileError` naming it; nothing is opened, created or changed.
"""

from __future__ import annotations

import errno
import logging
import os
import secrets
import stat
from pathlib import Path

from station.errors import InputError

PRIVATE_DIR_MODE = 0o700
PRIVATE_FILE_MODE = 0o600
SQLITE_SIDE_FILES = ("-wal", "-shm", "-journal")
_OTHERS_MAY_WRITE = stat.S_IWGRP | stat.S_IWOTH
_CREATE_FLAGS = (
    os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
)

log = logging.getLogger(__name__)


class NotRegularFileError(InputError):
    """A path the product would open as its own file is a symlink, folder, FIFO or device (exit status 2)."""

    def __init__(self, field: str, path: Path, kind: str) -> None:
        super().__init__(
            field, "a regular file or a new path (not a symlink, folder, FIFO or device)", str(path), kind
        )
        self.path = path
        self.kind = kind


def file_kind(mode: int) -> str:
    """What an ``lstat`` *mode* is, in words (``"a symbolic link"``, ``"a FIFO"``, ``"a character device"`` …)."""
    for test, name in (
        (stat.S_ISLNK, "a symbolic link"),
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISREG, "a regular file"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def _lstat(path: Path) -> os.stat_result | None:
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None


def check_regular(path: Path | str, field: str = "database") -> bool:
    """Whether *path* exists as a regular file (``False``: it does not exist); never follows a symlink.

    Raises :class:`NotRegularFileError` naming *field* and the path when it is anything else.
    """
    file = Path(path)
    st = _lstat(file)
    if st is None:
        return False
    if not stat.S_ISREG(st.st_mode):
        raise NotRegularFileError(field, file, file_kind(st.st_mode))
    return True


def private_dir(path: Path | str) -> Path:
    """Create *path* and its missing parents, each 0700; an existing folder is left exactly as it is.

    Only the levels created here get a mode; an existing folder others may write to is used as it is,
    with a warning in the log (the product never changes the mode of a folder it did not create).
    """
    folder = Path(path)
    missing: list[Path] = []
    level = folder
    while not level.exists():
        missing.append(level)
        if level.parent == level:
            break
        level = level.parent
    for new in reversed(missing):
        try:
            os.mkdir(new, PRIVATE_DIR_MODE)  # the umask can only take bits away from 0700
        except FileExistsError:
            pass  # another process made it at the same moment: theirs, left as it is
    if not missing:
        st = os.stat(folder)
        if not stat.S_ISDIR(st.st_mode):
            raise NotADirectoryError(errno.ENOTDIR, "not a folder", str(folder))
        if st.st_mode & _OTHERS_MAY_WRITE:
            log.warning(
                "folder %s may be written by others (mode %04o); the product leaves its mode as it is",
                folder,
                stat.S_IMODE(st.st_mode),
            )
    return folder


def _create_empty(file: Path) -> bool:
    """Create *file* empty with mode 0600 unless something already has its name; whether this call made it.

    The file is made under a temporary name in the same folder, closed, then hard-linked to its name,
    so no descriptor of it is ever open while it carries its name (no process's lock on it can be
    dropped by this close). Where the file system has no hard links it is created in place with
    ``O_EXCL`` (no descriptor exists before it does, so none holds a lock yet).
    """
    temp = file.with_name(f".{file.name}.{secrets.token_hex(6)}.new")
    os.close(os.open(temp, _CREATE_FLAGS, PRIVATE_FILE_MODE))
    try:
        os.link(temp, file, follow_symlinks=False)
    except FileExistsError:
        return False
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EXDEV, errno.EMLINK):
            raise
        try:
            os.close(os.open(file, _CREATE_FLAGS, PRIVATE_FILE_MODE))
        except FileExistsError:
            return False
    finally:
        os.unlink(temp)
    return True


def private_file(path: Path | str, field: str = "file") -> Path:
    """Create *path* empty with mode 0600 when missing; an existing regular file is left as it is; the path.

    Raises :class:`NotRegularFileError` (naming *field*) when the path is a symlink, folder, FIFO or device.
    """
    file = Path(path)
    if not check_regular(file, field) and not _create_empty(file):
        check_regular(file, field)  # another process made it at the same moment: it must still be a file
    return file


def private_sqlite(path: Path | str, field: str = "database") -> Path:
    """Make sure the SQLite database *path* can be opened by SQLite as the product's own file; the path.

    Missing: created empty, 0600, without a descriptor ever open on it under its name. Existing: must
    be a regular file, and so must any ``-wal``/``-shm``/``-journal`` beside it; nothing is opened,
    changed or ``chmod``-ed. Otherwise :class:`NotRegularFileError` naming *field* and the path.
    """
    file = Path(path)
    for suffix in SQLITE_SIDE_FILES:
        check_regular(file.with_name(file.name + suffix), field)
    return private_file(file, field)


def write_private_text(path: Path | str, text: str) -> Path:
    """Write *text* to *path* as a new 0600 file that replaces what was there; the path.

    The text goes to a new file beside it (``O_EXCL``, ``O_NOFOLLOW``) that is then renamed over the
    name, so a symlink or another file at *path* is replaced, never written through or ``chmod``-ed.
    """
    file = Path(path)
    temp = file.with_name(f".{file.name}.{secrets.token_hex(6)}.new")
    fd = os.open(temp, _CREATE_FLAGS, PRIVATE_FILE_MODE)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            out.write(text)
            out.flush()
            os.fsync(out.fileno())
        os.replace(temp, file)
    except BaseException:
        temp.unlink(missing_ok=True)
        raise
    return file
