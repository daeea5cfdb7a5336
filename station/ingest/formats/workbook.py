"""The MA-T12-style workbook (``.xlsx``, read with openpyxl): sheet ``Spectral Data``, one row per geometry.

X-Rite MA-T12 exports hold a sheet ``Spectral Data`` with one row per geometry named like ``45as45``
(twelve geometries in two illumination blocks, 15° and 45°) and 31 reflectance columns, 400–700 nm at
10 nm. The reader is driven by the sheet's header row (the first row naming a geometry column):

* ``Geometry`` (or ``Angle``): the geometry name, ``45as15`` style;
* wavelength columns headed by a number of nanometres (``400``, ``400nm``, ``400 nm``); values are
  reflectance factors, or percent when any value exceeds 2 (the sheet then reads as percent);
* optional ``Sample Name`` (or ``Sample``, ``Name``) — rows of one sample share it; without it the
  file's stem names the one sample;
* optional ``Date/Time``: the measurement instant of the sample (its first row's cell): an Excel date
  (the instrument computer's local time, which carries no zone: read as UTC) or ISO 8601 text;
  anything else is refused naming ``Date/Time``;
* optional ``L``, ``a``, ``b`` (``L*``, ``a*``, ``b*``) Lab columns;
* optional texture columns headed ``Sparkle…`` or ``Graininess…`` (stored as ``sparkle_intensity``,
  ``graininess``: lower case, spaces as ``_``), tagged with the vendor (``Manufacturer`` in a sheet
  ``Info`` when present, else ``X-Rite``, the workbook's maker), never compared across vendors.

Rows above the header are titles, except an ``Illuminant/Observer`` row (``Illuminant/Observer |
D65/10°`` or one cell ``Illuminant/Observer: D65/10°``): it gives the conditions of the Lab and is
refused naming ``Illuminant/Observer`` when it does not read as ``<illuminant>/<observer>``; an
illuminant or observer the store does not keep is refused as ``illuminant``/``observer``.

A sheet ``Texture Data`` (header: ``Sample Name``, ``Geometry``, ``Sparkle…``/``Graininess…``
columns) adds texture values per sample and geometry (a graininess, or a row without geometry, is
per sample); a sample not in ``Spectral Data`` is refused naming ``Sample``, two different values
for one quantity and geometry naming the quantity. An optional sheet ``Info`` with ``key | value``
rows gives ``Instrument``, ``Serial``, ``Manufacturer``, ``Measured at`` (used when there is no
``Date/Time`` column), ``Illuminant`` and ``Observer``. ``Texture Images`` (pictures) are not read.
Refusals are :class:`~station.ingest.errors.WorkbookImportError` naming the sheet, the cell row and
the column.

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
TEXTURE_SHEET = "Texture Data"
_SAMPLE_KEYS = ("sample", "sample name", "name")
_DATE_KEYS = ("date/time", "date / time", "datetime", "date", "measured at")
_CONDITIONS = re.compile(r"^\s*([A-Za-z]+\d*)\s*/\s*(\d+)\s*(?:°|deg(?:ree)?s?)?\s*$")
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


def _load(
    data: bytes, file: str, budget: _CellBudget
) -> tuple[dict[str, Any], list[tuple[Any, ...]], list | None]:
    """The ``Info`` map, the ``Spectral Data`` rows and the ``Texture Data`` rows (``None``: no sheet)."""
    import openpyxl  # loaded on use: the other formats do not need it

    try:
        wb = openpyxl.load_workbook(io.BytesIO(data), read_only=True, data_only=True)
        try:
            sheets = list(wb.sheetnames)
            if SHEET not in sheets:
                raise WorkbookImportError(file, "workbook", "sheet", f"a sheet {SHEET!r}", sheets)
            info = _info(wb, budget)
            rows = list(budget.rows(wb[SHEET], SHEET))
            texture = list(budget.rows(wb[TEXTURE_SHEET], TEXTURE_SHEET)) if TEXTURE_SHEET in sheets else None
        finally:
            wb.close()
    except WorkbookImportError:
        raise
    except Exception as exc:  # a damaged zip or XML part fails in many ways inside openpyxl: "not a workbook"
        raise WorkbookImportError(
            file,
            "workbook",
            "xlsx",
            "an Excel workbook (.xlsx), not truncated",
            f"{type(exc).__name__}: {exc}",
        ) from exc
    return info, rows, texture


def _conditions(above: Sequence[tuple[Any, ...]], info: dict[str, Any], file: str) -> tuple[str, str]:
    """Illuminant and observer: the ``Illuminant/Observer`` row above the header (``D65/10°``), else
    the ``Info`` sheet's ``Illuminant`` and ``Observer``, else D65 and 10°."""
    illuminant = str(info.get("illuminant") or "D65").strip().upper()
    observer_text = str(info.get("observer") or "10").strip()
    for r, row in enumerate(above, start=1):
        cells = [str(c).strip() for c in row if c is not None and str(c).strip()]
        if not cells or not cells[0].lower().replace(" ", "").startswith("illuminant/observer"):
            continue
        if len(cells) > 1:
            text = " ".join(cells[1:])  # label cell, value cell
        else:
            text = cells[0].split(":", 1)[1] if ":" in cells[0] else ""  # "Illuminant/Observer: D65/10°"
        m = _CONDITIONS.match(text)
        if m is None:
            raise WorkbookImportError(
                file,
                f"sheet {SHEET!r} row {r}",
                "Illuminant/Observer",
                'an illuminant and observer like "D65/10°"',
                text,
            )
        illuminant, observer_text = m.group(1).upper(), m.group(2)
    return illuminant, observer_name(observer_text) or observer_text


