"""Imported measurements → ingest records (:class:`~station.ingest.Reading`), idempotent by content.

Each record's client id is a UUID5 of the file's SHA-256, the measurement's index in the file and the
illumination block, so importing the same bytes again (a retry, a watch folder restarted after being
killed mid-file, the same file dropped twice) stores nothing new: the ingest path answers
``"duplicate"``. The payload is a function of the file too (its instant, or the file's modification
time when the file states none), so a replay never meets a client-id conflict.

A stored reading holds one illumination block (the measurement table keys geometries by aspecular
angle under its ``illumination_deg``): a two-illumination file (an MA-T12's 45° and 15° blocks) becomes
one reading per block on the same panel, or the one block asked for. Lab is the file's (with its
illuminant and observer), or computed from the spectra when the file gives none. Vendor texture values
travel vendor-tagged with the block of their geometry; per-sample values (graininess) with the file's 45°
block (``station.model.domain.ILLUMINATION_DEG``), or its first block when it has none at 45°, so a block's
reading is the same whichever blocks one import stores (``--illumination 15`` leaves them out).
"""

from __future__ import annotations

import datetime as dt
import functools
import hashlib
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from station.ingest.errors import ImportFileError
from station.ingest.formats.measurement import (
    ErrorFactory,
    ImportedFile,
    ImportedMeasurement,
    canonical_geometry,
    lab_of,
)
from station.ingest.records import LAB_DECIMALS, SPECTRA_DECIMALS
from station.ingest.schema import InstrumentRef, PanelRef, Reading, TextureValue
from station.model.domain import ILLUMINATION_DEG, parse_geometry

__all__ = ["ImportOptions", "file_sha256", "import_client_id", "readings_from_file", "readings_from_import"]

_IMPORT_NAMESPACE = uuid.UUID("6f1d2f0e-4b7a-4c55-9d8e-3a7b1c2d4e5f")
#: Notes of the panel of an imported sample: this prefix and the sample name.
NOTE_PREFIX = "sample: "


@dataclass(frozen=True)
class ImportOptions:
    """What an import files its readings under, the same for every file of one import or watch folder.

    Attributes
    ----------
    operator
        Who imports (the readings' operator).
    job, part
        The panel each reading names (both or neither): job, part and ``notes = "sample: NAME"``.
    illumination_deg
        The one illumination block stored (degrees); ``None``: every block of each measurement.
    """

    operator: str
    job: str | None = None
    part: str | None = None
    illumination_deg: float | None = None


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


def _texture(
    m: ImportedMeasurement, illumination_deg: float, per_sample: bool, err: ErrorFactory
) -> list[TextureValue] | None:
    """The texture values of *m* that go with its *illumination_deg* block (and the per-sample ones).

    A value's geometry is read in the domain's spelling; a malformed one is *err* naming ``texture.geometry``.
    """
    out = []
    for t in m.texture:
        geometry = "" if t.geometry == "" else canonical_geometry(t.geometry, "texture.geometry", err)
        if (geometry == "" and per_sample) or (geometry and parse_geometry(geometry)[0] == illumination_deg):
            out.append(TextureValue(vendor=t.vendor, name=t.name, geometry=geometry, value=t.value))
    return out or None


