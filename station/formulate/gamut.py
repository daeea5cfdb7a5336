"""The colorant gamut: whether a paint can be mixed from the shipped colorants, and the nearest that can.

The rule (one place; the QA step, the CLI and the service ask it): a paint is **inside the colorant
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

from station.formulate.colorants import ColorantDatabase, default_database, predict_gloss, predict_lab
from station.formulate.formulation import DEFAULT_TOLERANCE, FormulationResult, formulate
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
