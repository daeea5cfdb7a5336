"""CGATS.17 ASCII measurement files, as X-Rite and ArgyllCMS write them: read and write.

Layout read (ANSI CGATS.17): a first line naming the file type (``CGATS.17``, ``CTI3``, …), keyword
lines (``KEYWORD value``; a value with spaces is double-quoted, ``""`` inside quotes is one quote),
``BEGIN_DATA_FORMAT`` … ``END_DATA_FORMAT`` listing the fields, and ``BEGIN_DATA`` … ``END_DATA`` with
one row per sample and geometry. ``#`` outside quotes starts a comment. Only the first table is read.

Fields used: ``SAMPLE_ID`` and ``SAMPLE_NAME`` (rows with the same ``SAMPLE_NAME``, or without that
field the same ``SAMPLE_ID``, are one sample; a name repeating a geometry: one sample per
``SAMPLE_ID``, repeat readings); ``GEOMETRY`` (``45as15``) or ``ILLUMINATION_ANGLE`` +
``ASPECULAR_ANGLE`` (degrees) — or, in a single-geometry file without them, the keyword
``MEASUREMENT_GEOMETRY`` (``"45/0"`` → ``45as45``; every row is then one sample at that geometry);
``LAB_L``, ``LAB_A``, ``LAB_B`` and/or spectral fields ``SPECTRAL_NMxxx`` (X-Rite) or ``SPEC_xxx``
(ArgyllCMS), divided by the keyword ``SPECTRAL_NORM`` when present (``100``/``"100.000000"``: percent;
absent: reflectance factors); vendor texture fields ``SPARKLE…`` and
``GRAININESS…`` (an empty ``""`` cell means "not measured at this geometry"), tagged with the
``MANUFACTURER`` keyword (else ``INSTRUMENTATION``). Any other field and keyword is ignored.

Keywords read: ``INSTRUMENTATION`` (model; ArgyllCMS: ``TARGET_INSTRUMENT``), ``MANUFACTURER``,
``INSTRUMENT_SERIAL`` (or ``SERIAL_NUMBER``), ``CREATED`` (the measurement instant: ISO 8601, or
ArgyllCMS's ``"Wed Mar 04 09:12:44 2026"`` read as UTC), ``MEASUREMENT_SOURCE``
(``"Illumination=D65 ObserverAngle=10"``, X-Rite's form) or ``ILLUMINANT`` and ``OBSERVER``; the default
is D65 and the CIE 1964 10° observer, except in an ArgyllCMS ``CTI3`` file, whose Lab are ICC PCS
values: D50 and the CIE 1931 2° observer.

Refused (:class:`~station.ingest.errors.CgatsImportError` naming the line and field): not UTF-8, no
data table, a table without ``END_DATA`` (truncated), a row with too few or too many values, a row
count different from ``NUMBER_OF_SETS``, a missing sample, geometry or colour field, a number that
does not parse or is not finite, a repeated geometry in a sample, Lab outside the domain bound.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from station.ingest.errors import CgatsImportError
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
    single_angle_geometry,
)
from station.model.domain import geometry_name

__all__ = ["is_complete", "read_cgats", "write_cgats"]

_SPECTRAL = re.compile(r"^(?:SPECTRAL_NM_?|SPEC_)(\d+(?:\.\d+)?)$", re.IGNORECASE)
#: Conditions of an ArgyllCMS ``CTI3`` file that states none: its Lab/XYZ are ICC PCS values (D50, 2°).
_ARGYLL_CONDITIONS = ("D50", "2")
_TEXTURE = re.compile(r"^(SPARKLE|GRAININESS)", re.IGNORECASE)
_ORIGINATOR = "CACAD Station"
LAB_DECIMALS = 4
SPECTRA_DECIMALS = 6


def _tokens(line: str, file: str, lineno: int) -> list[str]:
    """Split one line into tokens: whitespace-separated, double quotes group, ``#`` starts a comment."""
    out: list[str] = []
    i, n = 0, len(line)
    while i < n:
        c = line[i]
        if c.isspace():
            i += 1
        elif c == "#":
            break
        elif c == '"':
            j, buf = i + 1, []
            while True:
                if j >= n:
                    raise CgatsImportError(file, f"line {lineno}", "quote", 'a closing "', line.strip())
                if line[j] == '"':
                    if j + 1 < n and line[j + 1] == '"':
                        buf.append('"')
                        j += 2
                        continue
                    break
                buf.append(line[j])
                j += 1
            out.append("".join(buf))
            i = j + 1
        else:
            j = i
            while j < n and not line[j].isspace() and line[j] != '"':
                j += 1
            out.append(line[i:j])
            i = j
    return out


