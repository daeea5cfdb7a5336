"""Vendor measurement files into the measurement store, from the viewer (Qt-free).

The viewer imports CxF3, CGATS.17, MA-T12-style workbooks and CSV-template files the way
``station import FILE --store`` does, through the same public ingest functions:
``station.ingest.formats.read_measurement_file`` reads and validates the file,
``station.ingest.formats.readings_from_import`` makes one ingest record per sample and illumination
block (client ids from the file's bytes, so importing a file again stores nothing new), and the
viewer's sink's :class:`~station.ingest.Ingestor` stores them (the database, or the service in service
mode; queued on disk while it is away). Each file gives a :class:`FileImport`: how many samples and
readings, what became of them, or the error naming the file, the place and the field.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from station.errors import StationError

if TYPE_CHECKING:
    from station.ingest import Ingestor

#: Receipt statuses that mean the reading is in the store.
STORED_STATUSES = ("stored", "duplicate")


def import_suffixes() -> tuple[str, ...]:
    """Every file suffix an importer recognises (``station.ingest.formats.FORMATS``)."""
    from station.ingest.formats import FORMATS

    return tuple(s for suffixes in FORMATS.values() for s in suffixes)


def import_filter() -> str:
    """The file dialog's name filter for the importable files."""
    return "Vendor measurement files (" + " ".join(f"*{s}" for s in import_suffixes()) + ")"


def importable(path: Path | str) -> bool:
    """Whether *path* is a file with a suffix an importer recognises (drag and drop offers only these)."""
    p = Path(path)
    return p.is_file() and p.suffix.lower() in import_suffixes()


@dataclass(frozen=True)
class FileImport:
    """What became of one file: its format and samples, the readings stored, duplicate, queued or
    refused, their measurement ids, or ``error`` (the file was not stored at all)."""

    file: str
    format: str = ""
    samples: int = 0
    statuses: tuple[str, ...] = ()
    measurement_ids: tuple[int, ...] = ()
    messages: tuple[str, ...] = ()
    error: str = ""

    @property
    def stored(self) -> int:
        """Readings now in the store (new or already there)."""
        return sum(s in STORED_STATUSES for s in self.statuses)

    def text(self) -> str:
        """One line for the screen."""
        if self.error:
            return f"{self.file}: NOT IMPORTED — {self.error}"
        counts = {s: self.statuses.count(s) for s in dict.fromkeys(self.statuses)}
        told = ", ".join(f"{n} {s}" for s, n in counts.items())
        extra = "".join(f"; {m}" for m in self.messages if m)
        return f"{self.file} ({self.format}): {self.samples} samples, {len(self.statuses)} readings: {told}{extra}"


def import_file(path: Path | str, ingestor: Ingestor, job: str | None, part: str | None) -> FileImport:
    """Read *path*, validate every reading, then store them through *ingestor*; a bad file stores
    nothing and is answered with its error (never raised). *job*/*part* name the panels (both or
    neither), as ``station import --job --part``."""
    from station.ingest import operator_name
    from station.ingest.formats import load_measurement_file
    from station.ingest.formats.records import ImportOptions, readings_from_file

    path = Path(path)
    try:
        imported, data = load_measurement_file(path)  # parsed and hashed from one read
        options = ImportOptions(operator_name(), job, part)
        # every reading validated before the first is stored
        readings = readings_from_file(imported, path, options, data=data)
    except (StationError, OSError) as exc:
        return FileImport(path.name, error=str(exc))
    receipts = [ingestor.submit(r) for r in readings]
    return FileImport(
        path.name,
        imported.format,
        len(imported.measurements),
        tuple(r.status for r in receipts),
        tuple(int(r.measurement_id) for r in receipts if r.measurement_id is not None),
        tuple(r.message for r in receipts if r.status not in STORED_STATUSES),
    )


def import_files(
    paths: Sequence[Path | str], ingestor: Ingestor, job: str | None, part: str | None
) -> list[FileImport]:
    """:func:`import_file` for each of *paths*, in order (one bad file does not stop the others)."""
    return [import_file(p, ingestor, job, part) for p in paths]


def import_summary(results: Sequence[FileImport]) -> str:
    """One line over all files: readings stored and files refused."""
    stored = sum(r.stored for r in results)
    bad = [r.file for r in results if r.error]
    line = f"imported {len(results) - len(bad)} of {len(results)} files: {stored} readings stored"
    return line + (f"; not imported: {', '.join(bad)}" if bad else "")
