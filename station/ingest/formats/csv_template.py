"""The station CSV import template (docs/import.md): for any instrument software without CxF or CGATS.

One row per sample and geometry, UTF-8, comma-separated, a header row naming the columns (any order,
case-insensitive); lines starting with ``#`` before the header are comments.

=================  ========  ==============================================================
column             required  meaning
=================  ========  ==============================================================
``sample``         yes       sample (panel) name; rows with the same name are one sample
``geometry``       yes       ``45as15`` style (illumination ``as`` aspecular, degrees)
``L``, ``a``, ``b``  one of    CIE L*a*b* under ``illuminant`` / ``observer``
``nm400`` …        these     reflectance factor (0–1, unitless) at that wavelength, nm
``instrument``     no        instrument model
``serial``         no        instrument serial number
``manufacturer``   no        instrument manufacturer
``illuminant``     no        D65 (default), D50, A, C, F2, F7, F11
``observer``       no        10 (default) or 2, degrees
``measured_at``    no        ISO 8601 instant, e.g. ``2026-11-23T08:30:00Z``
``texture:V:NAME`` no        vendor V's texture value NAME at this geometry (``texture:V:NAME:sample``
                             for a per-sample value such as graininess); empty = not measured
=================  ========  ==============================================================

The per-sample columns (instrument … measured_at) are read from a sample's first row; a per-sample
texture value may stand on any of its rows (on several: the same value, else refused naming the column). A text cell a
spreadsheet would run as a formula (``=``, ``+``, ``@`` …) is refused unless written with a leading
single quote (which is removed), as :func:`write_csv` writes it (:mod:`station.csv_cells`).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from station.csv_cells import escape_cell, is_formula
from station.ingest.errors import CsvImportError
from station.ingest.formats._text import decode_utf8, factory, parse_instant, read_bytes
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

__all__ = ["TEMPLATE_COLUMNS", "is_complete", "read_csv", "write_csv"]

#: Columns of the template other than the spectral ``nmXXX`` and ``texture:…`` ones.
TEMPLATE_COLUMNS = (
    "sample",
    "geometry",
    "L",
    "a",
    "b",
    "instrument",
    "serial",
    "manufacturer",
    "illuminant",
    "observer",
    "measured_at",
)
LAB_DECIMALS = 4
SPECTRA_DECIMALS = 6


def _text(cell: str, fld: str, file: str, lineno: int) -> str:
    if cell.startswith("'") and is_formula(cell[1:]):
        return cell[1:]
    if is_formula(cell) and not _is_number(cell):
        raise CsvImportError(
            file, f"line {lineno}", fld, "text that does not start with = + - @ (or a leading ')", cell
        )
    return cell


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _float(cell: str, fld: str, file: str, lineno: int) -> float:
    try:
        return float(cell)
    except ValueError as exc:
        raise CsvImportError(file, f"line {lineno}", fld, "a number", cell) from exc


def is_complete(data: bytes) -> bool:
    """Whether *data* ends with a line break. A CSV has no end marker, so this only tells a row cut
    short; a writer that pauses between rows must write under a ``.part`` name and rename the file
    when done (docs/import.md, watch folder)."""
    return data.endswith((b"\n", b"\r"))


def _table(text: str, file: str) -> tuple[int, list[list[str]]]:
    """The first non-comment line's index (the header) and the CSV rows from it on."""
    lines = text.splitlines()
    start = 0
    while start < len(lines) and (not lines[start].strip() or lines[start].lstrip().startswith("#")):
        start += 1
    if start == len(lines):
        raise CsvImportError(file, "line 1", "header", "a header row (sample,geometry,L,a,b,…)", "empty")
    try:
        return start, list(csv.reader(io.StringIO("\n".join(lines[start:])), strict=True))
    except csv.Error as exc:
        raise CsvImportError(file, f"line {start + 1}", "csv", "well-formed CSV", str(exc)) from exc


def _columns(header: list[str], where: str, file: str) -> dict[str, Any]:
    """Which columns hold what (module doc), checked: each once, sample and geometry, Lab whole."""
    lower = [h.lower() for h in header]
    col = {h: i for i, h in enumerate(lower)}
    if len(col) != len(lower):
        dup = next(h for h in lower if lower.count(h) > 1)
        raise CsvImportError(file, where, "header", "each column once", dup)
    for required in ("sample", "geometry"):
        if required not in col:
            raise CsvImportError(file, where, required, f"a {required!r} column", header)
    lab_cols = [col.get(c) for c in "lab"]
    has_lab = all(c is not None for c in lab_cols)
    if any(c is not None for c in lab_cols) and not has_lab:
        raise CsvImportError(file, where, "L", "all of the L, a, b columns (or none)", header)
    spectral: list[tuple[float, int]] = []
    texture_cols: list[tuple[str, str, bool, int]] = []
    for i, h in enumerate(lower):
        if h.startswith("nm") and _is_number(h[2:]):
            spectral.append((float(h[2:]), i))
        elif h.startswith("texture:"):
            parts = header[i].split(":")
            if len(parts) not in (3, 4) or not parts[1] or not parts[2] or parts[3:] not in ([], ["sample"]):
                raise CsvImportError(
                    file, where, "header", "texture:VENDOR:NAME or texture:VENDOR:NAME:sample", header[i]
                )
            texture_cols.append((parts[1], parts[2], len(parts) == 4, i))
    spectral.sort()
    if not has_lab and not spectral:
        raise CsvImportError(file, where, "L", "L, a, b and/or nmXXX columns", header)
    return {"col": col, "lab": lab_cols if has_lab else None, "spectral": spectral, "texture": texture_cols}


