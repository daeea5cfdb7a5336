"""What every importer returns: one :class:`ImportedMeasurement` per sample, validated on the way in.

A measurement holds one row per geometry (named ``"<illumination>as<aspecular>"``, e.g. ``45as15``,
parsed by :func:`station.model.domain.parse_geometry`), CIE L*a*b* per geometry under the stated
illuminant and observer (checked against the domain bound, :func:`station.model.domain.check_lab`)
and/or reflectance factors (unitless) at ``wavelengths_nm`` (nm). Vendor texture values (sparkle,
graininess) are :class:`VendorValue`: tagged with the vendor whose non-disclosed procedure made them,
and refused when compared with another vendor's (PTB: sparkle and graininess are device-dependent).

:func:`build_measurement` is the one validation every importer calls with the file and the place in
it, so each malformed value is refused by the format's own error class naming file, place and field.
"""

from __future__ import annotations

import datetime as dt
import itertools
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Final, get_args

import numpy as np

from station.errors import InputError
from station.ingest.errors import ImportFileError
from station.ingest.schema import MAX_GEOMETRIES, MAX_WAVELENGTHS, Illuminant, Observer
from station.model.domain import check_lab, geometry_name, parse_geometry
from station.model.errors import ModelInputError
from station.wire import iso_time, wire_form

__all__ = [
    "ILLUMINANTS",
    "OBSERVERS",
    "ImportedFile",
    "ImportedMeasurement",
    "Instrument",
    "VendorValue",
    "build_measurement",
    "observer_name",
    "single_angle_geometry",
]

#: Illuminants a stored reading may state (the ingest record's vocabulary).
ILLUMINANTS: Final[tuple[str, ...]] = get_args(Illuminant)
#: Observers a stored reading may state, full CIE names (the ingest record's vocabulary).
OBSERVERS: Final[tuple[str, ...]] = get_args(Observer)
_OBSERVER_SHORT: Final[Mapping[str, str]] = MappingProxyType({"2": OBSERVERS[0], "10": OBSERVERS[1]})

ErrorFactory = Callable[[str, str, object], ImportFileError]
"""``(field, accepted, got) -> error`` bound to one file and one place in it."""


def observer_name(text: str) -> str | None:
    """Full CIE observer name of ``"10"``, ``"10_Degree"``, ``"10°"`` or a full name; ``None`` if unknown."""
    t = text.strip()
    if t in OBSERVERS:
        return t
    short = t.removesuffix("_Degree").removesuffix("°").removesuffix("deg").strip()
    return _OBSERVER_SHORT.get(short)


def observer_degrees(name: str) -> str:
    """``"10"`` or ``"2"`` for a full observer name (what CGATS, CSV and CxF write)."""
    return next(k for k, v in _OBSERVER_SHORT.items() if v == name)


@dataclass(frozen=True)
class Instrument:
    """The instrument named by a file: model, serial number and manufacturer (any may be empty)."""

    model: str = ""
    serial: str = ""
    manufacturer: str = ""

    def to_dict(self) -> dict[str, str]:
        """JSON form."""
        return wire_form(self)


@dataclass(frozen=True)
class VendorValue:
    """A device-dependent texture value (sparkle, graininess) tagged with the vendor that computed it.

    ``geometry`` is the geometry name it belongs to, or ``""`` for a per-sample value (graininess is
    measured under diffuse light). Values of two vendors never compare: :meth:`difference` refuses.
    """

    vendor: str
    name: str
    value: float
    geometry: str = ""

    def __post_init__(self) -> None:
        if not self.vendor.strip():
            raise InputError(f"texture.{self.name}", "a vendor name (texture values are vendor-specific)")
        if not math.isfinite(self.value):
            raise InputError(f"texture.{self.name}", "a finite number", self.value)

    def difference(self, other: VendorValue) -> float:
        """``self.value - other.value`` for the same vendor, quantity and geometry; else :class:`InputError`."""
        if other.vendor != self.vendor:
            raise InputError(
                f"texture.{self.name}",
                f"a value from the same vendor ({self.vendor}); texture values are device-dependent",
                other.vendor,
            )
        if (other.name, other.geometry) != (self.name, self.geometry):
            raise InputError("texture", f"{self.name} at {self.geometry or 'the sample'}", other.name)
        return self.value - other.value

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"vendor": self.vendor, "name": self.name, "geometry": self.geometry, "value": self.value}


@dataclass(frozen=True)
class ImportedMeasurement:
    """One sample read from a file: geometries, Lab and/or spectra, instrument, conditions, texture.

    Build it through :func:`build_measurement` (which validates); ``lab`` is ``None`` only when the
    file gave spectra alone, ``spectra`` ``None`` when it gave Lab alone.
    """

    sample: str
    geometries: tuple[str, ...]
    lab: tuple[tuple[float, float, float], ...] | None
    wavelengths_nm: tuple[float, ...] | None
    spectra: tuple[tuple[float, ...], ...] | None
    instrument: Instrument
    illuminant: str
    observer: str
    measured_at: dt.datetime | None
    texture: tuple[VendorValue, ...] = field(default=())

    @property
    def illuminations(self) -> tuple[float, ...]:
        """Illumination angles present, degrees, in first-seen order."""
        seen: list[float] = []
        for g in self.geometries:
            ill = parse_geometry(g)[0]
            if ill not in seen:
                seen.append(ill)
        return tuple(seen)

    def to_dict(self) -> dict[str, Any]:
        """The ``station import --json`` form of one measurement."""
        return wire_form(self, convert={"measured_at": iso_time})


