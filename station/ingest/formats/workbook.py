"""The MA-T12-style workbook (``.xlsx``, read with openpyxl): sheet ``Spectral Data``, one row per geometry.

X-Rite MA-T12 exports hold a sheet ``Spectral Data`` with one row per geometry named like ``45as45``
(twelve geometries in two illumination blocks, 15° and 45°) and 31 reflectance columns, 400–700 nm at
10 nm. The reader is driven by the sheet's header row (the first row naming a geometry column):

* ``Geometry`` (or ``Angle``): the geometry name, ``45as15`` style;
* wavelength columns headed by a number of nanometres (``400``, ``400nm``, ``400 nm``); values are
  reflectance factors, or percent when any value exceeds 2 (the sheet then reads as percent);
* optional ``Sample`` (or ``Name``) — rows of one sample share it; without it the file's stem names
  the one sample;
* optional ``L``, ``a``, ``b`` (``L*``, ``a*``, ``b*``) Lab columns;
* optional texture columns headed ``Sparkle…`` or ``Graininess…``, stored tagged with the vendor
  (``Manufacturer`` in a sheet ``Info`` when present, else ``X-Rite``, the workbook's maker), never compared across vendors.

An optional sheet ``Info`` with ``key | value`` rows gives ``Instrument``, ``Serial``, ``Manufacturer``,
``Measured at`` (an ISO 8601 instant or a date cell), ``Illuminant`` and ``Observer``. Other sheets
(``Texture Images``) are ignored. Refusals are :class:`~station.ingest.errors.WorkbookImportError`
naming the sheet, the cell row and the column.

A workbook is read as a stream (openpyxl's read-only mode), within bounds a hostile file cannot
stretch: at most :data:`MAX_WORKBOOK_BYTES` bytes on disk, :data:`MAX_WORKBOOK_XML_BYTES` bytes
unpacked (:data:`MAX_SHARED_STRINGS_BYTES` of them the shared-strings part, which openpyxl holds
whole) and :data:`MAX_WORKBOOK_CELLS` cells read, padding of short rows and skipped rows included;
past any of them the workbook is refused naming the bound.
"""

from __future__ import annotations

import datetime as dt
import io
import re
import zipfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from station.ingest.errors import WorkbookImportError
from station.ingest.formats._text import factory, parse_instant, read_bytes
from station.ingest.formats.measurement import (
    ImportedFile,
    ImportedMeasurement,
    Instrument,
    VendorValue,
    build_measurement,
    canonical_geometry,
    observer_degrees,
    observer_name,
)

__all__ = [
    "MAX_SHARED_STRINGS_BYTES",
    "MAX_WORKBOOK_BYTES",
    "MAX_WORKBOOK_CELLS",
    "MAX_WORKBOOK_XML_BYTES",
    "SHEET",
    "is_complete",
    "read_workbook",
    "write_workbook",
]

SHEET = "Spectral Data"
INFO = "Info"
DEFAULT_VENDOR = "X-Rite"
_NM = re.compile(r"^(\d{3,4}(?:\.\d+)?)\s*(?:nm)?$", re.IGNORECASE)
_TEXTURE = re.compile(r"^(sparkle|graininess)", re.IGNORECASE)
_ROW_NUMBER = re.compile(rb"<row\b[^>]*?\sr=\"(\d{1,12})\"")
LAB_DECIMALS = 4
SPECTRA_DECIMALS = 6
#: Largest workbook read, bytes on disk (an MA-T12 export of 1000 samples is ≈ 3 MB).
MAX_WORKBOOK_BYTES = 16 << 20
#: Largest workbook unpacked, bytes: the sum of its zip members' sizes (1000 samples ≈ 25 MB of XML).
MAX_WORKBOOK_XML_BYTES = 128 << 20
#: Largest shared-strings part, bytes unpacked (openpyxl keeps it whole in memory).
MAX_SHARED_STRINGS_BYTES = 16 << 20
#: Most cells read from a workbook, its sheets together (1000 samples × 12 geometries × 40 columns
#: = 480 000): each short row counts as padded to its last cell, an empty row as one cell.
MAX_WORKBOOK_CELLS = 1_000_000