def _float(text: str, fld: str, file: str, lineno: int) -> float:
    try:
        return float(text)
    except ValueError as exc:
        raise CgatsImportError(file, f"line {lineno}", fld, "a number", text) from exc


def _conditions(keywords: dict[str, str], file_type: str) -> tuple[str, str]:
    """Illuminant and observer: ``MEASUREMENT_SOURCE``, ``ILLUMINANT``/``OBSERVER``, else the default of
    the file type (ArgyllCMS ``CTI3``: D50 and 2°; others D65 and 10°)."""
    ill0, obs0 = _ARGYLL_CONDITIONS if file_type == "CTI3" else ("D65", "10")
    illuminant, observer = ill0, observer_name(obs0) or ""
    source = keywords.get("MEASUREMENT_SOURCE", "")
    for part in source.replace(",", " ").split():
        key, _, value = part.partition("=")
        if key.lower() == "illumination" and value:
            illuminant = value.upper()
        elif key.lower() == "observerangle" and value:
            observer = observer_name(value) or value
    if "ILLUMINANT" in keywords:
        illuminant = keywords["ILLUMINANT"].strip().upper()
    if "OBSERVER" in keywords:
        observer = observer_name(keywords["OBSERVER"]) or keywords["OBSERVER"]
    return illuminant, observer


def is_complete(data: bytes) -> bool:
    """Whether *data* holds a whole CGATS file: its ``END_DATA`` line is written (a writer still at
    work has not written it yet)."""
    return any(line.split()[:1] == [b"END_DATA"] for line in data.upper().splitlines())


def read_cgats(path: Path | str, data: bytes | None = None) -> ImportedFile:
    """Read a CGATS.17 file into one :class:`ImportedMeasurement` per sample (module doc for the rules)."""
    path = Path(path)
    file = path.name
    text = decode_utf8(read_bytes(path, CgatsImportError, data), file, CgatsImportError)
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise CgatsImportError(file, "line 1", "file type", "a first line such as CGATS.17", "empty")
    keywords: dict[str, str] = {}
    fields: list[str] = []
    rows: list[tuple[int, list[str]]] = []
    state = "header"
    declared_sets: tuple[int, int] | None = None
    for lineno, raw in enumerate(lines[1:], start=2):
        toks = _tokens(raw, file, lineno)
        if not toks:
            continue
        head = toks[0].upper()
        if state == "header":
            if head == "BEGIN_DATA_FORMAT":
                state, fields = "format", [t.upper() for t in toks[1:]]
            elif head == "BEGIN_DATA":
                raise CgatsImportError(file, f"line {lineno}", "BEGIN_DATA", "a BEGIN_DATA_FORMAT first")
            elif head == "NUMBER_OF_SETS":
                value = toks[1] if len(toks) > 1 else ""
                if not value.isdigit():
                    raise CgatsImportError(file, f"line {lineno}", "NUMBER_OF_SETS", "a count", value)
                declared_sets = (int(value), lineno)
            elif head != "KEYWORD":
                keywords[head] = toks[1] if len(toks) > 1 else ""
        elif state == "format":
            if head == "END_DATA_FORMAT":
                state = "between"
            else:
                fields.extend(t.upper() for t in toks)
        elif state == "between":
            if head == "BEGIN_DATA":
                state = "data"
            elif head == "NUMBER_OF_SETS":
                value = toks[1] if len(toks) > 1 else ""
                if not value.isdigit():
                    raise CgatsImportError(file, f"line {lineno}", "NUMBER_OF_SETS", "a count", value)
                declared_sets = (int(value), lineno)
            elif head != "KEYWORD":
                keywords[head] = toks[1] if len(toks) > 1 else ""
        elif state == "data":
            if head == "END_DATA":
                state = "done"
                break
            if len(toks) != len(fields):
                raise CgatsImportError(
                    file, f"line {lineno}", "row", f"{len(fields)} values (one per field)", len(toks)
                )
            rows.append((lineno, toks))
    last = len(lines)
    if state in ("header", "format"):
        raise CgatsImportError(file, f"line {last}", "BEGIN_DATA", "a data table (file truncated?)")
    if state in ("between", "data"):
        raise CgatsImportError(file, f"line {last}", "END_DATA", "an END_DATA line (file truncated?)")
    if declared_sets is not None and declared_sets[0] != len(rows):
        raise CgatsImportError(
            file, f"line {declared_sets[1]}", "NUMBER_OF_SETS", f"the number of data rows ({len(rows)})",
            declared_sets[0],
        )  # fmt: skip
    if not rows:
        raise CgatsImportError(file, "BEGIN_DATA", "rows", "at least one data row", 0)
    file_type = (_tokens(lines[0], file, 1) or [""])[0].upper()
    return ImportedFile("cgats", file, _samples(file, fields, rows, keywords, file_type))


