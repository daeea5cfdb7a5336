"""Recipe panels: a virtual panel painted with a recipe of the SYNTHETIC colorant database.

A recipe is what :mod:`station.formulate` produces (``station formulate DESIGN --json`` prints it as
``{"recipe": {colorant: mass fraction}, ...}``). The panel's spectral reflectance at any aspecular
angle θ comes straight from the colorant model,
:func:`station.formulate.colorants.predict_reflectance` (Kubelka–Munk per geometry + Saunderson,
docs/formulate.md "Colorant model"), which is defined for every θ: absorption does not depend on θ,
the scattering of flakes, pearls and interference pigments carries their angular lobe g_i(|θ|) and
the interference band shift. So every geometry of every simulated instrument is evaluated exactly,
with no fit of ``station.model``'s clamped quadratic and no spectral recovery in between:

* MA6 (45° illumination) at −15/15/25/45/75/110°, MA3 at 15/45/110°;
* the optional 15°-illumination block of the 12-geometry MA6 (−45/−15/15/25/45/60°): the colorant
  model, like the face/flop/travel design, depends on the aspecular angle only (its lobes are
  functions of |θ|), so those geometries are evaluated at their aspecular angles too;
* gloss: the colorant model predicts the 60° gloss from the matting fraction,
  :func:`station.formulate.colorants.predict_gloss` (G = 90 − 650 c_matting GU, 5.5–90 GU); the
  gloss-meter simulator reads a panel with that 60° gloss.

A file's other fields (predicted Lab, ``gloss_gu``, ΔE …) are not read: the panel is the recipe.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from station.errors import InputError
from station.formulate.colorants import (
    ColorantDatabase,
    default_database,
    predict_gloss,
    predict_lab,
    predict_reflectance,
)

__all__ = ["RecipeInputError", "RecipePanel", "load_recipe", "recipe_from_json"]

_TOL = 1e-9  # as ColorantDatabase.check: optimiser output may sit on a bound


class RecipeInputError(InputError):
    """A recipe file that cannot define a panel (the field and the accepted range are named)."""


@dataclass(frozen=True)
class RecipePanel:
    """A panel painted with ``recipe`` (``{colorant: mass fraction}``) of database ``db``."""

    recipe: dict[str, float]
    concentrations: NDArray[np.float64]
    db: ColorantDatabase
    name: str = "recipe"

    def reflectance(self, aspecular_deg: Sequence[float]) -> NDArray[np.float64]:
        """Reflectance factors at each aspecular angle (degrees, 45° illumination), shape ``(n, 31)``,
        400–700 nm / 10 nm."""
        return predict_reflectance(self.concentrations, tuple(float(a) for a in aspecular_deg), self.db)

    def lab_at(self, aspecular_deg: Sequence[float]) -> NDArray[np.float64]:
        """Predicted CIE L*a*b* (D65, CIE 1964 10°) at each aspecular angle, shape ``(n, 3)``."""
        return predict_lab(self.concentrations, tuple(float(a) for a in aspecular_deg), self.db)

    @property
    def gloss_gu(self) -> float:
        """Predicted 60° gloss (GU) from the matting fraction."""
        return float(predict_gloss(self.concentrations, self.db))


def recipe_from_json(data: object, db: ColorantDatabase | None = None, name: str = "recipe") -> RecipePanel:
    """Panel from parsed JSON: ``station formulate --json`` output, or its ``"recipe"`` object.

    Raises :class:`RecipeInputError` naming the field (``recipe``, ``recipe.<colorant>``) and the
    accepted range: unknown colorant, a fraction that is not a finite number or lies outside
    0 ≤ c ≤ max_fraction, a total above the database's maximum, too much flake/pearl, an empty recipe.
    """
    db = db or default_database()
    if not isinstance(data, dict):
        raise RecipeInputError(
            "recipe",
            'a JSON object: {"recipe": {colorant: fraction}, ...} or {colorant: fraction}',
            type(data).__name__,
        )
    rec = data["recipe"] if "recipe" in data else data
    if not isinstance(rec, dict):
        raise RecipeInputError("recipe", "an object {colorant: mass fraction}", type(rec).__name__)
    names = db.names
    ub = db.upper_bounds
    c = np.zeros(len(names))
    for key, val in rec.items():
        if key not in names:
            raise RecipeInputError(f"recipe.{key}", f"a colorant of the database ({', '.join(names)})", key)
        i = names.index(key)
        if isinstance(val, bool) or not isinstance(val, int | float) or not math.isfinite(val):
            raise RecipeInputError(f"recipe.{key}", "a finite mass fraction (number)", val)
        if not -_TOL <= val <= ub[i] + _TOL:
            raise RecipeInputError(f"recipe.{key}", f"0 <= fraction <= {ub[i]:g}", val)
        c[i] = min(max(float(val), 0.0), ub[i])
    if not np.any(c > 0):
        raise RecipeInputError("recipe", "at least one colorant with a mass fraction > 0", rec)
    if c.sum() > db.max_total + _TOL:
        raise RecipeInputError("recipe", f"total mass fraction <= {db.max_total:g}", round(float(c.sum()), 6))
    effect = float(c[db.effect_mask].sum())
    if effect > db.max_effect + _TOL:
        raise RecipeInputError(
            "recipe", f"aluminium + pearl + interference fraction <= {db.max_effect:g}", round(effect, 6)
        )
    return RecipePanel(db.recipe(c, threshold=0.0), c, db, name)


def load_recipe(path: str | Path, db: ColorantDatabase | None = None) -> RecipePanel:
    """Read a recipe file (see :func:`recipe_from_json`); unreadable or non-JSON files name ``recipe_file``."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise RecipeInputError(
            "recipe_file", "a readable UTF-8 JSON file", str(path), detail=str(exc)
        ) from exc
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RecipeInputError(
            "recipe_file",
            "JSON (the output of `station formulate --json` or its recipe object)",
            str(path),
            detail=str(exc),
        ) from exc
    design = data.get("design") if isinstance(data, dict) else None
    return recipe_from_json(data, db, name=design if isinstance(design, str) else path.stem)
