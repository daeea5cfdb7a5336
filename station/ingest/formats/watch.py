"""Watch folder: each measurement file dropped into a folder is ingested exactly once, and nothing
outside the folder is touched.

A file is read (:func:`~station.ingest.formats.read_measurement_file`), turned into readings whose
client ids derive from its bytes (:func:`~station.ingest.formats.readings_from_import`), submitted
through the one ingest path (:class:`~station.ingest.Ingestor`: stored, or queued in the outbox when
the database is away) and only then moved to ``done/``. A file that cannot be imported, or whose
readings the destination refuses, moves to ``rejected/`` next to a ``NAME.reason`` file (mode 0600)
saying why: the error's class, the field, the accepted form and the place, never a byte of the file;
nothing of it is stored.

The watcher's folders. ``done/``, ``rejected/`` and ``processing/`` are made by the watcher as real
folders of mode 0700; one that exists as a symbolic link, as something other than a folder, or owned
by another user makes the watcher refuse to run (:class:`~station.errors.InputError`, one line) and
nothing is followed or changed. They are opened once and every move goes through their descriptors,
so renaming or replacing them later cannot redirect a file.

Claiming. A settled, whole file (below) is claimed by renaming it into the watcher's own folder
``processing/PID-XXXXXXXX/``: a rename is atomic, so of two watchers on one folder exactly one takes
a file and writes its outcome. The watcher holds a lock on its own folder while it runs; a folder
whose lock is free belonged to a watcher that was killed, and the next scan adopts its files. Killed
at any instant, the watcher loses nothing and stores nothing twice: a file leaves ``processing/`` only
after all its readings are stored or queued, and reading it again resubmits the same client ids,
which the store answers as duplicates.

What is read. A dropped name is opened with ``O_NOFOLLOW`` and checked on its descriptor: only a
regular file with one name is read. A symbolic link, a FIFO, a device, a socket or a hard link is
moved to ``rejected/`` without being opened or read. A file is imported once it is settled (unchanged
for *settle_s* seconds) and whole (:func:`~station.ingest.formats.is_complete`: a CxF's root element
closed, a CGATS ``END_DATA`` line, an ``.xlsx`` zip's central directory, a JSON document closed, a
CSV's last line ended); one not yet whole waits. A file that changes after it was read is refused, so
no partial file is ever imported. A CSV has no end marker: a writer that can pause between rows
writes ``NAME.csv.part`` and renames it to ``NAME.csv`` when done.

Skipped: sub-folders, hidden names (``.x``), ``~x``, names ending in ``.part``, ``.tmp``,
``.partial``, ``.crdownload`` or ``.reason``.
"""

from __future__ import annotations

import datetime as dt
import errno
import fcntl
import hashlib
import logging
import os
import secrets
import stat
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from db.files import file_kind
from station.closing import Closing
from station.errors import InputError
from station.ingest.errors import ImportFileError, IngestError
from station.ingest.formats import is_complete, read_measurement_file
from station.ingest.formats._text import MAX_FILE_BYTES
from station.ingest.formats.records import ImportOptions, readings_from_import
from station.ingest.ingestor import Ingestor
from station.wire import wire_form

log = logging.getLogger(__name__)

__all__ = [
    "DONE",
    "PROCESSING",
    "REJECTED",
    "WatchFolder",
    "WatchOutcome",
    "reason_of",
    "scan_once",
    "watch_folder",
]

DONE = "done"
REJECTED = "rejected"
#: The watchers' working folder: one sub-folder per running watcher holds the files it has claimed.
PROCESSING = "processing"
SKIPPED_SUFFIXES = (".part", ".tmp", ".partial", ".crdownload", ".reason")
#: Default settle time: a file younger than this (seconds since its last change) waits for the next scan.
SETTLE_S = 2.0
#: Default patience with a file that is not whole: unchanged this long (seconds) and still not whole, it is
#: taken as truncated and rejected (``Incomplete``) instead of waiting for ever.
ABANDON_S = 600.0
#: Mode of the folders the watcher makes (owner only).
FOLDER_MODE = 0o700
#: Mode of a ``.reason`` file (owner only).
REASON_MODE = 0o600

_DIR_FLAGS = os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC
_READ_FLAGS = os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC


@dataclass(frozen=True)
class WatchOutcome:
    """What became of one dropped file: moved to ``done/`` or ``rejected/``, with receipts or the reason."""

    file: str
    status: Literal["done", "rejected"]
    moved_to: str
    receipts: tuple[dict[str, Any], ...] = field(default=())
    reason: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return wire_form(self)


class _Refused(Exception):
    """A claimed file the watcher rejects; *reason* is already free of the file's contents."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def shown(name: str) -> str:
    """*name* for a log line or a reason: as is when printable, else escaped (no control characters)."""
    return name if name.isprintable() else ascii(name)[1:-1]


def reason_of(exc: BaseException) -> str:
    """Why a file was refused, in one line that holds no byte of the file.

    The error's class, then for an input error its field, the accepted form, the file's name and the
    place in it (never the value found there, which :class:`~station.errors.InputError` calls *got*).
    """
    kind = type(exc).__name__
    if isinstance(exc, InputError):
        where = ""
        if isinstance(exc, ImportFileError):
            where = f" ({exc.file}, {exc.where})" if exc.where else f" ({exc.file})"
        return shown(f"{kind}: {exc.field}: expected {exc.accepted}{where}")
    if isinstance(exc, IngestError):
        return f"{kind}: the destination refused the reading"
    return f"{kind}: the file could not be read"


def _fsync(fd: int) -> None:
    try:
        os.fsync(fd)
    except OSError:
        pass


def _own_folder(parent: int, name: str, shown_path: str) -> int:
    """A descriptor of the folder *name* in *parent*: made 0700 when absent; refused (one line) when it
    is a symbolic link, not a folder, or not this user's. Nothing found there is followed or changed."""
    try:
        os.mkdir(name, FOLDER_MODE, dir_fd=parent)
    except FileExistsError:
        pass
    accepted = "a folder the watcher makes (a real folder of this user's, not a symbolic link)"
    try:
        st = os.lstat(name, dir_fd=parent)
    except OSError as exc:
        raise InputError(name, accepted, exc.strerror, detail=shown_path) from exc
    if not stat.S_ISDIR(st.st_mode):
        raise InputError(name, accepted, file_kind(st.st_mode), detail=shown_path)
    if st.st_uid != os.geteuid():
        raise InputError(name, accepted, f"a folder of user id {st.st_uid}", detail=shown_path)
    if stat.S_IMODE(st.st_mode) & 0o077:  # made by someone else, or an older version: left as it is
        log.warning(
            "%s is open to other users (mode %o); the watcher leaves it so",
            shown_path,
            stat.S_IMODE(st.st_mode),
        )
    fd = os.open(name, _DIR_FLAGS | os.O_NOFOLLOW, dir_fd=parent)
    fst = os.fstat(fd)
    if (fst.st_dev, fst.st_ino) != (st.st_dev, st.st_ino):  # swapped between the check and the open
        os.close(fd)
        raise InputError(name, accepted, "a folder that changed while it was opened", detail=shown_path)
    return fd


def _same(fd: int, parent: int, name: str) -> bool:
    """Whether *name* in *parent* is still the folder open as *fd*."""
    try:
        st = os.lstat(name, dir_fd=parent)
    except FileNotFoundError:
        return False
    fst = os.fstat(fd)
    return (st.st_dev, st.st_ino) == (fst.st_dev, fst.st_ino)


def _free_name(folder: int, name: str, taken: Callable[[str], bool] | None = None) -> Iterator[str]:
    """``name``, then ``stem.N.suffix`` for N = 1, 2, …: the candidates not present in *folder*."""
    p = Path(name)
    n = 0
    while True:
        cand = name if n == 0 else f"{p.stem}.{n}{p.suffix}"
        n += 1
        try:
            os.lstat(cand, dir_fd=folder)
        except FileNotFoundError:
            if taken is None or not taken(cand):
                yield cand


def _read_whole(fd: int) -> bytes:
    chunks = []
    left = MAX_FILE_BYTES + 1  # a reader refuses more than its bound, naming it
    while left > 0:
        chunk = os.read(fd, min(left, 1 << 20))
        if not chunk:
            break
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


