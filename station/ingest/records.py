"""Instrument reading → ingest record: the one conversion every front uses (service, viewer, CLI).

A :class:`station.drivers.readings.SpectralReading` (taken structurally, as :class:`SpectralLike`:
ingest and drivers are peers and do not import each other) becomes a validated :class:`Reading`: the aspecular
angles (degrees) of one illumination block, CIE L*a*b* per geometry computed from the spectra by
``station.model.spectra.reflectance_to_lab`` (D65, CIE 1964 10°; never the instrument's own Lab), the
reflectance factors (unitless) at the instrument's wavelengths (nm), the instrument by serial, the
calibration in force keyed by :func:`calibration_client_id`, and 60° gloss (GU, ISO 2813) when a gloss
meter reading joins it.
"""

from __future__ import annotations

import datetime as dt
import getpass
import os
import uuid
from collections.abc import Mapping, Sequence
from typing import Final, Literal, Protocol, Required, TypedDict

import numpy as np

from station.errors import InputError
from station.ingest.schema import CalibrationRef, InstrumentRef, PanelRef, Reading

__all__ = [
    "GlossLike",
    "InstrumentLike",
    "ReadingTarget",
    "SpectralLike",
    "calibration_client_id",
    "operator_name",
    "record_from_reading",
]

_CAL_NAMESPACE = uuid.UUID("0b9e8c1e-5d0c-4c7b-8f5e-2b7c3f1d9a11")
GLOSS_GEOMETRY_DEG: Final = 60
LAB_DECIMALS = 4
SPECTRA_DECIMALS = 6


class SpectralLike(Protocol):
    """What the conversion reads of a spectral reading (``station.drivers.readings.SpectralReading``)."""

    @property
    def geometries(self) -> tuple[str, ...]: ...
    @property
    def serial(self) -> str: ...
    @property
    def calibration_id(self) -> str: ...
    @property
    def time(self) -> dt.datetime: ...
    @property
    def wavelengths_nm(self) -> Sequence[int]: ...
    @property
    def model(self) -> str: ...
    def block(self, illumination_deg: int) -> tuple[tuple[int, ...], np.ndarray]:
        """``(aspecular angles in degrees, reflectance rows)`` of one illumination direction."""
        ...


class GlossLike(Protocol):
    """What the conversion reads of a gloss reading: gloss units (GU) by geometry in degrees."""

    @property
    def gloss_gu(self) -> Mapping[int, float]: ...


class InstrumentLike(Protocol):
    """What the conversion reads of an instrument's identity (``identify()``)."""

    @property
    def model(self) -> str: ...
    @property
    def serial(self) -> str: ...
    @property
    def firmware(self) -> str: ...


class ReadingTarget(TypedDict, total=False):
    """The keywords of :func:`record_from_reading` besides the reading and its gloss, for a front that
    passes them on (``station.scan.make_records``): who measured, which illumination block (degrees),
    the idempotency key, the instrument's identity and the panel (by id, or by job and part)."""

    operator: Required[str]
    illumination_deg: int
    client_id: uuid.UUID | None
    instrument: InstrumentLike | None
    panel_id: int | None
    panel: PanelRef | None


def calibration_client_id(serial: str, calibration_id: str) -> uuid.UUID:
    """The stable client id of an instrument's calibration: the same device calibration id, the same record."""
    return uuid.uuid5(_CAL_NAMESPACE, f"{serial}/{calibration_id}")


def operator_name(fallback: str = "station") -> str:
    """The operator recorded with a reading: ``$CACAD_OPERATOR``, the login name, or *fallback*."""
    name = os.environ.get("CACAD_OPERATOR", "")
    if not name:
        try:
            name = getpass.getuser()
        except (OSError, KeyError):  # no login name in some containers
            name = ""
    name = "".join(c for c in name if c.isprintable()).strip()[:64]
    return name or fallback


def _gloss_60(gloss: GlossLike | None) -> tuple[float | None, Literal[60] | None]:
    if gloss is None:
        return None, None
    if GLOSS_GEOMETRY_DEG not in gloss.gloss_gu:
        raise InputError("gloss", "a gloss reading with a 60° geometry", sorted(gloss.gloss_gu))
    return float(gloss.gloss_gu[GLOSS_GEOMETRY_DEG]), GLOSS_GEOMETRY_DEG


def record_from_reading(
    reading: SpectralLike,
    *,
    operator: str,
    illumination_deg: int = 45,
    client_id: uuid.UUID | None = None,
    instrument: InstrumentLike | None = None,
    panel_id: int | None = None,
    panel: PanelRef | None = None,
    gloss: GlossLike | None = None,
) -> Reading:
    """The ingest record of the *illumination_deg* block of *reading* (validated by :class:`Reading`).

    Lab is ``reflectance_to_lab`` of each reflectance row (D65/10°, rounded to 4 decimals; spectra to
    6). *client_id* defaults to a fresh UUID: pass the caller's id to make a retry idempotent.
    *instrument* (from ``identify()``) supplies model and firmware when the reading lacks them. Raises
    :class:`InputError` naming ``illumination_deg`` when the reading has no geometry lit from that
    angle, or ``gloss`` when *gloss* has no 60° value; :class:`pydantic.ValidationError` (a
    ``ValueError``) when the values are outside the record's ranges.
    """
    # the model (colour-science behind it) loads here, not with the ingest package: ≈1.8 s off a
    # process that only replays or stores readings
    from station.model.spectra import reflectance_to_lab

    angles, refl = reading.block(illumination_deg)
    if not angles:
        lit = sorted({int(g.split("as")[0]) for g in reading.geometries})
        raise InputError("illumination_deg", f"one of {lit}", illumination_deg)
    rows = np.asarray(refl, dtype=float)
    lab = np.asarray(reflectance_to_lab(rows), dtype=float)
    gloss_gu, gloss_geometry = _gloss_60(gloss)
    serial = reading.serial or (instrument.serial if instrument is not None else "") or "unknown"
    model = (instrument.model if instrument is not None else "") or reading.model or "unknown"
    firmware = (instrument.firmware if instrument is not None else "") or None
    calibration = None
    if reading.calibration_id:
        calibration = CalibrationRef(
            client_id=calibration_client_id(serial, reading.calibration_id), performed_at=reading.time
        )
    return Reading(
        client_id=client_id or uuid.uuid4(),
        instrument=InstrumentRef(serial=serial, model=model, kind="multiangle", firmware=firmware),
        calibration=calibration,
        panel_id=panel_id,
        panel=panel,
        operator=operator,
        measured_at=reading.time,
        illumination_deg=float(illumination_deg),
        geometries_deg=[float(a) for a in angles],
        lab=lab.round(LAB_DECIMALS).tolist(),
        wavelengths_nm=[float(w) for w in reading.wavelengths_nm],
        spectra=rows.round(SPECTRA_DECIMALS).tolist(),
        gloss_gu=gloss_gu,
        gloss_geometry_deg=gloss_geometry,
    )
