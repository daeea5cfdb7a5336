"""The colorant gamut: whether a paint can be mixed from the shipped colorants, and the nearest that can.

Two questions, two functions:

* :func:`line_gamut` — **can the toner line mix it at all?** The line's gamut: the best recipe with
  every colorant of the line free and the amounts unrounded (the line-wide fit of
  :func:`station.formulate.formulation.line_wide_fit`, the matting agent set by the gloss) reaches the
  tolerance. A design outside it is refused before formulation: no recipe of that line, of any size,
  makes it, so a chemist's recipe of a few weighable colorants cannot either.
* :func:`colorant_gamut` — **does the chemist's recipe reach it?**

The second rule (one place; the QA step, the CLI and the service ask it): a paint is **inside the colorant
gamut** when the formulator (:func:`station.formulate.formulation.formulate`) reaches it within the
formulation tolerance (mean CIEDE2000 over 15/45/110°, :data:`station.model.domain.FORMULATION_TOLERANCE_DE00`).
Outside it, the **nearest achievable paint** is the colour of the best recipe: its predicted Lab at the
five standard angles, fitted to face/flop/travel/gloss (:func:`station.model.fit.fit_fftg`), with the
recipe that makes it. The analysis package's own "paintable" bound (station.analysis.gamut: sRGB
chromaticity, reflectance) is the physical pre-check; this one is the check against the colorants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from station.formulate.colorants import (
    GLOSS_CLEAR_GU,
    ColorantDatabase,
    default_database,
    predict_gloss,
    predict_lab,
)
from station.formulate.de_kernels import cie2000
from station.formulate.formulation import (
    DEFAULT_TOLERANCE,
    MAX_STARTS,
    FormulationResult,
    formulate,
    line_wide_fit,
    matting_for_gloss,
)
from station.formulate.lines import lines_for_design
from station.formulate.snap import validate_design_lab
from station.model import ANGLES_3, ANGLES_5, AspecularMeasurements, FaceFlopTravelGloss
from station.model.design_io import design_to_dict
from station.model.fit import fit_fftg


@dataclass(frozen=True)
class ColorantGamutReport:
    """Verdict of :func:`colorant_gamut`.

    ``inside``: the paint is formulable within ``tolerance``; ``mean_de``: the best recipe's predicted
    mean ΔE00 at 15/45/110°; ``nearest``: the paint that recipe makes (the paint itself when inside);
    ``formulation``: the formulation result (recipe, batch); ``message``: one sentence.
    """

    inside: bool
    mean_de: float
    tolerance: float
    nearest: FaceFlopTravelGloss
    formulation: FormulationResult
    message: str

    def to_dict(self) -> dict[str, object]:
        """JSON-able form."""
        return {
            "inside_colorant_gamut": self.inside,
            "mean_de": self.mean_de,
            "tolerance": self.tolerance,
            "metric": "cie2000",
            "nearest_achievable_paint": design_to_dict(self.nearest),
            "recipe": self.formulation.recipe,
            "message": self.message,
            "synthetic_colorants": self.formulation.synthetic,
        }


def colorant_gamut(
    paint: FaceFlopTravelGloss,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
    time_budget_s: float | None = None,
) -> ColorantGamutReport:
    """Whether *paint* can be mixed from the colorants, and the nearest achievable paint (module docstring).

    *time_budget_s* is accepted for compatibility and ignored: the formulator stops on counts only."""
    del time_budget_s
    db = db or default_database()
    lab = paint.lab_at(np.array(ANGLES_3))
    result = formulate(lab, ANGLES_3, gloss_gu=paint.gloss_gu, tolerance=tolerance, db=db)
    if result.formulable:
        nearest = paint
        msg = f"inside the colorant gamut: mean ΔE00 {result.mean_de:.2f} <= {tolerance:g}"
    else:
        five = predict_lab(result.concentrations, ANGLES_5, db)
        gloss = float(predict_gloss(result.concentrations, db))
        fit = fit_fftg(AspecularMeasurements(ANGLES_5, five, gloss))
        nearest = FaceFlopTravelGloss(
            fit.design.face, fit.design.flop, fit.design.travel_deg, fit.design.gloss_gu, "nearest achievable"
        )
        msg = (
            f"outside the colorant gamut: the best recipe misses by mean ΔE00 {result.mean_de:.2f} > "
            f"{tolerance:g}; nearest achievable paint face {np.round(nearest.face, 1).tolist()}, "
            f"flop {np.round(nearest.flop, 1).tolist()}"
        )
    return ColorantGamutReport(result.formulable, result.mean_de, float(tolerance), nearest, result, msg)


@dataclass(frozen=True)
class LineGamutReport:
    """Verdict of :func:`line_gamut`: ``inside`` when the best line-wide recipe's mean ΔE00 (over the
    design's angles, amounts unrounded) is at most ``tolerance``; ``line`` the line that came closest,
    ``recipe`` its recipe (mass fractions), ``per_line`` the best mean ΔE00 of every line tried."""

    inside: bool
    mean_de: float
    tolerance: float
    line: str
    recipe: dict[str, float]
    per_line: dict[str, float]


def line_gamut(
    design_lab: ArrayLike,
    angles_deg: tuple[float, ...] = ANGLES_3,
    gloss_gu: float | None = None,
    *,
    line: str | None = None,
    paint_type: str | None = None,
    starts: list[tuple[str, ArrayLike | dict[str, float]]] | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    db: ColorantDatabase | None = None,
) -> LineGamutReport:
    """Whether the toner line (named, else from *paint_type*, else from the design's type, as
    :func:`station.formulate.lines.lines_for_design` picks it) can mix the design with any amounts of
    all its colorants (module docstring). *starts*: starting recipes (e.g. ColorSnap matches' recipes)
    besides the generic ones; *gloss_gu* sets the matting agent (``None``: full gloss)."""
    db = db or default_database()
    angles = tuple(float(a) for a in angles_deg)
    design = validate_design_lab(design_lab, len(angles), "design_lab")
    c_mat, _ = matting_for_gloss(GLOSS_CLEAR_GU if gloss_gu is None else gloss_gu, db)
    given = [
        (
            lb,
            db.check(
                db.vector(r) if isinstance(r, dict) else np.asarray(r, dtype=np.float64), f"starts[{lb}]"
            ),
        )
        for lb, r in starts or []
    ]
    best: tuple[float, str, dict[str, float]] = (np.inf, "", {})
    per_line: dict[str, float] = {}
    for name in lines_for_design(design, line, paint_type):
        prob, _, tried = line_wide_fit(design, angles, given, c_mat, db, name, MAX_STARTS, tolerance)
        c = prob.full(tried[0][2])
        de = float(cie2000(design, predict_lab(c, angles, db)).mean())
        per_line[name] = de
        if de < best[0]:
            best = (de, name, db.recipe(c))
        if de <= tolerance:
            break
    return LineGamutReport(best[0] <= tolerance, best[0], float(tolerance), best[1], best[2], per_line)
