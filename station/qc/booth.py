"""The virtual light booth's numbers: standard against sample under each booth illuminant, per geometry.

For each illuminant and each geometry both readings share: the standard's and the sample's Lab under
that illuminant (its own white, the chosen observer: :func:`station.model.spectra.reflectance_to_lab`),
their CIEDE2000 difference, and the CIE special metamerism index against the reference illuminant D65
(the sample corrected additively in Lab for its D65 mismatch:
:func:`station.model.spectra.metamerism_index`, the one implementation). The index under the reference
itself is 0 by definition. ``mean_de`` is the mean ΔE00 over the geometries.

Both readings need spectra covering the product's 400–700 nm grid at 10 nm (any finer or wider grid
holding those bands is cut to them); a reading without spectra is refused naming its source.

Either side may be a recipe (:class:`BoothRecipe`): its reading is the colorant model's predicted
reflectance (:func:`station.formulate.recipe_spectra.recipe_spectra`) at the other side's geometries, or
at the product's standard 3-angle set when both sides are recipes (:func:`booth_sides`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.errors import FormulateInputError
from station.formulate.recipe_spectra import is_recipe_document, recipe_from_document, recipe_spectra
from station.model.colorimetry import OBSERVER_10
from station.model.difference import delta_e
from station.model.domain import ANGLES_3, DEFAULT_BOOTH_ILLUMINANTS, aspecular_name
from station.model.errors import ModelInputError
from station.model.illuminants import REFERENCE_ILLUMINANT, Illuminant, illuminant_sd, observer_cie_name
from station.model.spectra import WAVELENGTHS, metamerism_index, reflectance_to_lab
from station.qc.errors import QcInputError
from station.qc.readings import Reading, load_readings
from station.wire import wire_form

__all__ = [
    "DEFAULT_BOOTH_ILLUMINANTS",
    "BoothComparison",
    "BoothGeometry",
    "BoothIlluminant",
    "BoothRecipe",
    "booth_compare",
    "booth_compare_spectra",
    "booth_sides",
    "load_booth_side",
    "product_spectra",
    "recipe_reading",
]

#: The illuminants of a booth check when none are named: daylight, tungsten, shop light.


@dataclass(frozen=True)
class BoothGeometry:
    """One geometry under one illuminant: both Lab (that illuminant's white), ΔE00 and the index."""

    aspecular_deg: float
    standard_lab: tuple[float, float, float]
    sample_lab: tuple[float, float, float]
    de00: float
    metamerism_index: float

    @property
    def geometry(self) -> str:
        """Geometry name, e.g. ``"45as15"``."""
        return aspecular_name(self.aspecular_deg)

    def to_dict(self) -> dict[str, Any]:
        return wire_form(
            self,
            rename={"aspecular_deg": "geometry", "de00": "dE00"},
            convert={"aspecular_deg": aspecular_name},
        )


@dataclass(frozen=True)
class BoothIlluminant:
    """Every shared geometry under one illuminant, and the mean ΔE00 over them."""

    name: str
    per_geometry: tuple[BoothGeometry, ...]

    @property
    def mean_de(self) -> float:
        """Mean ΔE00 over the geometries."""
        return float(np.mean([g.de00 for g in self.per_geometry]))

    def to_dict(self) -> dict[str, Any]:
        return wire_form(self, after={"per_geometry": {"mean_de": self.mean_de}})


@dataclass(frozen=True)
class BoothComparison:
    """A booth check: one :class:`BoothIlluminant` per illuminant, in the order asked."""

    illuminants: tuple[BoothIlluminant, ...]
    reference: str = REFERENCE_ILLUMINANT
    observer: str = OBSERVER_10

    def under(self, name: str) -> BoothIlluminant:
        """The rows of illuminant *name* (as named in the comparison)."""
        for row in self.illuminants:
            if row.name == name:
                return row
        raise QcInputError("illuminant", f"one of {', '.join(r.name for r in self.illuminants)}", name)

    def to_dict(self) -> dict[str, Any]:
        """``{"illuminants": [{"name", "per_geometry": [...], "mean_de"}], "reference": "D65"}``."""
        return wire_form(self, omit={"observer"})


def product_spectra(reading: Reading, role: str = "") -> NDArray[np.float64]:
    """The reading's reflectance per geometry on :data:`~station.model.spectra.WAVELENGTHS`, (n, 31).

    Raises
    ------
    QcInputError
        No spectra (the message names the reading's source), or spectra missing a band of 400–700 nm
        at 10 nm.
    """
    where = reading.where if not role else f"{role} {reading.where}"
    if reading.spectra is None or reading.wavelengths_nm is None:
        raise QcInputError(
            where, "a reading with spectra (the booth computes Lab from spectra)", "no spectra"
        )
    wl = [float(w) for w in reading.wavelengths_nm]
    try:
        cols = [wl.index(float(w)) for w in WAVELENGTHS]
    except ValueError as exc:
        raise QcInputError(
            f"{where}.wavelengths_nm",
            f"every band of {WAVELENGTHS[0]:g}–{WAVELENGTHS[-1]:g} nm at {WAVELENGTHS[1] - WAVELENGTHS[0]:g} nm",
            f"{wl[0]:g}–{wl[-1]:g} nm ({len(wl)} bands)",
        ) from exc
    return np.asarray(reading.spectra, dtype=float)[:, cols]


def _name(illuminant: str | Illuminant) -> str:
    return illuminant.name if isinstance(illuminant, Illuminant) else illuminant_sd(illuminant)[0]


def booth_compare_spectra(
    standard: ArrayLike,
    sample: ArrayLike,
    aspecular_deg: Sequence[float],
    illuminants: Sequence[str | Illuminant] = DEFAULT_BOOTH_ILLUMINANTS,
    observer: str = OBSERVER_10,
    reference: str | Illuminant = REFERENCE_ILLUMINANT,
) -> BoothComparison:
    """Booth comparison of two sets of spectra at the same geometries (measured, imported or predicted).

    Parameters
    ----------
    standard, sample
        Reflectance per geometry, shape (n, 31), 400–700 nm at 10 nm.
    aspecular_deg
        The n aspecular angles, degrees (45° illumination).
    illuminants
        Booth names (``"D65"``, ``"A"``, ``"F11"``, ``"TL84"``, ``"LED-B3"``, …) or user
        :class:`~station.model.illuminants.Illuminant` objects; names must be distinct.
    observer
        ``"2"``, ``"10"`` or a colour-science observer name.
    reference
        The metamerism index's reference illuminant (D65).
    """
    try:
        obs = observer_cie_name(observer)
        names = [_name(i) for i in illuminants]
        ref_name = _name(reference)
    except ModelInputError as exc:
        raise QcInputError(exc.field, exc.accepted, exc.got) from exc
    if not names:
        raise QcInputError("illuminants", "at least one illuminant", [])
    if len(set(names)) != len(names):
        raise QcInputError("illuminants", "distinct illuminants", names)
    std = np.asarray(standard, dtype=float)
    smp = np.asarray(sample, dtype=float)
    angles = tuple(float(a) for a in aspecular_deg)
    if std.shape != smp.shape or std.ndim != 2 or std.shape[0] != len(angles):
        raise QcInputError(
            "sample.spectra", f"{len(angles)} spectra like the standard's {list(std.shape)}", list(smp.shape)
        )
    try:
        index = metamerism_index(std, smp, reference, tuple(illuminants), "cie2000", observer=obs)
        rows = []
        for ill, name in zip(illuminants, names, strict=True):
            lab_std = reflectance_to_lab(std, ill, obs)
            lab_smp = reflectance_to_lab(smp, ill, obs)
            de = delta_e(lab_std, lab_smp, "cie2000")
            mi = (
                np.zeros(len(angles))
                if name == ref_name
                else index[ill.name if isinstance(ill, Illuminant) else ill]
            )
            rows.append(
                BoothIlluminant(
                    name,
                    tuple(
                        BoothGeometry(
                            a,
                            (float(lab_std[g, 0]), float(lab_std[g, 1]), float(lab_std[g, 2])),
                            (float(lab_smp[g, 0]), float(lab_smp[g, 1]), float(lab_smp[g, 2])),
                            float(de[g]),
                            float(mi[g]),
                        )
                        for g, a in enumerate(angles)
                    ),
                )
            )
    except ModelInputError as exc:
        raise QcInputError(exc.field, exc.accepted, exc.got) from exc
    return BoothComparison(tuple(rows), ref_name, obs)


def booth_compare(
    standard: Reading,
    sample: Reading,
    illuminants: Sequence[str | Illuminant] = DEFAULT_BOOTH_ILLUMINANTS,
    observer: str = OBSERVER_10,
) -> BoothComparison:
    """Booth comparison of two readings at the geometries both have (in the standard's order).

    Raises
    ------
    QcInputError
        A reading without spectra (naming its source), no shared geometry, an unknown illuminant or
        observer.
    """
    std_all = product_spectra(standard, "standard")
    smp_all = product_spectra(sample, "sample")
    angles = tuple(a for a in standard.aspecular_deg if a in sample.aspecular_deg)
    if not angles:
        raise QcInputError(
            "sample.geometries", f"a geometry of the standard {list(standard.geometries)}", None
        )
    si = [standard.aspecular_deg.index(a) for a in angles]
    pi = [sample.aspecular_deg.index(a) for a in angles]
    return booth_compare_spectra(std_all[si], smp_all[pi], angles, illuminants, observer)


@dataclass(frozen=True)
class BoothRecipe:
    """A recipe on one side of the booth: ``{colorant: mass fraction}`` and its name for messages (a file
    name, ``"recipe 4"``)."""

    fractions: Mapping[str, float] = field(hash=False)
    where: str = "recipe"


def recipe_reading(recipe: BoothRecipe, aspecular_deg: Sequence[float] = ANGLES_3, role: str = "") -> Reading:
    """The reading of *recipe* predicted by the colorant model at *aspecular_deg*: spectra per geometry
    on the product's grid and their Lab (D65 / 10°).

    Raises
    ------
    QcInputError
        Naming the recipe: an unknown colorant, a fraction or total out of bounds.
    """
    where = recipe.where if not role else f"{role} {recipe.where}"
    angles = tuple(float(a) for a in aspecular_deg)
    try:
        spectra = recipe_spectra(recipe.fractions, angles, where=where)
    except FormulateInputError as exc:
        raise QcInputError(exc.field, exc.accepted, exc.got) from exc
    lab = reflectance_to_lab(spectra)
    return Reading(
        angles,
        tuple((float(r[0]), float(r[1]), float(r[2])) for r in lab),
        tuple(tuple(float(v) for v in row) for row in spectra),
        tuple(float(w) for w in WAVELENGTHS),
        sample=recipe.where,
        where=where,
    )


def booth_sides(standard: Reading | BoothRecipe, sample: Reading | BoothRecipe) -> tuple[Reading, Reading]:
    """Both sides as readings: a recipe is predicted at the other side's geometries, or at the product's
    standard 3-angle set (:data:`~station.model.domain.ANGLES_3`) when both are recipes."""

    def geometries(other: Reading | BoothRecipe) -> tuple[float, ...]:
        return other.aspecular_deg if isinstance(other, Reading) else ANGLES_3

    std = (
        standard
        if isinstance(standard, Reading)
        else recipe_reading(standard, geometries(sample), "standard")
    )
    smp = sample if isinstance(sample, Reading) else recipe_reading(sample, geometries(standard), "sample")
    return std, smp


def load_booth_side(path: str | Path, role: str) -> Reading | BoothRecipe:
    """One side of the booth from file *path*, recognised by its content: a recipe (JSON with
    ``"recipe": {colorant: fraction}``, as ``station formulate --json`` writes it) or a file
    ``station import`` reads holding one reading with spectra.

    Raises
    ------
    QcInputError
        Naming *role* and the file when it is neither a recipe nor one reading with spectra.
    """
    p = Path(path)
    where = f"{role} {p.name}"
    accepted = (
        "a measurement with spectra (a file station import reads) or a recipe (station formulate --json)"
    )
    data = _json_or_none(p)
    if data is not None and is_recipe_document(data):
        return BoothRecipe(recipe_from_document(data, where), p.name)
    try:
        readings = load_readings(p)
    except QcInputError as exc:
        raise QcInputError(where, accepted, None, detail=str(exc)) from exc
    if len(readings) != 1:
        raise QcInputError(
            where, "one reading with spectra (spectra are not averaged) or a recipe", len(readings)
        )
    if readings[0].spectra is None:
        raise QcInputError(where, accepted, "no spectra")
    return readings[0]


def _json_or_none(path: Path) -> Any:
    try:
        raw = path.read_bytes()
    except OSError:
        return None  # load_readings says why
    if raw.lstrip(b"\xef\xbb\xbf").lstrip()[:1] != b"{":
        return None
    try:
        return json.loads(raw.decode("utf-8-sig"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        return None
