"""Imported measurements → ingest records (:class:`~station.ingest.Reading`), idempotent by content.

Each record's client id is a UUID5 of the file's SHA-256, the measurement's index in the file and the
illumination block, so importing the same bytes again (a retry, a watch folder restarted after being
killed mid-file, the same file dropped twice) stores nothing new: the ingest path answers
``"duplicate"``. The payload is a function of the file too (its instant, or the file's modification
time when the file states none), so a replay never meets a client-id conflict.

A stored reading holds one illumination block (the measurement table keys geometries by aspecular
angle): by default the 45° block (``station.model.domain.ILLUMINATION_DEG``). Lab is the file's (with
its illuminant and observer), or computed from the spectra when the file gives none.
"""

from __future__ import annotations

import datetime as dt
import functools
import hashlib
import uuid
from pathlib import Path

from pydantic import ValidationError

from station.ingest.errors import ImportFileError
from station.ingest.formats.measurement import ImportedFile, ImportedMeasurement, lab_of
from station.ingest.records import LAB_DECIMALS, SPECTRA_DECIMALS
from station.ingest.schema import InstrumentRef, PanelRef, Reading
from station.model.domain import ILLUMINATION_DEG, parse_geometry

__all__ = ["file_sha256", "import_client_id", "readings_from_import"]

_IMPORT_NAMESPACE = uuid.UUID("6f1d2f0e-4b7a-4c55-9d8e-3a7b1c2d4e5f")
#: Notes of the panel of an imported sample: this prefix and the sample name.
NOTE_PREFIX = "sample: "


def file_sha256(path: Path | str) -> str:
    """SHA-256 (hex) of the bytes of *path*."""
    h = hashlib.sha256()
    with Path(path).open("rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def import_client_id(sha256: str, index: int, illumination_deg: float) -> uuid.UUID:
    """The client id of measurement *index* (0-based) of the file with *sha256*, one illumination block."""
    return uuid.uuid5(_IMPORT_NAMESPACE, f"{sha256}/{index}/{illumination_deg:g}")


def _block(m: ImportedMeasurement, illumination_deg: float) -> list[int]:
    return [i for i, g in enumerate(m.geometries) if parse_geometry(g)[0] == illumination_deg]


def readings_from_import(
    imported: ImportedFile,
    *,
    sha256: str,
    operator: str,
    fallback_time: dt.datetime,
    illumination_deg: float = ILLUMINATION_DEG,
    job: str | None = None,
    part: str | None = None,
    error: type[ImportFileError] = ImportFileError,
) -> list[Reading]:
    """One validated :class:`Reading` per measurement of *imported* (its *illumination_deg* block).

    *fallback_time* (UTC) is the instant of a measurement whose file states none. With *job* and
    *part* each reading names its panel: job, part and ``notes = "sample: NAME"`` (found or created
    by the ingest store). Raises *error* naming the measurement when it has no geometry lit from
    *illumination_deg* or a value the ingest record refuses.
    """
    if (job is None) != (part is None):
        raise error(imported.file, "", "job" if job is None else "part", "--job and --part together")
    out = []
    for n, m in enumerate(imported.measurements):
        where = f"measurement {n + 1} ({m.sample})"
        idx = _block(m, illumination_deg)
        if not idx:
            lit = sorted({parse_geometry(g)[0] for g in m.geometries})
            raise error(imported.file, where, "illumination_deg", f"one of {lit}", illumination_deg)
        lab = lab_of(m, functools.partial(error, imported.file, where))
        serial = m.instrument.serial or "unknown"
        model = m.instrument.model or m.instrument.manufacturer or "unknown"
        try:
            panel = None
            if job is not None and part is not None:
                panel = PanelRef(job=job, part=part, notes=f"{NOTE_PREFIX}{m.sample}"[:4000])
            reading = Reading(
                client_id=import_client_id(sha256, n, illumination_deg),
                instrument=InstrumentRef(serial=serial[:64], model=model[:64], kind="multiangle"),
                calibration=None,
                panel=panel,
                operator=operator,
                measured_at=m.measured_at or fallback_time,
                illuminant=m.illuminant,  # type: ignore[arg-type]  # validated against the Literal
                observer=m.observer,  # type: ignore[arg-type]
                geometries_deg=[parse_geometry(m.geometries[i])[1] for i in idx],
                lab=lab[idx].round(LAB_DECIMALS).tolist(),
                wavelengths_nm=None if m.wavelengths_nm is None else list(m.wavelengths_nm),
                spectra=None
                if m.spectra is None
                else [[round(v, SPECTRA_DECIMALS) for v in m.spectra[i]] for i in idx],
            )
        except ValidationError as exc:
            first = exc.errors()[0]
            fld = ".".join(str(p) for p in first["loc"]) or "reading"
            raise error(imported.file, where, fld, first["msg"], first.get("input")) from exc
        out.append(reading)
    return out