@dataclass(frozen=True)
class ImportedFile:
    """A whole imported file: its format, its name and its measurements (at least one)."""

    format: str
    file: str
    measurements: tuple[ImportedMeasurement, ...]

    def to_dict(self) -> dict[str, Any]:
        """The ``station import --json`` document."""
        return wire_form(self)


def _finite(value: float, fld: str, err: ErrorFactory) -> float:
    if not math.isfinite(value):
        raise err(fld, "a finite number", value)
    return value


def canonical_geometry(name: str, fld: str, err: ErrorFactory) -> str:
    """*name* (``45as15``, ``45AS15``, `` 15as-15 ``) in the domain's spelling, or the format's error."""
    try:
        ill, asp = parse_geometry(name.strip().lower(), fld)
    except ModelInputError as exc:
        raise err(fld, exc.accepted, name) from exc
    return geometry_name(ill, asp)


_SINGLE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*[/:]\s*(\d+(?:\.\d+)?)\s*$")


def single_angle_geometry(text: str, fld: str, err: ErrorFactory) -> str:
    """The geometry name of a single-angle geometry written ``"45/0"`` (CIE illumination/viewing
    angles from the normal, ``:`` also accepted) or already ``"45as45"``.

    Viewing is on the far side of the normal from the illumination, so the aspecular angle is
    ``illumination − viewing`` (45/0 → ``45as45``, the 45/0 geometry lit from one direction).
    Refused (*err*): anything else, and 0/45 (illumination along the normal has no aspecular side).
    """
    m = _SINGLE.match(text)
    if m is None:
        return canonical_geometry(text, fld, err)
    ill, view = float(m.group(1)), float(m.group(2))
    if ill == 0.0:
        raise err(fld, 'a directional geometry such as "45/0" or "45as45"', text)
    return canonical_geometry(geometry_name(ill, ill - view), fld, err)


def _checked_lab(
    rows: Sequence[tuple[str, ErrorFactory]], lab: Sequence[Sequence[float]], err: ErrorFactory
) -> tuple[tuple[float, float, float], ...]:
    """One finite L*a*b* within the domain bound per geometry row (each refusal names its row)."""
    if len(lab) != len(rows):
        raise err("lab", f"one L*a*b* per geometry ({len(rows)})", len(lab))
    checked = []
    for (_, row_err), triple in zip(rows, lab, strict=True):
        vals = [_finite(float(v), f"lab.{c}", row_err) for c, v in zip("Lab", triple, strict=False)]
        try:
            checked.append(check_lab(vals, "lab"))
        except ModelInputError as exc:
            raise row_err(exc.field, exc.accepted, exc.got) from exc
    return tuple(checked)


def _checked_spectra(
    rows: Sequence[tuple[str, ErrorFactory]],
    wavelengths_nm: Sequence[float] | None,
    spectra: Sequence[Sequence[float]] | None,
    err: ErrorFactory,
) -> tuple[tuple[float, ...] | None, tuple[tuple[float, ...], ...] | None]:
    """The wavelength grid (nm, strictly increasing) and one reflectance curve (≥ 0) per geometry row."""
    if (spectra is None) != (wavelengths_nm is None):
        raise err("spectra", "spectra together with their wavelengths", None)
    if spectra is None or wavelengths_nm is None:
        return None, None
    wl = [_finite(float(w), "wavelengths_nm", err) for w in wavelengths_nm]
    if not 2 <= len(wl) <= MAX_WAVELENGTHS:
        raise err("wavelengths_nm", f"2 to {MAX_WAVELENGTHS} wavelengths", len(wl))
    if any(b <= a for a, b in itertools.pairwise(wl)):
        raise err("wavelengths_nm", "strictly increasing wavelengths (nm)", wl)
    if len(spectra) != len(rows):
        raise err("spectra", f"one spectrum per geometry ({len(rows)})", len(spectra))
    curves = []
    for (_, row_err), curve in zip(rows, spectra, strict=True):
        if len(curve) != len(wl):
            raise row_err("spectra", f"{len(wl)} values (one per wavelength)", len(curve))
        vals = [_finite(float(v), "spectra", row_err) for v in curve]
        if min(vals) < 0.0:
            raise row_err("spectra", "reflectance factors >= 0", min(vals))
        curves.append(tuple(vals))
    return tuple(wl), tuple(curves)


