"""``station measure --json`` output (and ``station import --json`` output) read back as measurements.

So every command that takes "a measurement file" takes what the station itself prints: a measure
document (``geometries``, ``lab``, optional ``spectra`` with ``wavelengths_nm``, ``model``, ``serial``,
``time``; one sample, named by ``panel`` or the file's stem) or an import document
(``{"measurements": [...]}``, as ``station import --json`` prints it). Refusals are
:class:`~station.ingest.errors.JsonImportError` naming the JSON path of the value.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from station.ingest.errors import JsonImportError
from station.ingest.formats._text import decode_utf8, factory, parse_instant, read_bytes
from station.ingest.formats.measurement import (
    OBSERVERS,
    ImportedFile,
    ImportedMeasurement,
    Instrument,
    VendorValue,
    build_measurement,
    observer_name,
)

__all__ = ["is_complete", "read_measure_json"]

#: A closed JSON string (escapes included), as bytes.
_STRINGS = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number JSON allows")


def _list(doc: dict[str, Any], key: str, file: str, where: str) -> list[Any] | None:
    value = doc.get(key)
    if value is None:
        return None
    if not isinstance(value, list):
        raise JsonImportError(file, where, key, "a list", type(value).__name__)
    return value


def _numbers(rows: list[Any], key: str, file: str, where: str) -> list[list[float]]:
    out = []
    for i, row in enumerate(rows):
        if not isinstance(row, list) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in row
        ):
            raise JsonImportError(file, f"{where}.{key}[{i}]", key, "a list of numbers", row)
        out.append([float(v) for v in row])
    return out


def _one(doc: dict[str, Any], file: str, where: str, default_sample: str) -> ImportedMeasurement:
    err = factory(JsonImportError, file, where)
    geometries = _list(doc, "geometries", file, where)
    if not geometries or not all(isinstance(g, str) for g in geometries):
        raise JsonImportError(
            file, where, "geometries", 'a list of geometry names ("45as15")', doc.get("geometries")
        )
    lab = _list(doc, "lab", file, where)
    spectra = _list(doc, "spectra", file, where)
    wl = _list(doc, "wavelengths_nm", file, where)
    if spectra == []:  # a gloss-only measure document prints empty lists
        spectra = None
    rows = [(g, factory(JsonImportError, file, f"{where}.geometries[{i}]")) for i, g in enumerate(geometries)]
    found = doc.get("instrument")
    instrument_doc: dict[str, Any] = found if isinstance(found, dict) else {}
    instrument = Instrument(
        model=str(instrument_doc.get("model") or doc.get("model") or ""),
        serial=str(instrument_doc.get("serial") or doc.get("serial") or ""),
        manufacturer=str(instrument_doc.get("manufacturer") or ""),
    )
    texture = []
    for i, t in enumerate(_list(doc, "texture", file, where) or []):
        if not isinstance(t, dict) or not isinstance(t.get("value"), (int, float)):
            raise JsonImportError(
                file, f"{where}.texture[{i}]", "texture", "{vendor, name, geometry, value}", t
            )
        texture.append(
            VendorValue(
                str(t.get("vendor", "")),
                str(t.get("name", "")),
                float(t["value"]),
                str(t.get("geometry", "")),
            )
        )
    when = doc.get("measured_at", doc.get("time"))
    sample = doc.get("sample") or doc.get("panel") or default_sample
    return build_measurement(
        sample=str(sample),
        rows=rows,
        lab=None if lab is None else _numbers(lab, "lab", file, where),
        wavelengths_nm=None
        if spectra is None or wl is None
        else [float(w) for w in wl if isinstance(w, (int, float))],
        spectra=None if spectra is None else _numbers(spectra, "spectra", file, where),
        instrument=instrument,
        illuminant=str(doc.get("illuminant") or "D65"),
        observer=observer_name(str(doc.get("observer") or "")) or str(doc.get("observer") or OBSERVERS[1]),
        measured_at=parse_instant(str(when)) if when else None,
        texture=texture,
        err=err,
    )


def is_complete(data: bytes) -> bool:
    """Whether every string, object and array *data* opens is closed (a document cut short is not);
    malformed JSON counts as complete: the reader refuses it whole."""
    bare = _STRINGS.sub(b"", data)
    if b'"' in bare:  # a string still open
        return False
    opened = bare.count(b"{") + bare.count(b"[")
    return bool(bare.strip()) and opened <= bare.count(b"}") + bare.count(b"]")


def read_measure_json(path: Path | str, data: bytes | None = None) -> ImportedFile:
    """Read a ``station measure --json`` or ``station import --json`` document (module doc)."""
    path = Path(path)
    file = path.name
    text = decode_utf8(read_bytes(path, JsonImportError, data), file, JsonImportError)
    try:
        doc = json.loads(text, parse_constant=_reject_constant)
    except (json.JSONDecodeError, ValueError) as exc:
        line = getattr(exc, "lineno", 0)
        raise JsonImportError(
            file,
            f"line {line}" if line else "document",
            "json",
            "a JSON document (file truncated?)",
            str(exc),
        ) from exc
    if not isinstance(doc, dict):
        raise JsonImportError(file, "$", "json", "a JSON object", type(doc).__name__)
    if "measurements" in doc:
        items = doc["measurements"]
        if not isinstance(items, list) or not items or not all(isinstance(m, dict) for m in items):
            raise JsonImportError(file, "$.measurements", "measurements", "a non-empty list of objects")
        found = tuple(_one(m, file, f"$.measurements[{i}]", path.stem) for i, m in enumerate(items))
    else:
        found = (_one(doc, file, "$", path.stem),)
    return ImportedFile("json", file, found)