def _created(text: str) -> dt.datetime | None:
    """The ``CREATED`` keyword: ISO 8601 (naive means UTC), or ArgyllCMS's C ``ctime`` form
    (``"Wed Mar 04 09:12:44 2026"``, local time without a zone: read as UTC); else ``None``."""
    value = parse_instant(text)
    if value is None and text.strip():
        try:
            value = dt.datetime.strptime(" ".join(text.split()), "%a %b %d %H:%M:%S %Y").replace(
                tzinfo=dt.UTC
            )
        except ValueError:
            return None
    return value


def _layout(file: str, fields: list[str], keywords: dict[str, str]) -> dict[str, Any]:
    """Which fields hold what, checked against the format's rules (module doc)."""
    col = {f: i for i, f in enumerate(fields)}
    where_fmt = "BEGIN_DATA_FORMAT"
    key_field = "SAMPLE_NAME" if "SAMPLE_NAME" in col else "SAMPLE_ID"
    if key_field not in col:
        raise CgatsImportError(file, where_fmt, "SAMPLE_ID", "a SAMPLE_ID or SAMPLE_NAME field")
    single = None
    if "GEOMETRY" not in col and not {"ILLUMINATION_ANGLE", "ASPECULAR_ANGLE"} <= col.keys():
        if "MEASUREMENT_GEOMETRY" not in keywords:
            raise CgatsImportError(
                file, where_fmt, "GEOMETRY", "a GEOMETRY field, ILLUMINATION_ANGLE and ASPECULAR_ANGLE, "
                'or for a single-geometry file a MEASUREMENT_GEOMETRY keyword (e.g. "45/0")',
            )  # fmt: skip
        err = factory(CgatsImportError, file, "header")
        single = single_angle_geometry(keywords["MEASUREMENT_GEOMETRY"], "MEASUREMENT_GEOMETRY", err)
    lab_cols = [col.get(f"LAB_{c}") for c in "LAB"]
    has_lab = all(c is not None for c in lab_cols)
    if any(c is not None for c in lab_cols) and not has_lab:
        raise CgatsImportError(file, where_fmt, "LAB_L", "all of LAB_L, LAB_A, LAB_B (or none)")
    spectral = sorted(
        ((float(m.group(1)), i) for i, f in enumerate(fields) if (m := _SPECTRAL.match(f))),
        key=lambda t: t[0],
    )
    if not has_lab and not spectral:
        raise CgatsImportError(
            file, where_fmt, "LAB_L", "LAB_L/LAB_A/LAB_B and/or SPECTRAL_NMxxx or SPEC_xxx fields"
        )
    norm_text = keywords.get("SPECTRAL_NORM", "").strip()
    try:
        divisor = float(norm_text) if norm_text else 1.0
    except ValueError:
        divisor = math.nan
    if not (divisor > 0 and math.isfinite(divisor)):
        raise CgatsImportError(file, "header", "SPECTRAL_NORM", "a number > 0 (100: percent)", norm_text)
    texture_cols = [(f, i) for i, f in enumerate(fields) if _TEXTURE.match(f)]
    vendor = keywords.get("MANUFACTURER", "").strip() or keywords.get("INSTRUMENTATION", "").strip()
    if texture_cols and not vendor:
        raise CgatsImportError(
            file, "header", "MANUFACTURER", "a MANUFACTURER or INSTRUMENTATION keyword with texture fields"
        )
    return {
        "col": col, "key": key_field, "single": single, "lab": lab_cols if has_lab else None,
        "spectral": spectral, "divisor": divisor, "texture": texture_cols, "vendor": vendor,
    }  # fmt: skip


