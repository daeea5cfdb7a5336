"""A formulated recipe and its predicted colour (:class:`FormulationResult`), as the CLI, the service
and the viewer show it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from station.formulate.batch import batch_masses
from station.formulate.selection import RecipeOption
from station.wire import wire_form

__all__ = ["FormulationResult", "RecipeGamutReport"]


@dataclass(frozen=True)
class RecipeGamutReport:
    """Verdict of :func:`station.formulate.gamut.recipe_gamut`: is the design inside the gamut of its toner
    line *for a recipe of at most* ``max_colorants`` colorants (binder and matting agent not counted)?

    ``inside``: the best screened recipe of at most ``max_colorants`` colorants, refitted with its amounts
    unrounded, reaches ``tolerance`` (mean CIEDE2000 over the design's angles), ``mean_de`` its mean ΔE00
    and ``recipe`` its mass fractions, on ``line``; ``line_inside``/``line_mean_de``: the same with every
    colorant of the line free (the line's gamut, which holds the N-colorant one); ``needed_colorants``:
    when only the colorant limit refuses the design, the fewest colorants whose screen reaches it
    (``None`` when none up to the allowed maximum does, or when the limit is not the reason);
    ``message``: one sentence for the user."""

    inside: bool
    line_inside: bool
    mean_de: float
    line_mean_de: float
    max_colorants: int
    tolerance: float
    line: str
    recipe: dict[str, float]
    needed_colorants: int | None
    message: str

    def to_dict(self) -> dict[str, object]:
        """JSON-able form (every field, and the ΔE formula)."""
        return wire_form(self, after={"tolerance": {"metric": "cie2000"}})


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
    gamut
        When the best recipe misses the tolerance and the front asked why
        (:func:`station.formulate.gamut.formulate_in_gamut`), the colorant-limited gamut verdict; its
        sentence ends ``message``.
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
    gamut: RecipeGamutReport | None = None

    def to_dict(self) -> dict[str, object]:
        """JSON-able form for the CLI and the service."""
        nearest = None if self.formulable else self.predicted_lab
        return wire_form(
            self,
            rename={"synthetic": "synthetic_colorants"},
            omit={"concentrations", "evaluations", "candidates", "recipes"},
            after={
                "max_de": {"metric": "cie2000"},
                "warnings": {"batch": batch_masses(self.recipe), "nearest_achievable_lab": nearest},
                "mean_de_unrounded": {"evaluations": self.evaluations, "recipes": self.recipes},
            },
        )