def readings_from_import(
    imported: ImportedFile,
    options: ImportOptions,
    *,
    sha256: str,
    fallback_time: dt.datetime,
    error: type[ImportFileError] = ImportFileError,
) -> list[Reading]:
    """One validated :class:`Reading` per measurement of *imported* and illumination block.

    *options*: :class:`ImportOptions`; its *illumination_deg* ``None``: every block of each measurement
    (in the file's order); a number: that block only. *fallback_time* (UTC) is the instant of a
    measurement whose file states none. With a job and a part each reading names its panel: job, part and
    ``notes = "sample: NAME"`` (found or created by the ingest store), the same panel for every block of a
    sample. Raises *error* naming the measurement when it has no geometry lit from the block asked for or
    a value the ingest record refuses.
    """
    job, part, illumination_deg = options.job, options.part, options.illumination_deg
    if (job is None) != (part is None):
        raise error(imported.file, "", "job" if job is None else "part", "--job and --part together")
    out = []
    for n, m in enumerate(imported.measurements):
        where = f"measurement {n + 1} ({m.sample})"
        blocks = m.illuminations if illumination_deg is None else (illumination_deg,)
        if not _block(m, blocks[0]):
            lit = sorted(m.illuminations)
            raise error(imported.file, where, "illumination_deg", f"one of {lit}", illumination_deg)
        # per-sample texture goes with one block of the file, whichever blocks are stored
        sample_block = ILLUMINATION_DEG if ILLUMINATION_DEG in m.illuminations else m.illuminations[0]
        lab = lab_of(m, functools.partial(error, imported.file, where))
        for block in blocks:
            reading = _reading(
                imported,
                m,
                n,
                block,
                lab,
                options,
                sha256=sha256,
                fallback_time=fallback_time,
                error=error,
                per_sample=block == sample_block,
            )
            out.append(reading)
    return out


def readings_from_file(
    imported: ImportedFile,
    path: Path | str,
    options: ImportOptions,
    *,
    data: bytes | None = None,
) -> list[Reading]:
    """:func:`readings_from_import` of *imported*, read from the file at *path*: under the SHA-256 of
    *data*, the bytes *imported* was parsed from (``None``: the file's bytes now, which differ when the
    file was saved again since it was parsed: pass *data*), with the file's modification time (UTC,
    whole seconds) for a measurement whose file states none.

    Raises ``OSError`` when *path* cannot be read, :class:`ImportFileError` as :func:`readings_from_import`.
    """
    mtime = dt.datetime.fromtimestamp(Path(path).stat().st_mtime, dt.UTC).replace(microsecond=0)
    sha256 = file_sha256(path) if data is None else hashlib.sha256(data).hexdigest()
    return readings_from_import(imported, options, sha256=sha256, fallback_time=mtime)


def _reading(
    imported: ImportedFile,
    m: ImportedMeasurement,
    n: int,
    illumination_deg: float,
    lab: np.ndarray,
    options: ImportOptions,
    *,
    sha256: str,
    fallback_time: dt.datetime,
    error: type[ImportFileError],
    per_sample: bool,
) -> Reading:
    """The reading of the *illumination_deg* block of measurement *n* (0-based) of *imported*, filed as
    *options* say."""
    job, part = options.job, options.part
    where = f"measurement {n + 1} ({m.sample})"
    idx = _block(m, illumination_deg)
    serial = m.instrument.serial or "unknown"
    model = m.instrument.model or m.instrument.manufacturer or "unknown"
    try:
        panel = None
        if job is not None and part is not None:
            panel = PanelRef(job=job, part=part, notes=f"{NOTE_PREFIX}{m.sample}"[:4000])
        reading = Reading(
            client_id=import_client_id(sha256, n, illumination_deg),
            illumination_deg=illumination_deg,
            instrument=InstrumentRef(serial=serial[:64], model=model[:64], kind="multiangle"),
            calibration=None,
            panel=panel,
            operator=options.operator,
            measured_at=m.measured_at or fallback_time,
            illuminant=m.illuminant,  # type: ignore[arg-type]  # validated against the Literal
            observer=m.observer,  # type: ignore[arg-type]
            geometries_deg=[parse_geometry(m.geometries[i])[1] for i in idx],
            lab=lab[idx].round(LAB_DECIMALS).tolist(),
            wavelengths_nm=None if m.wavelengths_nm is None else list(m.wavelengths_nm),
            spectra=None
            if m.spectra is None
            else [[round(v, SPECTRA_DECIMALS) for v in m.spectra[i]] for i in idx],
            texture=_texture(m, illumination_deg, per_sample, functools.partial(error, imported.file, where)),
        )
    except ValidationError as exc:
        first = exc.errors()[0]
        fld = ".".join(str(p) for p in first["loc"]) or "reading"
        raise error(imported.file, where, fld, first["msg"], first.get("input")) from exc
    return reading