def _row(file: str, fields: list[str], lay: dict[str, Any], lineno: int, toks: list[str], acc: dict) -> None:
    """Add one data row (one geometry of a sample) to the sample's accumulators *acc*."""
    col = lay["col"]
    err = factory(CgatsImportError, file, f"line {lineno}")
    if lay["single"] is not None:
        geometry = lay["single"]
    else:
        if "GEOMETRY" in col:
            name = toks[col["GEOMETRY"]]
        else:
            ill = _float(toks[col["ILLUMINATION_ANGLE"]], "ILLUMINATION_ANGLE", file, lineno)
            asp = _float(toks[col["ASPECULAR_ANGLE"]], "ASPECULAR_ANGLE", file, lineno)
            name = geometry_name(ill, asp)
        geometry = canonical_geometry(name, "GEOMETRY", err)
    acc["rows"].append((geometry, err))
    if lay["lab"] is not None:
        acc["lab"].append([_float(toks[c], f, file, lineno) for c, f in zip(lay["lab"], ("LAB_L", "LAB_A", "LAB_B"), strict=True)])  # fmt: skip
    if lay["spectral"]:
        acc["spectra"].append([_float(toks[i], fields[i], file, lineno) / lay["divisor"] for _, i in lay["spectral"]])  # fmt: skip
    for f, i in lay["texture"]:
        if toks[i] == "":
            continue
        value = _float(toks[i], f, file, lineno)
        per_sample = f.startswith("GRAININESS")
        acc["texture"].append(VendorValue(lay["vendor"], f.lower(), value, "" if per_sample else geometry))


def _samples(
    file: str, fields: list[str], rows: list[tuple[int, list[str]]], keywords: dict[str, str], file_type: str
) -> tuple[ImportedMeasurement, ...]:
    """One validated measurement per sample (rows grouped by ``SAMPLE_NAME``, else ``SAMPLE_ID``)."""
    lay = _layout(file, fields, keywords)
    instrument = Instrument(
        model=(keywords.get("INSTRUMENTATION") or keywords.get("TARGET_INSTRUMENT") or "").strip(),
        serial=(keywords.get("INSTRUMENT_SERIAL") or keywords.get("SERIAL_NUMBER") or "").strip(),
        manufacturer=keywords.get("MANUFACTURER", "").strip(),
    )
    illuminant, observer = _conditions(keywords, file_type)
    measured_at = _created(keywords.get("CREATED", ""))
    groups = _groups(file, rows, lay)
    out = []
    for (key, _), group in groups.items():
        acc: dict[str, list[Any]] = {"rows": [], "lab": [], "spectra": [], "texture": []}
        for lineno, toks in group:
            _row(file, fields, lay, lineno, toks, acc)
        out.append(
            build_measurement(
                sample=key,
                rows=acc["rows"],
                lab=acc["lab"] if lay["lab"] is not None else None,
                wavelengths_nm=[w for w, _ in lay["spectral"]] if lay["spectral"] else None,
                spectra=acc["spectra"] if lay["spectral"] else None,
                instrument=instrument,
                illuminant=illuminant,
                observer=observer,
                measured_at=measured_at,
                texture=_dedupe(acc["texture"], file, group[0][0]),
                err=factory(CgatsImportError, file, f"line {group[0][0]}"),
            )
        )
    return tuple(out)


def _dedupe(values: list[VendorValue], file: str, lineno: int) -> list[VendorValue]:
    """Per-sample values repeated on each row of a sample count once; they must agree."""
    seen: dict[tuple[str, str], VendorValue] = {}
    for v in values:
        prior = seen.get((v.name, v.geometry))
        if prior is not None and prior.value != v.value:
            raise CgatsImportError(file, f"line {lineno}", v.name.upper(), "one value per sample", v.value)
        seen[(v.name, v.geometry)] = v
    return list(seen.values())


def _quote(text: str) -> str:
    return '"' + text.replace('"', '""') + '"'


def _num(value: float, decimals: int) -> str:
    return f"{value:.{decimals}f}"