class WatchFolder(Closing):
    """One watcher on a folder: its own folders opened and checked, its claim folder locked.

    Use as a context manager; :meth:`scan` processes the files there now. Closing releases the lock
    and removes the watcher's (then empty) claim folder.
    """

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._fds: dict[str, int] = {}
        self._mine = -1  # this watcher's claim folder, once made
        self._waiting: set[tuple[str, int, int]] = set()  # (name, inode, size) logged as not yet whole
        try:
            self._root = os.open(self.folder, _DIR_FLAGS)
        except OSError as exc:
            raise InputError("folder", "an existing folder", str(self.folder)) from exc
        self._mine_name = ""
        try:
            self._open_folders()
        except BaseException:
            self._close_fds()
            raise

    def _make_mine(self) -> None:
        """Make and lock this watcher's claim folder in ``processing/``."""
        if self._mine >= 0:
            os.close(self._mine)
            self._mine = -1
        self._mine_name = f"{os.getpid()}-{secrets.token_hex(4)}"
        os.mkdir(self._mine_name, FOLDER_MODE, dir_fd=self._fds[PROCESSING])
        self._mine = os.open(self._mine_name, _DIR_FLAGS | os.O_NOFOLLOW, dir_fd=self._fds[PROCESSING])
        fcntl.flock(self._mine, fcntl.LOCK_EX | fcntl.LOCK_NB)

    def _open_folders(self) -> None:
        for name in (DONE, REJECTED, PROCESSING):
            if name in self._fds and _same(self._fds[name], self._root, name):
                continue
            if name in self._fds:  # removed or replaced while running: made again, or refused
                os.close(self._fds.pop(name))
            self._fds[name] = _own_folder(self._root, name, str(self.folder / name))
            if name == PROCESSING:
                self._make_mine()

    def _close_fds(self) -> None:
        for fd in self._fds.values():
            os.close(fd)
        self._fds.clear()
        if self._mine >= 0:
            os.close(self._mine)
            self._mine = -1
        os.close(self._root)

    def close(self) -> None:
        """Remove the (empty) claim folder, release its lock and close every descriptor."""
        if self._mine >= 0:
            try:
                os.rmdir(self._mine_name, dir_fd=self._fds[PROCESSING])
            except OSError:
                pass  # not empty (a move failed): a later watcher adopts what is left
        self._close_fds()

    # ----------------------------------------------------------------- scanning

    def scan(
        self,
        ingestor: Ingestor,
        options: ImportOptions,
        *,
        settle_s: float = SETTLE_S,
        abandon_s: float = ABANDON_S,
    ) -> list[WatchOutcome]:
        """Process every settled, whole file now in the folder (name order), and the files of killed
        watchers, each imported as *options* say; one outcome per file. A file unchanged for *abandon_s*
        seconds and still not whole is rejected as ``Incomplete``."""
        self._open_folders()
        outcomes = [self._finish(name, ingestor, options) for name in self._adopt()]
        now = time.time()
        for name in sorted(os.listdir(self._root)):
            if name.startswith((".", "~")) or name.lower().endswith(SKIPPED_SUFFIXES):
                continue
            try:
                st = os.lstat(name, dir_fd=self._root)
            except FileNotFoundError:
                continue  # taken meanwhile
            if stat.S_ISDIR(st.st_mode):
                continue
            if stat.S_ISREG(st.st_mode) and now - st.st_mtime < settle_s:
                continue
            claimed = self._claim(name, st, abandoned=now - st.st_mtime >= abandon_s)
            if claimed is not None:
                outcomes.append(self._finish(claimed, ingestor, options))
        return outcomes

    def _claim(self, name: str, st: os.stat_result, abandoned: bool = False) -> str | None:
        """Move *name* into this watcher's folder when it is another kind of file, a hard link, a whole
        regular file that stayed as it was read, or (*abandoned*) one left unfinished for too long;
        ``None`` when it must wait or was taken."""
        if stat.S_ISREG(st.st_mode) and st.st_nlink == 1:
            try:
                fd = os.open(name, _READ_FLAGS, dir_fd=self._root)
            except PermissionError:
                return self._move_in(name)  # unreadable: rejected as such
            except OSError:
                return None  # taken, or replaced by a link: the next scan sees it
            try:
                before = os.fstat(fd)
                if not stat.S_ISREG(before.st_mode) or before.st_nlink != 1:
                    return None
                data = _read_whole(fd)
                after = os.fstat(fd)
                if (after.st_size, after.st_mtime_ns) != (before.st_size, before.st_mtime_ns):
                    return None  # still being written
                if not is_complete(name, data) and not abandoned:
                    key = (name, before.st_ino, before.st_size)
                    if key not in self._waiting:
                        self._waiting.add(key)
                        log.info("waiting for %s: not whole yet", shown(name))
                    return None
                target = self._move_in(name)
                if target is None:
                    return None
                return target
            finally:
                os.close(fd)
        return self._move_in(name)

    def _move_in(self, name: str) -> str | None:
        target = next(_free_name(self._mine, name))
        try:
            os.rename(name, target, src_dir_fd=self._root, dst_dir_fd=self._mine)
        except FileNotFoundError:
            return None  # another watcher claimed it
        return target

    def _adopt(self) -> list[str]:
        """Move the files of killed watchers (claim folders whose lock is free) into this one's."""
        adopted: list[str] = []
        proc = self._fds[PROCESSING]
        for other in sorted(os.listdir(proc)):
            if other == self._mine_name:
                continue
            try:
                fd = os.open(other, _DIR_FLAGS | os.O_NOFOLLOW, dir_fd=proc)
            except OSError:
                continue
            try:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError as exc:
                    if exc.errno in (errno.EAGAIN, errno.EWOULDBLOCK):
                        continue  # its watcher is running
                    raise
                for name in sorted(os.listdir(fd)):
                    if name.startswith("."):  # a reason the killed watcher was writing
                        os.unlink(name, dir_fd=fd)
                        continue
                    target = next(_free_name(self._mine, name))
                    try:
                        os.rename(name, target, src_dir_fd=fd, dst_dir_fd=self._mine)
                    except FileNotFoundError:
                        continue
                    adopted.append(target)
                try:
                    os.rmdir(other, dir_fd=proc)
                except OSError:
                    pass
            finally:
                os.close(fd)
        if adopted:
            log.info("took over %d file(s) of a watcher that was stopped", len(adopted))
        # and this watcher's own leftovers (a scan that failed midway, e.g. the database raised)
        return sorted(set(adopted) | {n for n in os.listdir(self._mine) if not n.startswith(".")})

    # ----------------------------------------------------------------- one claimed file

    def _finish(self, name: str, ingestor: Ingestor, options: ImportOptions) -> WatchOutcome:
        """Import the claimed *name* and move it to ``done/``, or reject it with its reason."""
        receipts: list[dict[str, Any]] = []
        try:
            data, mtime = self._read_claimed(name)
            readings = readings_from_import(
                read_measurement_file(name, data=data),
                options,
                sha256=hashlib.sha256(data).hexdigest(),
                fallback_time=dt.datetime.fromtimestamp(mtime, dt.UTC).replace(microsecond=0),
            )
        except _Refused as exc:
            return self._reject(name, exc.reason, receipts)
        except Exception as exc:  # unreadable: a typed error, or a parser failing on hostile bytes
            return self._reject(name, reason_of(exc), receipts)
        try:
            for reading in readings:
                receipt = ingestor.submit(reading)
                receipts.append(
                    {
                        "client_id": receipt.client_id,
                        "status": receipt.status,
                        "measurement_id": receipt.measurement_id,
                        "message": receipt.message,
                    }
                )
        except (IngestError, ValueError) as exc:  # refused by the destination (not unreachable)
            return self._reject(name, reason_of(exc), receipts)
        target = next(_free_name(self._fds[DONE], name))
        os.rename(name, target, src_dir_fd=self._mine, dst_dir_fd=self._fds[DONE])
        _fsync(self._fds[DONE])
        log.info("imported %s: %d readings", shown(name), len(receipts))
        return WatchOutcome(name, "done", str(self.folder / DONE / target), tuple(receipts))

    def _read_claimed(self, name: str) -> tuple[bytes, float]:
        """The bytes and modification time of the claimed *name*; :class:`_Refused` unless it is a whole
        regular file with one name (a link, FIFO or device is never opened)."""
        st = os.lstat(name, dir_fd=self._mine)
        if not stat.S_ISREG(st.st_mode):
            raise _Refused(f"NotARegularFile: file: expected a regular file, got {file_kind(st.st_mode)}")
        if st.st_nlink != 1:
            raise _Refused("HardLink: file: expected a file with one name, got a hard link")
        try:
            fd = os.open(name, _READ_FLAGS, dir_fd=self._mine)
        except OSError as exc:
            raise _Refused(f"Unreadable: file: expected a readable regular file ({exc.strerror})") from exc
        try:
            before = os.fstat(fd)
            if not stat.S_ISREG(before.st_mode) or (before.st_dev, before.st_ino) != (st.st_dev, st.st_ino):
                raise _Refused("NotARegularFile: file: expected a regular file")
            data = _read_whole(fd)
            after = os.fstat(fd)
        finally:
            os.close(fd)
        if (after.st_size, after.st_mtime_ns) != (before.st_size, before.st_mtime_ns):
            raise _Refused(
                "ChangedWhileRead: file: expected a file that is whole and no longer written "
                "(write it under NAME.part and rename it when done)"
            )
        if not is_complete(name, data):
            raise _Refused(
                "Incomplete: file: expected a whole file; it stopped changing before it was whole "
                "(truncated? write it under NAME.part and rename it when done)"
            )
        return data, before.st_mtime

    def _reject(self, name: str, reason: str, receipts: list[dict[str, Any]]) -> WatchOutcome:
        """Move the claimed *name* to ``rejected/`` beside ``NAME.reason`` (0600), written first."""
        rejected = self._fds[REJECTED]
        tmp = f".{secrets.token_hex(8)}.reason"
        fd = os.open(
            tmp,
            os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC,
            REASON_MODE,
            dir_fd=self._mine,
        )
        try:
            os.write(fd, (reason.rstrip() + "\n").encode("utf-8"))
            _fsync(fd)
        finally:
            os.close(fd)
        try:
            for target in _free_name(rejected, name, lambda c: _exists(rejected, c + ".reason")):
                try:  # reserves the name: a second watcher's link of the same name fails
                    os.link(
                        tmp,
                        target + ".reason",
                        src_dir_fd=self._mine,
                        dst_dir_fd=rejected,
                        follow_symlinks=False,
                    )
                except FileExistsError:
                    continue
                break
        finally:
            os.unlink(tmp, dir_fd=self._mine)
        os.rename(name, target, src_dir_fd=self._mine, dst_dir_fd=rejected)
        _fsync(rejected)
        log.warning("rejected %s: %s", shown(name), reason)
        return WatchOutcome(name, "rejected", str(self.folder / REJECTED / target), tuple(receipts), reason)


