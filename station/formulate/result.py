"""A formulated recipe and its predicted colour (:class:`FormulationResult`), as the CLI, the service
and the viewer show it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from station.formulate.batch import batch_masses
from station.formulate.selection import RecipeOption

__all__ = ["FormulationResult"]


@dataclass(frozen=True)
class FormulationResult:
    """A formulated recipe and its predicted colour.

    Attributes
    ----------
    recipe
        ``{colorant: mass fraction}`` (fractions below 1e-6 omitted).
    concentrations
        The full vector, in :attr:`ColorantDatabase.names` order.
    angles_deg, design_lab, predicted_lab
        Angles (degrees) and Lab (D65/10°) of the design and of the recipe's prediction, shape (A, 3).
    de_per_angle
        Predicted CIEDE2000 per angle; ``mean_de`` and ``max_de`` summarise it.
    formulable
        ``mean_de <= tolerance``; ``message`` says "not formulable with these colorants" otherwise.
    gloss_gu
        Predicted 60° gloss (GU) of the recipe.
    start
        Where the winning start came from (a library code, "given" or "generic").
    candidates
        ``(start label, full concentration vector)`` of the distinct recipes the starts converged to,
        the winning recipe first (filled when :func:`formulate` is asked for ``candidates``); their
        metamerism ranking is :func:`station.formulate.metamerism.rank_formulation`.
    line
        The toner line the recipe is drawn from.
    recipes
        The best few recipes, ranked (:mod:`station.formulate.selection`); ``recipe`` is the first.
    mean_de_unrounded
        Mean ΔE00 of the first recipe before its amounts were rounded to the scale.
    """

    recipe: dict[str, float]
    concentrations: NDArray[np.float64]
    angles_deg: tuple[float, ...]
    design_lab: NDArray[np.float64]
    predicted_lab: NDArray[np.float64]
    de_per_angle: tuple[float, ...]
    mean_de: float
    max_de: float
    formulable: bool
    tolerance: float
    gloss_gu: float
    start: str
    message: str
    elapsed_s: float = 0.0
    evaluations: int = 0
    synthetic: bool = True
    warnings: tuple[str, ...] = field(default=())
    candidates: tuple[tuple[str, NDArray[np.float64]], ...] = field(default=())
    line: str = ""
    recipes: tuple[RecipeOption, ...] = field(default=())
    mean_de_unrounded: float = float("nan")

    def to_dict(self) -> dict[str, object]:
        """JSON-able form for the CLI and the service."""
        return {
            "recipe": self.recipe,
            "angles_deg": list(self.angles_deg),
            "design_lab": self.design_lab.tolist(),
            "predicted_lab": self.predicted_lab.tolist(),
            "de_per_angle": list(self.de_per_angle),
            "mean_de": self.mean_de,
            "max_de": self.max_de,
            "metric": "cie2000",
            "formulable": self.formulable,
            "tolerance": self.tolerance,
            "gloss_gu": self.gloss_gu,
            "start": self.start,
            "message": self.message,
            "elapsed_s": self.elapsed_s,
            "synthetic_colorants": self.synthetic,
            "warnings": list(self.warnings),
            "batch": batch_masses(self.recipe).to_dict(),
            "nearest_achievable_lab": None if self.formulable else self.predicted_lab.tolist(),
            "line": self.line,
            "mean_de_unrounded": self.mean_de_unrounded,
            "evaluations": self.evaluations,
            "recipes": [o.to_dict() for o in self.recipes],
        }
