"""A QC reading: Lab (and optionally spectra) per geometry of one sample, with its provenance.

Every QC function takes :class:`Reading` values, whatever their source:

* a ``station measure --json`` output (``geometries`` like ``"45as15"``, ``lab``, ``spectra``,
  ``wavelengths_nm``, ``serial``/``model``, ``panel``, ``time``);
* a ``station import --json`` output (``{"measurements": [{"geometries", "lab", "spectra",
  "instrument", "sample"}, …]}``), one reading per entry;
* a stored :class:`db.models.Measurement` (:func:`reading_from_measurement`).

* any file ``station import`` reads (CxF3, CGATS.17, the CSV template), through the importers of
  ``station.ingest.formats`` when they are installed (:func:`load_readings`).

Geometries are aspecular angles under the standard 45° illumination (``45as15`` is 15° from the
specular direction), since tolerance sets and DIN 6175-2 weights are defined on aspecular angles at
45°. A source whose geometries include other illuminations (an MA-T12's second block, ``15as…``)
keeps its 45° geometries only; one with none at 45° is refused. Lab is D65 / CIE 1964 10°: when a
source has spectra on the product's 400–700 nm, 10 nm grid, Lab is computed from them wherever Lab is
absent or stated under another illuminant or observer
(:func:`station.model.spectra.reflectance_to_lab`); Lab under other conditions without such spectra is
refused, since it cannot be compared with a D65 standard.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from station.model.domain import ILLUMINATION_DEG, aspecular_name, check_lab, parse_geometry
from station.model.errors import ModelInputError
from station.model.spectra import WAVELENGTHS, reflectance_to_lab
from station.qc.errors import QcInputError
from station.qc.texture import TextureValue, texture_values

if TYPE_CHECKING:
    from db.models import Measurement

__all__ = ["Reading", "load_readings", "reading_from_dict", "reading_from_measurement", "readings_from_json"]


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


@dataclass(frozen=True)
class Reading:
    """Lab per geometry of one sample (immutable, validated).

    Parameters
    ----------
    aspecular_deg
        Aspecular angles of the rows, degrees, distinct (45° illumination).
    lab
        One (L*, a*, b*) per angle, inside the domain's Lab bound.
    spectra
        Optional reflectance (0–1) per angle, one value per wavelength of *wavelengths_nm*.
    wavelengths_nm
        Wavelengths of *spectra*, nm (required with *spectra*).
    instrument, sample
        Free text: the instrument (model and serial) and the sample (panel) name.
    measured_at
        When it was measured (timezone-aware), if known.
    measurement_id
        The stored measurement's id, if it came from the database.
    where
        Name of the source used in error messages (a file name, ``"standard"``).
    texture
        Vendor texture values (sparkle, graininess; :mod:`station.qc.texture`), if any.
    """

    aspecular_deg: tuple[float, ...]
    lab: tuple[tuple[float, float, float], ...]
    spectra: tuple[tuple[float, ...], ...] | None = None
    wavelengths_nm: tuple[float, ...] | None = None
    instrument: str = ""
    sample: str = ""
    measured_at: dt.datetime | None = None
    measurement_id: int | None = None
    where: str = "reading"
    texture: tuple[TextureValue, ...] = ()

    def __post_init__(self) -> None:
        w = self.where
        angles = tuple(self.aspecular_deg)
        if not angles or not all(_finite(a) for a in angles):
            raise QcInputError(f"{w}.geometries", "at least one aspecular angle (finite degrees)", angles)
        if len(set(angles)) != len(angles):
            raise QcInputError(f"{w}.geometries", "distinct geometries", [aspecular_name(a) for a in angles])
        object.__setattr__(self, "aspecular_deg", tuple(float(a) for a in angles))
        rows = tuple(self.lab)
        if len(rows) != len(angles):
            raise QcInputError(f"{w}.lab", f"{len(angles)} L*, a*, b* triples (one per geometry)", len(rows))
        try:
            labs = tuple(tuple(float(v) for v in check_lab(r, f"{w}.lab[{i}]")) for i, r in enumerate(rows))
        except ModelInputError as exc:
            raise QcInputError(exc.field, exc.accepted, exc.got) from exc
        object.__setattr__(self, "lab", labs)
        if (self.spectra is None) != (self.wavelengths_nm is None):
            raise QcInputError(f"{w}.wavelengths_nm", "spectra and wavelengths_nm together", "only one")
        if self.spectra is not None and self.wavelengths_nm is not None:
            wl = tuple(float(x) for x in self.wavelengths_nm)
            sp = np.asarray(self.spectra, dtype=float)
            if sp.shape != (len(angles), len(wl)) or not np.all(np.isfinite(sp)):
                raise QcInputError(
                    f"{w}.spectra", f"{len(angles)} finite spectra of {len(wl)} values", list(sp.shape)
                )
            object.__setattr__(self, "wavelengths_nm", wl)
            object.__setattr__(self, "spectra", tuple(tuple(float(v) for v in row) for row in sp))
        if self.measured_at is not None and self.measured_at.tzinfo is None:
            raise QcInputError(f"{w}.measured_at", "a timezone-aware time", self.measured_at.isoformat())

    @property
    def geometries(self) -> tuple[str, ...]:
        """Geometry names, e.g. ``("45as15", "45as45", "45as110")``."""
        return tuple(aspecular_name(a) for a in self.aspecular_deg)

    def lab_array(self) -> NDArray[np.float64]:
        """Lab as an (n, 3) array."""
        return np.asarray(self.lab, dtype=float)

    def has_product_spectra(self) -> bool:
        """Whether the spectra are on the product's 400–700 nm / 10 nm grid (metamerism needs that)."""
        return self.wavelengths_nm is not None and np.array_equal(
            np.asarray(self.wavelengths_nm, dtype=float), WAVELENGTHS
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (geometry names, Lab, spectra, provenance)."""
        return {
            "geometries": list(self.geometries),
            "aspecular_deg": list(self.aspecular_deg),
            "lab": [list(r) for r in self.lab],
            "spectra": None if self.spectra is None else [list(r) for r in self.spectra],
            "wavelengths_nm": None if self.wavelengths_nm is None else list(self.wavelengths_nm),
            "instrument": self.instrument,
            "sample": self.sample,
            "measured_at": None if self.measured_at is None else self.measured_at.isoformat(),
            "measurement_id": self.measurement_id,
        }


def _angle(value: Any, field: str) -> float:
    if _finite(value):
        return float(value)
    if isinstance(value, str):
        try:
            illum, asp = parse_geometry(value, field)
        except ModelInputError as exc:
            raise QcInputError(field, 'a geometry name like "45as15" or an aspecular angle', value) from exc
        if illum != ILLUMINATION_DEG:
            raise QcInputError(field, f"a {ILLUMINATION_DEG:g}° illumination geometry (45asNN)", value)
        return asp
    raise QcInputError(field, 'a geometry name like "45as15" or an aspecular angle', value)


def _illumination(value: Any, field: str) -> float:
    """The illumination angle of a geometry name (45 for a bare aspecular angle)."""
    if isinstance(value, str):
        try:
            return parse_geometry(value, field)[0]
        except ModelInputError as exc:
            raise QcInputError(field, 'a geometry name like "45as15" or an aspecular angle', value) from exc
    return ILLUMINATION_DEG


def _rows(value: Any, keep: Sequence[int], field: str, n: int) -> list[Any] | None:
    """The rows of *value* (one per geometry) at the indices *keep*; None when absent."""
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != n:
        got = len(value) if isinstance(value, list) else type(value).__name__
        raise QcInputError(field, f"one row per geometry ({n})", got)
    return [value[i] for i in keep]


def _conditions(data: Mapping[str, Any]) -> str:
    """Empty when the Lab is stated under D65 / 10° (or the conditions are not stated), else what they are."""
    ill = data.get("illuminant")
    obs = data.get("observer")
    other = []
    if ill not in (None, "", "D65"):
        other.append(str(ill))
    if obs not in (None, "") and "10" not in str(obs):
        other.append(str(obs))
    return ", ".join(other)


def _text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, Mapping):
        parts = [str(value[k]) for k in ("model", "serial", "name") if value.get(k)]
        return " ".join(parts)
    return str(value)


def _time(value: Any, field: str) -> dt.datetime | None:
    if value is None or value == "":
        return None
    if not isinstance(value, str):
        raise QcInputError(field, "an ISO 8601 time with a zone", value)
    try:
        t = dt.datetime.fromisoformat(value.replace("Z", "+00:00"))
    except ValueError as exc:
        raise QcInputError(field, "an ISO 8601 time with a zone", value) from exc
    if t.tzinfo is None:
        raise QcInputError(field, "an ISO 8601 time with a zone", value)
    return t


def reading_from_dict(data: Mapping[str, Any], where: str = "reading") -> Reading:
    """One reading from a ``station measure --json`` object or one entry of ``station import --json``.

    Keys read: ``geometries`` (names like ``"45as15"`` or aspecular angles), ``lab`` (optional when
    ``spectra`` on the 400–700/10 nm grid are given), ``spectra`` + ``wavelengths_nm``, ``instrument``
    (text or an object with model/serial) or ``model`` + ``serial``, ``sample`` or ``panel``,
    ``time``/``measured_at``, ``measurement_id``. Other keys are ignored (the measure output carries
    temperature, diagnosis …).
    """
    if not isinstance(data, Mapping):
        raise QcInputError(where, "a JSON object with geometries and lab", type(data).__name__)
    geoms = data.get("geometries")
    if not isinstance(geoms, list) or not geoms:
        raise QcInputError(
            f"{where}.geometries",
            "a non-empty list of geometries (a gloss-only reading has no colour)",
            geoms,
        )
    keep = [
        i for i, g in enumerate(geoms) if _illumination(g, f"{where}.geometries[{i}]") == ILLUMINATION_DEG
    ]
    if not keep:
        raise QcInputError(
            f"{where}.geometries", f"at least one {ILLUMINATION_DEG:g}° illumination geometry (45asNN)", geoms
        )
    angles = tuple(_angle(geoms[i], f"{where}.geometries[{i}]") for i in keep)
    spectra = _rows(data.get("spectra") or None, keep, f"{where}.spectra", len(geoms))
    wl = data.get("wavelengths_nm") or None
    if spectra is not None and wl is None:
        wl = WAVELENGTHS.tolist()
    lab = _rows(data.get("lab") or None, keep, f"{where}.lab", len(geoms))
    conditions = _conditions(data)
    if lab is None or conditions:
        sp = None if spectra is None else np.asarray(spectra, dtype=float)
        grid = wl is not None and np.array_equal(np.asarray(wl, dtype=float), WAVELENGTHS)
        if sp is None or not grid or sp.ndim != 2:
            accepted = "spectra at 400–700 nm in 10 nm steps"
            if lab is None:
                raise QcInputError(f"{where}.lab", f"L*, a*, b* per geometry (or {accepted})", None)
            raise QcInputError(
                f"{where}.illuminant", f"Lab under D65 / 10° (or {accepted} to compute it)", conditions
            )
        lab = reflectance_to_lab(sp).tolist()
    if not isinstance(lab, list) or not all(isinstance(r, list) and len(r) == 3 for r in lab):
        raise QcInputError(f"{where}.lab", "a list of [L*, a*, b*] triples", lab)
    for i, r in enumerate(lab):
        if not all(_finite(v) for v in r):
            raise QcInputError(f"{where}.lab[{i}]", "three finite numbers", r)
    instrument = data.get("instrument")
    if instrument is None:
        instrument = " ".join(str(data[k]) for k in ("model", "serial") if data.get(k))
    sample = data.get("sample", data.get("panel"))
    mid = data.get("measurement_id")
    return Reading(
        angles,
        tuple((float(r[0]), float(r[1]), float(r[2])) for r in lab),
        None if spectra is None else tuple(tuple(r) for r in spectra),
        None if spectra is None or wl is None else tuple(float(x) for x in wl),
        instrument=_text(instrument),
        sample=_text(sample),
        measured_at=_time(data.get("measured_at", data.get("time")), f"{where}.time"),
        measurement_id=mid if isinstance(mid, int) and not isinstance(mid, bool) else None,
        where=where,
        texture=texture_values(data.get("texture"), where),
    )


def readings_from_json(data: Any, where: str = "file") -> list[Reading]:
    """Every reading in a parsed JSON document: one measure output, an import output, or a list of them."""
    if isinstance(data, Mapping) and "measurements" in data:
        rows = data["measurements"]
        if not isinstance(rows, list) or not rows:
            raise QcInputError(f"{where}.measurements", "a non-empty list of measurements", rows)
        return [reading_from_dict(r, f"{where}.measurements[{i}]") for i, r in enumerate(rows)]
    if isinstance(data, list):
        if not data:
            raise QcInputError(where, "at least one measurement", data)
        return [reading_from_dict(r, f"{where}[{i}]") for i, r in enumerate(data)]
    return [reading_from_dict(data, where)]


def load_readings(path: str | Path) -> list[Reading]:
    """The readings of a file: ``station measure --json`` or ``station import --json`` output (JSON).

    A file that is not JSON goes to the importers of ``station import`` (CxF3, CGATS.17, CSV template),
    when they are installed. Raises :class:`~station.qc.errors.QcInputError` naming the file for an
    unreadable or unrecognised file and naming the field for a bad value.
    """
    p = Path(path)
    name = p.name
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise QcInputError(name, "a readable file", str(p), detail=type(exc).__name__) from exc
    if raw.lstrip(b"\xef\xbb\xbf").lstrip()[:1] not in (b"{", b"["):
        imported = _import_vendor_file(p)
        if imported is not None:
            return readings_from_json(imported, name)
    try:
        data = json.loads(raw.decode("utf-8"), parse_constant=_refuse_constant)
    except UnicodeDecodeError as exc:
        raise QcInputError(name, "a UTF-8 file", None, detail=f"byte {exc.start}") from exc
    except json.JSONDecodeError as exc:
        raise QcInputError(
            name,
            "JSON written by station measure --json or station import --json, or a file station import reads",
            None,
            detail=f"line {exc.lineno}: {exc.msg}",
        ) from exc
    return readings_from_json(data, name)


def _import_vendor_file(path: Path) -> dict[str, Any] | None:
    """The ``station import --json`` document of a vendor file, or None without the importers.

    The importers (``station.ingest.formats.read_measurement_file``) raise their own typed errors
    (input errors naming file, line or element and field).
    """
    import importlib

    try:
        formats = importlib.import_module("station.ingest.formats")
    except ImportError:
        return None
    reader = getattr(formats, "read_measurement_file", None)
    if reader is None:
        return None
    doc = reader(path).to_dict()
    return doc if isinstance(doc, dict) else None


def _refuse_constant(token: str) -> Any:
    raise QcInputError("file", "finite numbers (no NaN or Infinity)", token)


def reading_from_measurement(m: Measurement, instrument: str = "", sample: str = "") -> Reading:
    """A stored measurement as a reading (its aspecular angles, Lab, spectra and time).

    Only a measurement of the 45° illumination block is a QC reading: another block (the 15° block of
    an MA-T12-style reading, stored as its own measurement) is refused, never mixed with a 45° one.
    """
    illumination = ILLUMINATION_DEG if m.illumination_deg is None else float(m.illumination_deg)
    if illumination != ILLUMINATION_DEG:
        raise QcInputError(
            f"measurement {m.id}.illumination_deg",
            f"a measurement of the {ILLUMINATION_DEG:g}° illumination block "
            f"(its {ILLUMINATION_DEG:g}° sibling on the same panel)",
            illumination,
        )
    return Reading(
        tuple(float(a) for a in m.geometries_deg),
        tuple((float(r[0]), float(r[1]), float(r[2])) for r in m.lab),
        None if m.spectra is None else tuple(tuple(float(v) for v in r) for r in m.spectra),
        None if m.spectra is None or m.wavelengths_nm is None else tuple(float(x) for x in m.wavelengths_nm),
        instrument=instrument,
        sample=sample,
        measured_at=m.measured_at,
        measurement_id=m.id,
        where=f"measurement {m.id}",
        texture=texture_values(m.texture, f"measurement {m.id}"),
    )


def common_angles(readings: Sequence[Reading]) -> tuple[float, ...]:
    """The aspecular angles every reading has, in the first reading's order."""
    if not readings:
        return ()
    shared = set(readings[0].aspecular_deg)
    for r in readings[1:]:
        shared &= set(r.aspecular_deg)
    return tuple(a for a in readings[0].aspecular_deg if a in shared)


def lab_at(reading: Reading, angles: Sequence[float]) -> NDArray[np.float64]:
    """Lab of *reading* at *angles* (each must be one of its geometries), shape (len(angles), 3)."""
    index = {a: i for i, a in enumerate(reading.aspecular_deg)}
    missing = [aspecular_name(a) for a in angles if a not in index]
    if missing:
        raise QcInputError(
            f"{reading.where}.geometries", f"the geometries {', '.join(missing)}", list(reading.geometries)
        )
    lab = reading.lab_array()
    return lab[[index[a] for a in angles]]
