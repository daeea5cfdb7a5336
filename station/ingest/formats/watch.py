"""Watch folder: each measurement file dropped into a folder is ingested exactly once.

A file is read (:func:`~station.ingest.formats.read_measurement_file`), turned into readings whose
client ids derive from its bytes (:func:`~station.ingest.formats.readings_from_import`), submitted
through the one ingest path (:class:`~station.ingest.Ingestor`: stored, or queued in the outbox when
the database is away) and only then moved to ``done/``. A file that cannot be imported, or whose
readings the destination refuses, moves to ``rejected/`` next to a ``NAME.reason`` text file saying
why; nothing of it is stored.

Killed at any instant, the watcher loses nothing and stores nothing twice: a file leaves the folder
only after all its readings are stored or queued, and reading it again after a restart resubmits the
same client ids, which the store answers as duplicates.

Skipped: sub-folders, hidden names (``.x``), ``~x``, names ending in ``.part``, ``.tmp``,
``.partial``, ``.crdownload`` or ``.reason``, and files modified less than *settle_s* seconds ago
(still being copied in).
"""

from __future__ import annotations

import datetime as dt
import logging
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from station.errors import InputError
from station.ingest.errors import IngestError
from station.ingest.formats import read_measurement_file
from station.ingest.formats.records import file_sha256, readings_from_import
from station.ingest.ingestor import Ingestor

log = logging.getLogger(__name__)

__all__ = ["DONE", "REJECTED", "WatchOutcome", "process_file", "scan_once", "watch_folder"]

DONE = "done"
REJECTED = "rejected"
SKIPPED_SUFFIXES = (".part", ".tmp", ".partial", ".crdownload", ".reason")
#: Default settle time: a file younger than this (seconds since its last change) waits for the next scan.
SETTLE_S = 2.0


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
        return {
            "file": self.file,
            "status": self.status,
            "moved_to": self.moved_to,
            "receipts": list(self.receipts),
            "reason": self.reason,
        }


def _free_name(folder: Path, name: str) -> Path:
    """``folder/name``, or ``folder/stem.N.suffix`` with the first free N when taken."""
    target = folder / name
    n = 1
    while target.exists():
        p = Path(name)
        target = folder / f"{p.stem}.{n}{p.suffix}"
        n += 1
    return target


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _move(path: Path, folder: Path) -> Path:
    folder.mkdir(exist_ok=True)
    target = _free_name(folder, path.name)
    os.replace(path, target)
    _fsync_dir(folder)
    return target


def _reject(path: Path, reason: str) -> Path:
    folder = path.parent / REJECTED
    folder.mkdir(exist_ok=True)
    target = _free_name(folder, path.name)
    note = target.with_name(target.name + ".reason")
    tmp = note.with_name(note.name + ".tmp")
    tmp.write_text(reason.rstrip() + "\n", encoding="utf-8")
    os.replace(tmp, note)  # the reason is in place before the file moves
    os.replace(path, target)
    _fsync_dir(folder)
    return target


def process_file(
    path: Path,
    ingestor: Ingestor,
    *,
    operator: str,
    job: str | None = None,
    part: str | None = None,
    illumination_deg: float | None = None,
) -> WatchOutcome:
    """Import *path* through *ingestor*, then move it to ``done/`` (or ``rejected/`` with a reason)."""
    try:
        imported = read_measurement_file(path)
        mtime = dt.datetime.fromtimestamp(path.stat().st_mtime, dt.UTC).replace(microsecond=0)
        readings = readings_from_import(
            imported,
            sha256=file_sha256(path),
            operator=operator,
            fallback_time=mtime,
            illumination_deg=illumination_deg,
            job=job,
            part=part,
        )
    except InputError as exc:
        log.warning("rejected %s: %s", path.name, exc)
        target = _reject(path, f"{type(exc).__name__}: {exc}")
        return WatchOutcome(path.name, "rejected", str(target), reason=str(exc))
    receipts: list[dict[str, Any]] = []
    for reading in readings:
        try:
            receipt = ingestor.submit(reading)
        except (IngestError, ValueError) as exc:  # refused by the destination (not unreachable)
            log.warning("rejected %s: %s", path.name, exc)
            target = _reject(path, f"{type(exc).__name__}: {exc}")
            return WatchOutcome(path.name, "rejected", str(target), tuple(receipts), str(exc))
        receipts.append(
            {
                "client_id": receipt.client_id,
                "status": receipt.status,
                "measurement_id": receipt.measurement_id,
                "message": receipt.message,
            }
        )
    target = _move(path, path.parent / DONE)
    log.info("imported %s: %d readings", path.name, len(receipts))
    return WatchOutcome(path.name, "done", str(target), tuple(receipts))


def _candidates(folder: Path, settle_s: float) -> list[Path]:
    now = time.time()
    out = []
    for p in sorted(folder.iterdir()):
        name = p.name
        if name.startswith((".", "~")) or name.lower().endswith(SKIPPED_SUFFIXES):
            continue
        try:
            st = p.stat()
        except OSError:
            continue  # moved away meanwhile
        if not p.is_file() or now - st.st_mtime < settle_s:
            continue
        out.append(p)
    return out


def scan_once(
    folder: Path,
    ingestor: Ingestor,
    *,
    operator: str,
    settle_s: float = SETTLE_S,
    job: str | None = None,
    part: str | None = None,
    illumination_deg: float | None = None,
) -> list[WatchOutcome]:
    """Process every settled file now in *folder* (oldest name first); one outcome per file."""
    if not folder.is_dir():
        raise InputError("folder", "an existing folder", str(folder))
    outcomes = []
    for p in _candidates(folder, settle_s):
        try:
            outcomes.append(
                process_file(
                    p, ingestor, operator=operator, job=job, part=part, illumination_deg=illumination_deg
                )
            )
        except FileNotFoundError:  # taken away meanwhile (by a person, or a second watcher on the folder)
            log.info("%s left the folder before it was imported", p.name)
    return outcomes


def watch_folder(
    folder: Path,
    ingestor: Ingestor,
    *,
    operator: str,
    interval_s: float = 1.0,
    settle_s: float = SETTLE_S,
    stop: threading.Event | None = None,
    on_outcome: Callable[[WatchOutcome], None] | None = None,
    job: str | None = None,
    part: str | None = None,
    illumination_deg: float | None = None,
) -> None:
    """Scan *folder* every *interval_s* seconds until *stop* is set; *on_outcome* hears of each file."""
    stop = stop or threading.Event()
    while not stop.is_set():
        for outcome in scan_once(
            folder,
            ingestor,
            operator=operator,
            settle_s=settle_s,
            job=job,
            part=part,
            illumination_deg=illumination_deg,
        ):
            if on_outcome is not None:
                on_outcome(outcome)
        stop.wait(interval_s)