def _groups(
    file: str, rows: list[tuple[int, list[str]]], lay: dict[str, Any]
) -> dict[tuple[str, str], list[tuple[int, list[str]]]]:
    """The data rows per sample: grouped by ``SAMPLE_NAME`` (else ``SAMPLE_ID``); when one name holds the
    same geometry twice and the file has both fields, the rows of each ``SAMPLE_ID`` are a repeat reading
    of their own (what :func:`write_cgats` writes for repeats of one sample)."""
    col = lay["col"]
    geo = [col[f] for f in ("GEOMETRY", "ILLUMINATION_ANGLE", "ASPECULAR_ANGLE") if f in col]
    by_id = lay["key"] == "SAMPLE_NAME" and "SAMPLE_ID" in col
    if by_id:
        seen: dict[str, set[tuple[str, ...]]] = {}
        by_id = False
        for _, toks in rows:
            where, had = tuple(toks[i] for i in geo), seen.setdefault(toks[col["SAMPLE_NAME"]].strip(), set())
            by_id = by_id or where in had
            had.add(where)
    groups: dict[tuple[str, str], list[tuple[int, list[str]]]] = {}
    for lineno, toks in rows:
        key = toks[col[lay["key"]]].strip()
        if not key:
            raise CgatsImportError(file, f"line {lineno}", lay["key"], "a non-empty sample", key)
        groups.setdefault((key, toks[col["SAMPLE_ID"]].strip() if by_id else ""), []).append((lineno, toks))
    return groups


def write_cgats(measurements: Sequence[ImportedMeasurement], path: Path | str | None = None) -> str:
    """CGATS.17 text of *measurements* (one row per sample and geometry); written to *path* when given.

    Every measurement needs the same wavelength grid (or none) and, when one has Lab, all of them.
    Instrument, illuminant, observer and time come from the first measurement.
    """
    if not measurements:
        raise CgatsImportError(str(path or "cgats"), "", "measurements", "at least one measurement", 0)
    first = measurements[0]
    wl = first.wavelengths_nm
    has_lab = first.lab is not None
    fields = ["SAMPLE_ID", "SAMPLE_NAME", "GEOMETRY"]
    if has_lab:
        fields += ["LAB_L", "LAB_A", "LAB_B"]
    if wl is not None:
        fields += [f"SPECTRAL_NM{w:g}" for w in wl]
    texture_names = sorted({t.name.upper() for m in measurements for t in m.texture})
    fields += texture_names
    lines = [
        "CGATS.17",
        f"ORIGINATOR {_quote(_ORIGINATOR)}",
        f"DESCRIPTOR {_quote('multi-angle measurements')}",
    ]
    if first.measured_at is not None:
        lines.append(f"CREATED {_quote(first.measured_at.isoformat())}")
    if first.instrument.model:
        lines.append(f"INSTRUMENTATION {_quote(first.instrument.model)}")
    if first.instrument.manufacturer:
        lines.append(f"MANUFACTURER {_quote(first.instrument.manufacturer)}")
    if first.instrument.serial:
        lines += ['KEYWORD "INSTRUMENT_SERIAL"', f"INSTRUMENT_SERIAL {_quote(first.instrument.serial)}"]
    source = f"Illumination={first.illuminant} ObserverAngle={observer_degrees(first.observer)}"
    lines.append(f"MEASUREMENT_SOURCE {_quote(source)}")
    for f in ("SAMPLE_NAME", "GEOMETRY", *texture_names):
        lines.append(f'KEYWORD "{f}"')
    lines += [f"NUMBER_OF_FIELDS {len(fields)}", "BEGIN_DATA_FORMAT", " ".join(fields), "END_DATA_FORMAT"]
    body = []
    for n, m in enumerate(measurements, start=1):
        if m.wavelengths_nm != wl or (m.lab is not None) != has_lab:
            raise CgatsImportError(
                str(path or "cgats"), f"measurement {n}", "wavelengths_nm", "the first measurement's layout"
            )
        by_geo = {(t.name.upper(), t.geometry): t.value for t in m.texture}
        for k, g in enumerate(m.geometries):
            cells = [str(n), _quote(m.sample), g]
            if m.lab is not None:
                cells += [_num(v, LAB_DECIMALS) for v in m.lab[k]]
            if m.spectra is not None:
                cells += [_num(v, SPECTRA_DECIMALS) for v in m.spectra[k]]
            for t in texture_names:
                value = by_geo.get((t, g), by_geo.get((t, "")))
                cells.append('""' if value is None else repr(float(value)))
            body.append(" ".join(cells))
    lines += [f"NUMBER_OF_SETS {len(body)}", "BEGIN_DATA", *body, "END_DATA", ""]
    text = "\n".join(lines)
    if path is not None:
        Path(path).write_text(text, encoding="utf-8")
    return text