def build_measurement(
    *,
    sample: str,
    rows: Sequence[tuple[str, Callable[[str, str, object], ImportFileError]]],
    lab: Sequence[Sequence[float]] | None,
    wavelengths_nm: Sequence[float] | None,
    spectra: Sequence[Sequence[float]] | None,
    instrument: Instrument,
    illuminant: str,
    observer: str,
    measured_at: dt.datetime | None,
    texture: Sequence[VendorValue] = (),
    err: ErrorFactory,
) -> ImportedMeasurement:
    """Validate one sample and return it; every refusal is *err* (or a row's own factory) naming the field.

    *rows* pairs each geometry name with the error factory of the place it came from (its line or
    element). Refused: no geometry, more than ``MAX_GEOMETRIES``, a malformed or repeated geometry,
    neither Lab nor spectra, a non-finite number, Lab outside the domain bound, a wavelength grid
    that is not strictly increasing, a negative reflectance, an unknown illuminant or observer.
    """
    if not sample.strip():
        raise err("sample", "a non-empty sample name", sample)
    if not rows:
        raise err("geometry", "at least one geometry per sample", 0)
    if len(rows) > MAX_GEOMETRIES:
        raise err("geometry", f"at most {MAX_GEOMETRIES} geometries per sample", len(rows))
    names: list[str] = []
    for name, row_err in rows:
        g = canonical_geometry(name, "geometry", row_err)
        if g in names:
            raise row_err("geometry", "each geometry once per sample", name)
        names.append(g)
    if lab is None and spectra is None:
        raise err("lab", "Lab values and/or spectra per geometry", None)
    if illuminant not in ILLUMINANTS:
        raise err("illuminant", " | ".join(ILLUMINANTS), illuminant)
    if observer not in OBSERVERS:
        raise err("observer", "2 | 10 (degrees)", observer)
    lab_out = None if lab is None else _checked_lab(rows, lab, err)
    wl_out, sp_out = _checked_spectra(rows, wavelengths_nm, spectra, err)
    return ImportedMeasurement(
        sample=sample.strip(),
        geometries=tuple(names),
        lab=lab_out,
        wavelengths_nm=wl_out,
        spectra=sp_out,
        instrument=instrument,
        illuminant=illuminant,
        observer=observer,
        measured_at=measured_at,
        texture=tuple(texture),
    )


def lab_of(m: ImportedMeasurement, err: ErrorFactory) -> np.ndarray:
    """Lab per geometry of *m*: the file's, else ``reflectance_to_lab`` of its spectra (product grid).

    Spectra without Lab must cover the product grid (``station.model.spectra.WAVELENGTHS``,
    400–700 nm at 10 nm); other bands are ignored for the Lab.
    """
    if m.lab is not None:
        return np.asarray(m.lab, dtype=float)
    from station.model.spectra import WAVELENGTHS, reflectance_to_lab

    if m.spectra is None or m.wavelengths_nm is None:
        raise err("lab", "Lab values and/or spectra per geometry", None)
    wl = list(m.wavelengths_nm)
    try:
        cols = [wl.index(float(w)) for w in WAVELENGTHS]
    except ValueError as exc:
        raise err(
            "wavelengths_nm",
            f"with spectra only: every band of {WAVELENGTHS[0]:g}–{WAVELENGTHS[-1]:g} nm at "
            f"{WAVELENGTHS[1] - WAVELENGTHS[0]:g} nm",
            f"{wl[0]:g}–{wl[-1]:g} nm ({len(wl)} bands)",
        ) from exc
    rows = np.asarray(m.spectra, dtype=float)[:, cols]
    try:
        return np.asarray(reflectance_to_lab(rows, m.illuminant, m.observer), dtype=float)
    except ModelInputError as exc:
        raise err(exc.field, exc.accepted, exc.got) from exc


def from_spectral_reading(reading: Any, sample: str, manufacturer: str = "") -> ImportedMeasurement:
    """The :class:`ImportedMeasurement` of an instrument reading (``station.drivers.SpectralReading``).

    Every geometry of the reading (all illumination blocks), its reflectance factors on its
    wavelength grid, and Lab from ``station.model.spectra.reflectance_to_lab`` (D65, CIE 1964 10°),
    rounded like the ingest record (Lab 4 decimals, spectra 6): what a simulator exports.
    """
    from station.ingest.records import LAB_DECIMALS, SPECTRA_DECIMALS
    from station.model.spectra import reflectance_to_lab

    rows = np.asarray(reading.reflectance, dtype=float).round(SPECTRA_DECIMALS)
    lab = np.asarray(reflectance_to_lab(rows), dtype=float).round(LAB_DECIMALS)

    def err(fld: str, accepted: str, got: object) -> ImportFileError:
        return ImportFileError("reading", sample, fld, accepted, got)

    return build_measurement(
        sample=sample,
        rows=[(g, err) for g in reading.geometries],
        lab=lab.tolist(),
        wavelengths_nm=[float(w) for w in reading.wavelengths_nm],
        spectra=rows.tolist(),
        instrument=Instrument(model=reading.model, serial=reading.serial, manufacturer=manufacturer),
        illuminant="D65",
        observer=OBSERVERS[1],
        measured_at=reading.time,
        err=err,
    )