def _exists(folder: int, name: str) -> bool:
    try:
        os.lstat(name, dir_fd=folder)
    except FileNotFoundError:
        return False
    return True


def scan_once(
    folder: Path,
    ingestor: Ingestor,
    options: ImportOptions,
    *,
    settle_s: float = SETTLE_S,
    abandon_s: float = ABANDON_S,
) -> list[WatchOutcome]:
    """Process every settled, whole file now in *folder* (oldest name first), each imported as *options*
    say; one outcome per file."""
    with WatchFolder(folder) as watcher:
        return watcher.scan(ingestor, options, settle_s=settle_s, abandon_s=abandon_s)


def watch_folder(
    folder: Path,
    ingestor: Ingestor,
    options: ImportOptions,
    *,
    interval_s: float = 1.0,
    settle_s: float = SETTLE_S,
    stop: threading.Event | None = None,
    on_outcome: Callable[[WatchOutcome], None] | None = None,
    abandon_s: float = ABANDON_S,
) -> None:
    """Scan *folder* every *interval_s* seconds until *stop* is set, each file imported as *options* say;
    *on_outcome* hears of each file.

    Raises :class:`~station.errors.InputError` (before any file is touched) when the folder, or one of
    the watcher's own folders in it, is refused (module doc).
    """
    stop = stop or threading.Event()
    with WatchFolder(folder) as watcher:
        while not stop.is_set():
            for outcome in watcher.scan(ingestor, options, settle_s=settle_s, abandon_s=abandon_s):
                if on_outcome is not None:
                    on_outcome(outcome)
            stop.wait(interval_s)
