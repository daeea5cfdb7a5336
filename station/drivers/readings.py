"""Typed results of the instrument layer: identity, calibration, spectral and gloss readings.

Reflectance is a factor in [0, ~1.5] (not %), on ``WAVELENGTHS_NM`` = 400, 410, …, 700 nm (31 bands),
one row per geometry. Geometries are named as instruments export them: ``"45as15"`` = illumination at
45° from the normal, aspecular angle 15° (viewing angle measured from the specular direction, positive
towards the normal; thesis §3.3). Lab is *not* computed here: use
``station.model.spectra.reflectance_to_lab(reading.reflectance)``.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field

import numpy as np

from station.drivers.errors import DriverInputError
from station.model import domain
from station.model.errors import ModelInputError

__all__ = [
    "WAVELENGTHS_NM",
    "CalibrationResult",
    "CalibrationStatus",
    "CalibrationStepResult",
    "GlossReading",
    "InstrumentInfo",
    "SpectralReading",
    "geometry_name",
    "parse_geometry",
]

WAVELENGTHS_NM: tuple[int, ...] = tuple(range(400, 701, 10))


def geometry_name(illumination_deg: int, aspecular_deg: int) -> str:
    """Return the export name of a geometry, e.g. ``geometry_name(45, -15) == "45as-15"``.

    Instruments report whole degrees; the naming is :func:`station.model.domain.geometry_name`.
    """
    return domain.geometry_name(int(illumination_deg), int(aspecular_deg))


def parse_geometry(name: str) -> tuple[int, int]:
    """Return ``(illumination_deg, aspecular_deg)`` of a name like ``"45as110"`` (whole degrees)."""
    try:
        ill, asp = domain.parse_geometry(name)
    except ModelInputError as exc:
        raise DriverInputError(exc.field, exc.accepted, exc.got) from exc
    if not (ill.is_integer() and asp.is_integer()):
        raise DriverInputError("geometry", 'whole degrees, like "45as15"', name)
    return int(ill), int(asp)


@dataclass(frozen=True)
class InstrumentInfo:
    """Identity of an instrument: model, serial number, firmware version, geometries it measures."""

    model: str
    serial: str
    firmware: str
    geometries: tuple[str, ...] = ()


@dataclass(frozen=True)
class CalibrationStatus:
    """What the instrument needs: ``needed`` is ``None`` when it can measure, else the next step."""

    needed: str | None
    calibration_id: str
    expires: dt.datetime | None
    temperature_c: float | None = None


@dataclass(frozen=True)
class CalibrationResult:
    """Outcome of a full calibration: steps done, verification-tile ΔE00 and pass/fail, expiry."""

    calibration_id: str
    steps: tuple[str, ...]
    verification_de: float | None
    passed: bool
    expires: dt.datetime | None


@dataclass(frozen=True)
class CalibrationStepResult:
    """Outcome of one calibration step (``zero``, ``white``, ``verify`` or ``gloss``).

    ``calibration_id`` is set by the step that starts a new calibration (white tile, gloss standard);
    ``verification_de`` (CIEDE2000 against the tile's certificate) and ``expires`` by the step that
    ends it (verification tile, gloss standard).
    """

    step: str
    calibration_id: str = ""
    verification_de: float | None = None
    passed: bool = True
    expires: dt.datetime | None = None


@dataclass(frozen=True)
class SpectralReading:
    """One measurement of a multi-angle spectrophotometer.

    ``reflectance`` has shape ``(len(geometries), 31)``; ``warnings`` and ``diagnosis`` are the
    instrument's bitmasks (CM-MISDK meanings, docs/protocols/); ``time`` is the instrument's UTC clock.
    """

    geometries: tuple[str, ...]
    reflectance: np.ndarray
    temperature_c: float
    serial: str
    calibration_id: str
    time: dt.datetime
    warnings: int = 0
    diagnosis: int = 0
    wavelengths_nm: tuple[int, ...] = WAVELENGTHS_NM
    model: str = ""

    @property
    def aspecular_deg(self) -> tuple[int, ...]:
        """Aspecular angle of each geometry (°)."""
        return tuple(parse_geometry(g)[1] for g in self.geometries)

    def block(self, illumination_deg: int) -> tuple[tuple[int, ...], np.ndarray]:
        """Return ``(aspecular angles, reflectance rows)`` for one illumination direction."""
        rows = [i for i, g in enumerate(self.geometries) if parse_geometry(g)[0] == illumination_deg]
        return tuple(self.aspecular_deg[i] for i in rows), self.reflectance[rows]

    def to_dict(self) -> dict[str, object]:
        """Return a JSON-able dict (no Lab: that is the model's job)."""
        return {
            "model": self.model,
            "geometries": list(self.geometries),
            "wavelengths_nm": list(self.wavelengths_nm),
            "spectra": self.reflectance.tolist(),
            "temperature_c": self.temperature_c,
            "serial": self.serial,
            "calibration_id": self.calibration_id,
            "time": self.time.isoformat(),
            "warnings": self.warnings,
            "diagnosis": self.diagnosis,
        }


@dataclass(frozen=True)
class GlossReading:
    """One reading of a 20/60/85° gloss meter with haze, DOI and Rspec.

    ``gloss_gu`` maps geometry (°) to gloss units (GU, ISO 2813: polished black glass n = 1.567 is
    100 GU); ``haze_hu`` is haze units (ASTM E430 method B, 20° ± 1.9°), ``log_haze`` its log form;
    ``doi`` is distinctness of image (0–100) and ``rspec`` the narrow-aperture 20° peak (GU).
    """

    gloss_gu: dict[int, float]
    haze_hu: float
    log_haze: float
    doi: float
    rspec: float
    serial: str
    calibration_id: str
    time: dt.datetime
    temperature_c: float
    warnings: int = 0
    model: str = ""
    extra: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        """Return a JSON-able dict."""
        return {
            "model": self.model,
            "gloss_gu": {str(k): v for k, v in sorted(self.gloss_gu.items())},
            "haze_hu": self.haze_hu,
            "log_haze": self.log_haze,
            "doi": self.doi,
            "rspec": self.rspec,
            "serial": self.serial,
            "calibration_id": self.calibration_id,
            "time": self.time.isoformat(),
            "temperature_c": self.temperature_c,
            "warnings": self.warnings,
        }