def _header_map(row: Sequence[Any]) -> dict[str, int] | None:
    names = {str(c).strip().lower().rstrip("*"): i for i, c in enumerate(row) if c is not None}
    for key in ("geometry", "angle"):
        if key in names:
            names["geometry"] = names[key]
            return names
    return None


def _number(value: Any, fld: str, file: str, where: str) -> float:
    if isinstance(value, bool) or value is None or value == "":
        raise WorkbookImportError(file, where, fld, "a number", value)
    try:
        return float(value)
    except (TypeError, ValueError) as exc:
        raise WorkbookImportError(file, where, fld, "a number", value) from exc


class _CellBudget:
    """Counts the cells read against :data:`MAX_WORKBOOK_CELLS`; refuses the workbook past it."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.left = MAX_WORKBOOK_CELLS

    def rows(self, ws: Any, sheet: str) -> Iterator[tuple[Any, ...]]:
        """The rows of *ws* as value tuples (trailing empty cells dropped), each charged to the budget."""
        ws.reset_dimensions()  # a declared A1:XFD1048576 must not pad every row to 16 384 cells
        for r, row in enumerate(ws.iter_rows(values_only=True), start=1):
            self.left -= max(1, len(row))
            if self.left < 0:
                raise _cell_error(self.file, f"sheet {sheet!r} row {r}")
            end = len(row)
            while end and row[end - 1] is None:
                end -= 1
            yield tuple(row[:end])


def _cell_error(file: str, where: str) -> WorkbookImportError:
    return WorkbookImportError(file, where, "cells", f"at most {MAX_WORKBOOK_CELLS} cells")


def _count_cells(zf: zipfile.ZipFile, member: zipfile.ZipInfo, file: str) -> None:
    """Refuse a worksheet part holding more cells, or reaching further down, than the cell bound,
    counted on its unpacked XML as it streams by (C-speed, before openpyxl builds a cell)."""
    cells = 0
    tail = b""
    with zf.open(member) as fh:
        while chunk := fh.read(1 << 20):
            text = tail + chunk
            cells += text.count(b"<c ") + text.count(b"<c>") + text.count(b"<c/")
            rows = [int(m) for m in _ROW_NUMBER.findall(text)]
            if cells > MAX_WORKBOOK_CELLS or (rows and max(rows) > MAX_WORKBOOK_CELLS):
                raise _cell_error(file, f"part {member.filename!r}")
            tail = text[-64:]
            cells -= tail.count(b"<c ") + tail.count(b"<c>") + tail.count(b"<c/")  # counted again next


def _screen(data: bytes, file: str) -> None:
    """Refuse a workbook whose zip members unpack past the bounds, or whose sheets hold more cells
    than the bound (module doc), before openpyxl parses it."""
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            members = zf.infolist()
            total = sum(m.file_size for m in members)
            if total > MAX_WORKBOOK_XML_BYTES:
                raise WorkbookImportError(
                    file, "workbook", "xlsx", f"at most {MAX_WORKBOOK_XML_BYTES} bytes unpacked", total
                )
            strings = sum(m.file_size for m in members if m.filename.lower().endswith("sharedstrings.xml"))
            if strings > MAX_SHARED_STRINGS_BYTES:
                raise WorkbookImportError(
                    file,
                    "workbook",
                    "sharedStrings",
                    f"at most {MAX_SHARED_STRINGS_BYTES} bytes unpacked",
                    strings,
                )
            for m in members:
                if m.filename.lower().startswith("xl/worksheets/") and m.filename.lower().endswith(".xml"):
                    _count_cells(zf, m, file)
    except WorkbookImportError:
        raise
    except Exception as exc:  # a damaged zip fails in many ways (zlib, CRC, headers): all "not a workbook"
        raise WorkbookImportError(
            file, "workbook", "xlsx", "an Excel workbook (.xlsx), not truncated", type(exc).__name__
        ) from exc


def _info(wb: Any, budget: _CellBudget) -> dict[str, Any]:
    if INFO not in wb.sheetnames:
        return {}
    out = {}
    for row in budget.rows(wb[INFO], INFO):
        if row and row[0] is not None and len(row) > 1:
            out[str(row[0]).strip().lower()] = row[1]
    return out


def is_complete(data: bytes) -> bool:
    """Whether *data* holds a whole zip: its central directory, written last, is there. Bytes that are
    no zip at all count as complete (the reader refuses them)."""
    if not data.startswith(b"PK\x03\x04"):
        return True
    try:
        zipfile.ZipFile(io.BytesIO(data)).close()
    except zipfile.BadZipFile:
        return False
    except (OSError, ValueError, EOFError):
        return True
    return True


def read_workbook(path: Path | str, data: bytes | None = None) -> ImportedFile:
    """Read an MA-T12-style workbook (module doc) into one :class:`ImportedMeasurement` per sample.

    *data*: the file's bytes when already read (else read from *path*, which also names the file).
    """
    import openpyxl  # loaded on use: the other formats do not need it

    path = Path(path)
    file = path.name
    data = read_bytes(path, WorkbookImportError, data, MAX_WORKBOOK_BYTES)  # parsed from memory
    _screen(data, file)
    budget = _CellBudget(file)
    try:
        wb = openpyxl.load_workbook(io.BytesIO(data), read_only=True, data_only=True)
        try:
            sheets = list(wb.sheetnames)
            info = _info(wb, budget)
            rows = list(budget.rows(wb[SHEET], SHEET)) if SHEET in sheets else []
        finally:
            wb.close()
    except WorkbookImportError:
        raise
    except (
        Exception
    ) as exc:  # a damaged zip or XML part fails in many ways inside openpyxl: all are "not a workbook"
        raise WorkbookImportError(
            file,
            "workbook",
            "xlsx",
            "an Excel workbook (.xlsx), not truncated",
            f"{type(exc).__name__}: {exc}",
        ) from exc
    if SHEET not in sheets:
        raise WorkbookImportError(file, "workbook", "sheet", f"a sheet {SHEET!r}", sheets)
    header_at, col = next(
        ((i, m) for i, r in enumerate(rows) if (m := _header_map(r)) is not None), (-1, None)
    )
    if col is None:
        raise WorkbookImportError(file, f"sheet {SHEET!r}", "Geometry", "a header row with a Geometry column")
    header = rows[header_at]
    spectral = sorted(
        (float(match.group(1)), i)
        for i, c in enumerate(header)
        if c is not None and (match := _NM.match(str(c).strip()))
    )
    lab_cols = [col.get(k) for k in ("l", "a", "b")]
    has_lab = all(c is not None for c in lab_cols)
    if not spectral and not has_lab:
        raise WorkbookImportError(file, f"sheet {SHEET!r} row {header_at + 1}", "400", "wavelength columns (400 … 700 nm) and/or L, a, b")  # fmt: skip
    manufacturer = str(info.get("manufacturer") or "").strip()
    vendor = manufacturer or DEFAULT_VENDOR
    texture_cols = [(str(c).strip().lower(), i) for i, c in enumerate(header) if c is not None and _TEXTURE.match(str(c).strip())]  # fmt: skip
    measured = info.get("measured at")
    measured_at = measured if isinstance(measured, dt.datetime) else parse_instant(str(measured or ""))
    if measured_at is not None and measured_at.tzinfo is None:
        measured_at = measured_at.replace(tzinfo=dt.UTC)
    instrument = Instrument(
        model=str(info.get("instrument") or "MA-T12"),
        serial=str(info.get("serial") or ""),
        manufacturer=manufacturer,
    )
    illuminant = str(info.get("illuminant") or "D65").strip().upper()
    observer_text = str(info.get("observer") or "10").strip()
    observer = observer_name(observer_text) or observer_text
    groups: dict[str, list[tuple[int, tuple[Any, ...]]]] = {}
    sample_col = col.get("sample", col.get("name"))
    for r, row in enumerate(rows[header_at + 1 :], start=header_at + 2):
        if not row or all(c is None or str(c).strip() == "" for c in row):
            continue
        if len(row) < len(header):
            row = tuple(row) + (None,) * (len(header) - len(row))
        name = path.stem if sample_col is None else str(row[sample_col] or "").strip()
        groups.setdefault(name, []).append((r, row))
    if not groups:
        raise WorkbookImportError(file, f"sheet {SHEET!r}", "rows", "at least one geometry row", 0)
    curves_raw: list[
        tuple[str, list[tuple[str, Any]], list[list[float]], list[list[float]], list[VendorValue], int]
    ] = []
    peak = 0.0
    for name, group in groups.items():
        geo_rows, labs, curves, texture = [], [], [], []
        for r, row in group:
            where = f"sheet {SHEET!r} row {r}"
            err = factory(WorkbookImportError, file, where)
            geometry = canonical_geometry(str(row[col["geometry"]] or ""), "Geometry", err)
            geo_rows.append((geometry, err))
            if has_lab:
                labs.append([_number(row[c], h, file, where) for c, h in zip(lab_cols, "Lab", strict=True) if c is not None])  # fmt: skip
            if spectral:
                curve = [_number(row[i], f"{w:g} nm", file, where) for w, i in spectral]
                peak = max(peak, max(curve))
                curves.append(curve)
            for qty, i in texture_cols:
                if row[i] is None or str(row[i]).strip() == "":
                    continue
                per_sample = qty.startswith("graininess")
                texture.append(
                    VendorValue(
                        vendor, qty, _number(row[i], qty, file, where), "" if per_sample else geometry
                    )
                )
        curves_raw.append((name, geo_rows, labs, curves, texture, group[0][0]))
    percent = peak > 2.0
    out = []
    for name, geo_rows, labs, curves, texture, first_row in curves_raw:
        if percent:
            curves = [[v / 100.0 for v in c] for c in curves]
        seen = {
            (v.name, v.geometry): v for v in texture
        }  # a per-sample value repeated on each row counts once
        out.append(
            build_measurement(
                sample=name,
                rows=geo_rows,
                lab=labs if has_lab else None,
                wavelengths_nm=[w for w, _ in spectral] if spectral else None,
                spectra=curves if spectral else None,
                instrument=instrument,
                illuminant=illuminant,
                observer=observer,
                measured_at=measured_at,
                texture=list(seen.values()),
                err=factory(WorkbookImportError, file, f"sheet {SHEET!r} row {first_row}"),
            )
        )
    return ImportedFile("xlsx", file, tuple(out))


def write_workbook(measurements: Sequence[ImportedMeasurement], path: Path | str) -> None:
    """Write *measurements* as an MA-T12-style workbook (sheet ``Spectral Data`` and sheet ``Info``)."""
    import openpyxl

    if not measurements:
        raise WorkbookImportError(str(path), "", "measurements", "at least one measurement", 0)
    first = measurements[0]
    wl = first.wavelengths_nm
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = SHEET
    header: list[Any] = ["Sample", "Geometry"]
    if first.lab is not None:
        header += ["L*", "a*", "b*"]
    if wl is not None:
        header += [f"{w:g}" for w in wl]
    tex = sorted({(t.name, t.geometry == "") for m in measurements for t in m.texture})
    header += [name.capitalize() for name, _ in tex]
    ws.append(header)
    for n, m in enumerate(measurements, start=1):
        if m.wavelengths_nm != wl or (m.lab is None) != (first.lab is None):
            raise WorkbookImportError(
                str(path), f"measurement {n}", "wavelengths_nm", "the first measurement's layout"
            )
        values = {(t.name, t.geometry): t.value for t in m.texture}
        for k, g in enumerate(m.geometries):
            row: list[Any] = [m.sample, g]
            if m.lab is not None:
                row += [round(v, LAB_DECIMALS) for v in m.lab[k]]
            if m.spectra is not None:
                row += [round(v, SPECTRA_DECIMALS) for v in m.spectra[k]]
            row += [values.get((name, "" if per_sample else g)) for name, per_sample in tex]
            ws.append(row)
    info = wb.create_sheet(INFO)
    info.append(["Instrument", first.instrument.model])
    info.append(["Serial", first.instrument.serial])
    info.append(["Manufacturer", first.instrument.manufacturer])
    info.append(["Measured at", "" if first.measured_at is None else first.measured_at.isoformat()])
    info.append(["Illuminant", first.illuminant])
    info.append(["Observer", observer_degrees(first.observer)])
    wb.save(Path(path))