def _instant(value: Any, file: str, where: str) -> dt.datetime | None:
    """A ``Date/Time`` cell: an Excel date (instrument local time without a zone: read as UTC) or ISO text."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    if isinstance(value, dt.datetime):
        return value if value.tzinfo is not None else value.replace(tzinfo=dt.UTC)
    parsed = parse_instant(str(value))
    if parsed is None:
        raise WorkbookImportError(file, where, "Date/Time", "an Excel date cell or ISO 8601 text", value)
    return parsed


def _header(rows: Sequence[tuple[Any, ...]], file: str) -> dict[str, Any]:
    """The ``Spectral Data`` header: its row index and the columns of each quantity (module doc)."""
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
    return {
        "at": header_at,
        "width": len(header),
        "geometry": col["geometry"],
        "sample": next((col[k] for k in _SAMPLE_KEYS if k in col), None),
        "date": next((col[k] for k in _DATE_KEYS if k in col), None),
        "spectral": spectral,
        "lab": lab_cols if has_lab else None,
        "texture": _texture_columns(header),
    }


def _texture_columns(header: Sequence[Any]) -> list[tuple[str, int]]:
    """``(quantity, column)`` of each ``Sparkle…``/``Graininess…`` column, named ``sparkle_intensity``."""
    return [
        (re.sub(r"[\s\-]+", "_", str(c).strip().lower()), i)
        for i, c in enumerate(header)
        if c is not None and _TEXTURE.match(str(c).strip())
    ]


def _texture_value(
    vendor: str, qty: str, value: Any, geometry: str, file: str, where: str
) -> VendorValue | None:
    if value is None or str(value).strip() == "":
        return None
    per_sample = qty.startswith("graininess") or not geometry
    return VendorValue(vendor, qty, _number(value, qty, file, where), "" if per_sample else geometry)


def _texture_sheet(
    rows: list[tuple[Any, ...]], stem: str, vendor: str, file: str
) -> dict[str, list[VendorValue]]:
    """Per sample, the vendor texture values of the ``Texture Data`` sheet (module doc)."""
    sheet = f"sheet {TEXTURE_SHEET!r}"
    at = next((i for i, r in enumerate(rows) if _texture_columns(r)), None)
    if at is None:
        raise WorkbookImportError(file, sheet, "Sparkle", "a header row with Sparkle… or Graininess… columns")
    names = {str(c).strip().lower().rstrip("*"): i for i, c in enumerate(rows[at]) if c is not None}
    sample_col = next((names[k] for k in _SAMPLE_KEYS if k in names), None)
    geo_col = names.get("geometry", names.get("angle"))
    out: dict[str, list[VendorValue]] = {}
    for r, row in enumerate(rows[at + 1 :], start=at + 2):
        if not row or all(c is None or str(c).strip() == "" for c in row):
            continue
        row = tuple(row) + (None,) * (len(rows[at]) - len(row))
        where = f"{sheet} row {r}"
        name = stem if sample_col is None else str(row[sample_col] or "").strip()
        geo = str(row[geo_col] or "").strip() if geo_col is not None else ""
        geometry = (
            canonical_geometry(geo, "Geometry", factory(WorkbookImportError, file, where)) if geo else ""
        )
        for qty, i in _texture_columns(rows[at]):
            v = _texture_value(vendor, qty, row[i], geometry, file, where)
            if v is not None:
                out.setdefault(name, []).append(v)
    return out


def _merge_texture(values: list[VendorValue], file: str, where: str) -> list[VendorValue]:
    """One value per (quantity, geometry): a per-sample value repeated on rows counts once; they must agree."""
    seen: dict[tuple[str, str], VendorValue] = {}
    for v in values:
        prior = seen.get((v.name, v.geometry))
        if prior is not None and prior.value != v.value:
            raise WorkbookImportError(file, where, v.name, f"one value per sample ({prior.value:g})", v.value)
        seen[(v.name, v.geometry)] = v
    return list(seen.values())


def read_workbook(path: Path | str, data: bytes | None = None) -> ImportedFile:
    """Read an MA-T12-style workbook (module doc) into one :class:`ImportedMeasurement` per sample.

    *data*: the file's bytes when already read (else read from *path*, which also names the file).
    """
    path = Path(path)
    file = path.name
    data = read_bytes(path, WorkbookImportError, data, MAX_WORKBOOK_BYTES)  # parsed from memory
    _screen(data, file)
    info, rows, texture_rows = _load(data, file, _CellBudget(file))
    head = _header(rows, file)
    manufacturer = str(info.get("manufacturer") or "").strip()
    vendor = manufacturer or DEFAULT_VENDOR
    measured = info.get("measured at")
    ctx = {
        "file": file,
        "vendor": vendor,
        "measured_at": _instant(measured, file, f"sheet {INFO!r}") if measured else None,
        "instrument": Instrument(
            model=str(info.get("instrument") or "MA-T12"),
            serial=str(info.get("serial") or ""),
            manufacturer=manufacturer,
        ),
        "conditions": _conditions(rows[: head["at"]], info, file),
    }
    groups: dict[str, list[tuple[int, tuple[Any, ...]]]] = {}
    for r, row in enumerate(rows[head["at"] + 1 :], start=head["at"] + 2):
        if not row or all(c is None or str(c).strip() == "" for c in row):
            continue
        row = tuple(row) + (None,) * (head["width"] - len(row))
        name = path.stem if head["sample"] is None else str(row[head["sample"]] or "").strip()
        groups.setdefault(name, []).append((r, row))
    if not groups:
        raise WorkbookImportError(file, f"sheet {SHEET!r}", "rows", "at least one geometry row", 0)
    extra = _texture_sheet(texture_rows, path.stem, vendor, file) if texture_rows is not None else {}
    unknown = sorted(set(extra) - set(groups))
    if unknown:
        raise WorkbookImportError(
            file, f"sheet {TEXTURE_SHEET!r}", "Sample", f"a sample of sheet {SHEET!r}", unknown[0]
        )
    samples = [_sample(name, group, head, ctx) for name, group in groups.items()]
    percent = max((max(c) for s in samples for c in s["curves"]), default=0.0) > 2.0
    return ImportedFile(
        "xlsx", file, tuple(_build(s, head, ctx, percent, extra.get(s["name"], [])) for s in samples)
    )


def _sample(
    name: str, group: list[tuple[int, tuple[Any, ...]]], head: dict[str, Any], ctx: dict[str, Any]
) -> dict[str, Any]:
    """The rows of one sample: geometries, Lab, raw curves, texture and the measurement instant."""
    file = ctx["file"]
    geo_rows, labs, curves, texture = [], [], [], []
    when = None
    for r, row in group:
        where = f"sheet {SHEET!r} row {r}"
        err = factory(WorkbookImportError, file, where)
        geometry = canonical_geometry(str(row[head["geometry"]] or ""), "Geometry", err)
        geo_rows.append((geometry, err))
        if head["date"] is not None and when is None:
            when = _instant(row[head["date"]], file, where)
        if head["lab"] is not None:
            labs.append([_number(row[c], h, file, where) for c, h in zip(head["lab"], "Lab", strict=True)])
        if head["spectral"]:
            curves.append([_number(row[i], f"{w:g} nm", file, where) for w, i in head["spectral"]])
        for qty, i in head["texture"]:
            v = _texture_value(ctx["vendor"], qty, row[i], geometry, file, where)
            if v is not None:
                texture.append(v)
    return {
        "name": name,
        "first": group[0][0],
        "rows": geo_rows,
        "labs": labs,
        "curves": curves,
        "texture": texture,
        "when": when,
    }


def _build(
    s: dict[str, Any], head: dict[str, Any], ctx: dict[str, Any], percent: bool, extra: list[VendorValue]
) -> ImportedMeasurement:
    """Validate one sample (:func:`build_measurement`); percent curves become reflectance factors."""
    where = f"sheet {SHEET!r} row {s['first']}"
    curves = [[v / 100.0 for v in c] for c in s["curves"]] if percent else s["curves"]
    illuminant, observer = ctx["conditions"]
    return build_measurement(
        sample=s["name"],
        rows=s["rows"],
        lab=s["labs"] if head["lab"] is not None else None,
        wavelengths_nm=[w for w, _ in head["spectral"]] if head["spectral"] else None,
        spectra=curves if head["spectral"] else None,
        instrument=ctx["instrument"],
        illuminant=illuminant,
        observer=observer,
        measured_at=s["when"] or ctx["measured_at"],
        texture=_merge_texture([*s["texture"], *extra], ctx["file"], where),
        err=factory(WorkbookImportError, ctx["file"], where),
    )


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
    header.append("Date/Time")
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
            row.append("" if m.measured_at is None else m.measured_at.isoformat())
            ws.append(row)
    info = wb.create_sheet(INFO)
    info.append(["Instrument", first.instrument.model])
    info.append(["Serial", first.instrument.serial])
    info.append(["Manufacturer", first.instrument.manufacturer])
    info.append(["Measured at", "" if first.measured_at is None else first.measured_at.isoformat()])
    info.append(["Illuminant", first.illuminant])
    info.append(["Observer", observer_degrees(first.observer)])
    wb.save(Path(path))