def read_csv(path: Path | str, data: bytes | None = None) -> ImportedFile:
    """Read a file in the CSV template into one :class:`ImportedMeasurement` per sample."""
    path = Path(path)
    file = path.name
    text = decode_utf8(read_bytes(path, CsvImportError, data), file, CsvImportError)
    start, table = _table(text, file)
    header = [h.strip() for h in table[0]]
    lay = _columns(header, f"line {start + 1}", file)
    groups: dict[str, list[tuple[int, list[str]]]] = {}
    for k, row in enumerate(table[1:], start=start + 2):
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise CsvImportError(file, f"line {k}", "row", f"{len(header)} cells (one per column)", len(row))
        name = _text(row[lay["col"]["sample"]].strip(), "sample", file, k)
        if not name:
            raise CsvImportError(file, f"line {k}", "sample", "a non-empty sample name", "")
        groups.setdefault(name, []).append((k, row))
    if not groups:
        raise CsvImportError(file, f"line {start + 1}", "rows", "at least one data row", 0)
    return ImportedFile("csv", file, tuple(_sample(name, g, header, lay, file) for name, g in groups.items()))


def _sample(
    name: str, group: list[tuple[int, list[str]]], header: list[str], lay: dict[str, Any], file: str
) -> ImportedMeasurement:
    """One sample's rows as a validated measurement; per-sample columns are read from its first row."""
    col = lay["col"]
    k0, first = group[0]

    def opt(column: str) -> str:
        return _text(first[col[column]].strip(), column, file, k0) if column in col else ""

    observer_text = opt("observer") or "10"
    when = opt("measured_at")
    measured_at = parse_instant(when)
    if when and measured_at is None:
        raise CsvImportError(file, f"line {k0}", "measured_at", "an ISO 8601 instant", when)
    rows, labs, curves, texture = [], [], [], []
    per_sample_values: dict[int, float] = {}  # column → the per-sample value, whichever row holds it
    for k, row in group:
        err = factory(CsvImportError, file, f"line {k}")
        rows.append((row[col["geometry"]], err))
        if lay["lab"] is not None:
            labs.append([_float(row[c], h, file, k) for c, h in zip(lay["lab"], "Lab", strict=True)])
        if lay["spectral"]:
            curves.append([_float(row[i], header[i], file, k) for _, i in lay["spectral"]])
        for vendor, qty, per_sample, i in lay["texture"]:
            if not row[i].strip():
                continue
            value = _float(row[i], header[i], file, k)
            if per_sample and i in per_sample_values:
                if per_sample_values[i] != value:
                    raise CsvImportError(
                        file,
                        f"line {k}",
                        header[i],
                        f"one value per sample ({per_sample_values[i]!r})",
                        value,
                    )
                continue
            if per_sample:
                per_sample_values[i] = value
            geometry = "" if per_sample else canonical_geometry(row[col["geometry"]], "geometry", err)
            texture.append(VendorValue(vendor, qty, value, geometry))
    return build_measurement(
        sample=name,
        rows=rows,
        lab=labs if lay["lab"] is not None else None,
        wavelengths_nm=[w for w, _ in lay["spectral"]] if lay["spectral"] else None,
        spectra=curves if lay["spectral"] else None,
        instrument=Instrument(opt("instrument"), opt("serial"), opt("manufacturer")),
        illuminant=(opt("illuminant") or "D65").upper(),
        observer=observer_name(observer_text) or observer_text,
        measured_at=measured_at,
        texture=texture,
        err=factory(CsvImportError, file, f"line {k0}"),
    )


def write_csv(measurements: Sequence[ImportedMeasurement], path: Path | str | None = None) -> str:
    """The CSV template text of *measurements*; written to *path* when given (same layout rules as CGATS)."""
    if not measurements:
        raise CsvImportError(str(path or "csv"), "", "measurements", "at least one measurement", 0)
    first = measurements[0]
    wl = first.wavelengths_nm
    header = ["sample", "geometry"]
    if first.lab is not None:
        header += ["L", "a", "b"]
    if wl is not None:
        header += [f"nm{w:g}" for w in wl]
    header += ["instrument", "serial", "manufacturer", "illuminant", "observer", "measured_at"]
    tex = sorted({(t.vendor, t.name, t.geometry == "") for m in measurements for t in m.texture})
    header += [f"texture:{v}:{n}" + (":sample" if s else "") for v, n, s in tex]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    buf.write("# station measurement import template (docs/import.md)\n")
    writer.writerow(header)
    for n, m in enumerate(measurements, start=1):
        if m.wavelengths_nm != wl or (m.lab is None) != (first.lab is None):
            raise CsvImportError(
                str(path or "csv"), f"measurement {n}", "wavelengths_nm", "the first measurement's layout"
            )
        values = {(t.vendor, t.name, t.geometry): t.value for t in m.texture}
        for k, g in enumerate(m.geometries):
            cells = [escape_cell(m.sample), g]
            if m.lab is not None:
                cells += [f"{v:.{LAB_DECIMALS}f}" for v in m.lab[k]]
            if m.spectra is not None:
                cells += [f"{v:.{SPECTRA_DECIMALS}f}" for v in m.spectra[k]]
            cells += [escape_cell(m.instrument.model), escape_cell(m.instrument.serial)]
            cells += [escape_cell(m.instrument.manufacturer), m.illuminant, observer_degrees(m.observer)]
            cells.append("" if m.measured_at is None else m.measured_at.isoformat())
            for v, name, per_sample in tex:
                value = values.get((v, name, "" if per_sample else g))
                cells.append("" if value is None else repr(float(value)))
            writer.writerow(cells)
    text = buf.getvalue()
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text
