"""Candidate recipes ranked by their metamerism index under the lab's chosen illuminants.

A formulation reaches several distinct recipes from its starts (:attr:`FormulationResult.candidates`).
Each matches the design under D65 to some ΔE00, but a recipe built from other colorants than the
standard's can match in daylight and drift apart under shop or street light. For each candidate and
each chosen test illuminant the CIE special metamerism index (change in illuminant) is computed per
geometry by :func:`station.model.spectra.metamerism_index` (CIEDE2000; the candidate's mismatch under
the reference illuminant D65 corrected additively in Lab first), from

* the candidate's predicted reflectance per geometry (:func:`~station.formulate.colorants.predict_reflectance`);
* the standard's reflectance per geometry: a measured standard's spectra when given, else the
  smoothest reflectance reproducing the design's Lab (:func:`~station.model.spectra.reflectance_from_lab`,
  stated in the output as ``reference_spectra``).

Ranking rule (:func:`rank_candidates`), best first:

1. formulable candidates (mean ΔE00 under D65 within the tolerance) before the others;
2. the lower **worst index**: the largest metamerism index over the chosen illuminants and the
   geometries; indices are compared rounded to :data:`MI_RESOLUTION` (0.01 ΔE00), so smaller
   differences tie;
3. the lower mean ΔE00 to the design under D65;
4. the start's order (the ColorSnap matches' order, then the generic starts).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.batch import batch_masses
from station.formulate.colorants import (
    ColorantDatabase,
    default_database,
    lab_from_reflectance,
    predict_reflectance,
)
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import FormulationResult
from station.model.domain import aspecular_name
from station.model.errors import ModelInputError
from station.model.illuminants import (
    REFERENCE_ILLUMINANT,
    Illuminant,
    SpdFileError,
    illuminant_from_text,
)
from station.model.spectra import WAVELENGTHS, metamerism_index, reflectance_from_lab

__all__ = [
    "MI_RESOLUTION",
    "Candidate",
    "MetamerismRanking",
    "RankedCandidate",
    "chosen_illuminants",
    "rank_candidates",
    "rank_formulation",
]

#: Metamerism indices closer than this (ΔE00) rank as equal (rule step 2).
MI_RESOLUTION = 0.01
RULE = (
    "formulable first; then the lower worst metamerism index (max over illuminants and geometries, "
    f"CIEDE2000, resolution {MI_RESOLUTION:g}); then the lower mean ΔE00 under D65; then start order"
)


def chosen_illuminants(
    names: Sequence[str | Illuminant], field: str = "illuminants", allow_files: bool = False
) -> tuple[str | Illuminant, ...]:
    """The chosen test illuminants as catalogue names (or user SPDs), each once, in the order given.

    With *allow_files* a ``*.csv`` entry is a user SPD file
    (:func:`station.model.illuminants.illuminant_from_text`); an :class:`Illuminant` is kept as given.

    Raises
    ------
    FormulateInputError
        Empty, an unknown name, or the reference illuminant D65 itself (its index is 0 by construction);
        a bad SPD file raises its own error naming the file.
    """
    out: list[str | Illuminant] = []
    for i, raw in enumerate(names):
        try:
            name = raw if isinstance(raw, Illuminant) else illuminant_from_text(raw, allow_files)
        except SpdFileError:
            raise
        except ModelInputError as exc:
            raise FormulateInputError(f"{field}[{i}]", exc.accepted, raw) from exc
        if name == REFERENCE_ILLUMINANT:
            raise FormulateInputError(
                f"{field}[{i}]", f"a test illuminant other than the reference {REFERENCE_ILLUMINANT}", raw
            )
        if name not in out:
            out.append(name)
    if not out:
        raise FormulateInputError(field, "at least one test illuminant, e.g. A,F11", list(names))
    return tuple(out)


@dataclass(frozen=True)
class Candidate:
    """A recipe to rank: its predicted reflectance per geometry and its match under D65.

    Attributes
    ----------
    label
        Where it came from (a library code, ``generic``, ``given``).
    recipe
        ``{colorant: mass fraction}``.
    reflectance
        Predicted reflectance factors per geometry, shape (A, 31) on 400–700 nm / 10 nm.
    de_per_angle
        CIEDE2000 to the design under D65 per geometry.
    formulable
        Its mean ΔE00 is within the formulation tolerance.
    """

    label: str
    recipe: dict[str, float]
    reflectance: NDArray[np.float64]
    de_per_angle: tuple[float, ...]
    formulable: bool

    @property
    def mean_de(self) -> float:
        """Mean CIEDE2000 to the design under D65 over the geometries."""
        return float(np.mean(self.de_per_angle))


@dataclass(frozen=True)
class RankedCandidate:
    """A candidate with its metamerism index per illuminant and geometry and its place in the ranking."""

    rank: int
    candidate: Candidate
    index: dict[str, tuple[float, ...]]
    worst_index: float
    worst_illuminant: str
    worst_geometry: str

    def to_dict(self, angles_deg: Sequence[float]) -> dict[str, Any]:
        c = self.candidate
        return {
            "rank": self.rank,
            "start": c.label,
            "recipe": c.recipe,
            "formulable": c.formulable,
            "de_per_angle": list(c.de_per_angle),
            "mean_de": c.mean_de,
            "metamerism_index": {
                ill: [{"geometry": aspecular_name(a), "mi": v} for a, v in zip(angles_deg, vals, strict=True)]
                for ill, vals in self.index.items()
            },
            "max_index": {ill: max(vals) for ill, vals in self.index.items()},
            "worst_index": self.worst_index,
            "worst_illuminant": self.worst_illuminant,
            "worst_geometry": self.worst_geometry,
            "batch": batch_masses(c.recipe).to_dict(),
        }


@dataclass(frozen=True)
class MetamerismRanking:
    """Candidates best first under :data:`RULE`, with what the indices were computed from."""

    illuminants: tuple[str, ...]  # display names (a user SPD by its name)
    angles_deg: tuple[float, ...]
    reference_spectra: str
    ranked: tuple[RankedCandidate, ...]

    @property
    def best(self) -> RankedCandidate:
        """The first-ranked candidate."""
        return self.ranked[0]

    def to_dict(self) -> dict[str, Any]:
        return {
            "reference_illuminant": REFERENCE_ILLUMINANT,
            "illuminants": list(self.illuminants),
            "method": "cie2000",
            "index": "CIE special metamerism index (change in illuminant), additive correction from D65",
            "reference_spectra": self.reference_spectra,
            "rule": RULE,
            "candidates": [r.to_dict(self.angles_deg) for r in self.ranked],
        }


def rank_candidates(
    reference_reflectance: ArrayLike,
    candidates: Sequence[Candidate],
    angles_deg: Sequence[float],
    illuminants: Sequence[str | Illuminant],
    reference_spectra: str = "given",
) -> MetamerismRanking:
    """Rank *candidates* by their metamerism index against the standard (module docstring's rule).

    Parameters
    ----------
    reference_reflectance
        The standard's reflectance per geometry, shape (A, 31), same geometries as the candidates.
    candidates
        The recipes to rank (at least one).
    angles_deg
        Aspecular angles (degrees) of the A geometries.
    illuminants
        Test illuminants (catalogue names or user SPDs, :func:`chosen_illuminants`); reference D65.
    """
    chosen = chosen_illuminants(illuminants)
    ills = tuple(i.name if isinstance(i, Illuminant) else i for i in chosen)
    angles = tuple(float(a) for a in angles_deg)
    ref = np.asarray(reference_reflectance, dtype=float)
    if ref.shape != (len(angles), WAVELENGTHS.size):
        raise FormulateInputError(
            "reference_reflectance", f"shape ({len(angles)}, {WAVELENGTHS.size})", ref.shape
        )
    if not candidates:
        raise FormulateInputError("candidates", "at least one candidate recipe", 0)
    names = [aspecular_name(a) for a in angles]
    scored = []
    for order, cand in enumerate(candidates):
        out = metamerism_index(ref, cand.reflectance, REFERENCE_ILLUMINANT, chosen, method="cie2000")
        index = {ill: tuple(float(v) for v in out[ill]) for ill in ills}
        table = np.array([index[ill] for ill in ills])
        i, j = np.unravel_index(int(np.argmax(table)), table.shape)
        worst = float(table[i, j])
        key = (not cand.formulable, round(worst / MI_RESOLUTION), cand.mean_de, order)
        scored.append((key, cand, index, worst, ills[i], names[j]))
    scored.sort(key=lambda t: t[0])
    ranked = tuple(
        RankedCandidate(k + 1, cand, index, worst, ill, geo)
        for k, (_, cand, index, worst, ill, geo) in enumerate(scored)
    )
    return MetamerismRanking(ills, angles, reference_spectra, ranked)


def rank_formulation(
    result: FormulationResult,
    illuminants: Sequence[str | Illuminant],
    db: ColorantDatabase | None = None,
    reference_reflectance: ArrayLike | None = None,
) -> MetamerismRanking:
    """Rank the candidate recipes of a formulation (``formulate(..., candidates=n)``).

    *reference_reflectance* is the standard's measured reflectance per geometry of the result (A, 31);
    ``None`` recovers the smoothest reflectance reproducing the design's Lab.
    """
    db = db or default_database()
    cands = result.candidates or (("winner", result.concentrations),)
    angles = result.angles_deg
    if reference_reflectance is None:
        try:
            ref = reflectance_from_lab(result.design_lab)
        except ModelInputError as exc:
            raise FormulateInputError(
                "design_lab",
                "a design some reflectance reproduces (the metamerism reference), or the standard's spectra",
                exc.got,
            ) from exc
        source = "the smoothest reflectance reproducing the design's Lab (D65/10°) per geometry"
    else:
        ref = np.asarray(reference_reflectance, dtype=float)
        source = "the standard's measured spectra"
    conc = np.asarray([c for _, c in cands])
    refl = predict_reflectance(conc, angles, db)
    de = cie2000(result.design_lab[None], lab_from_reflectance(refl))
    rows = [
        Candidate(
            label,
            db.recipe(c, 1e-6),
            refl[k],
            tuple(float(v) for v in de[k]),
            bool(de[k].mean() <= result.tolerance),
        )
        for k, (label, c) in enumerate(cands)
    ]
    return rank_candidates(ref, rows, angles, illuminants, source)
