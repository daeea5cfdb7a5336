"""A recipe's predicted spectra per geometry, from the colorant model (:mod:`station.formulate.colorants`).

A recipe is ``{colorant: mass fraction}`` as the formulation writes it: the ``"recipe"`` key of
``station formulate --json`` output (:meth:`~station.formulate.formulation.FormulationResult.to_dict`) and
of a stored formulation job's ``recipe`` column (``GET /api/v1/recipes/{id}``). Its reflectance per
aspecular angle is :func:`~station.formulate.colorants.predict_reflectance` (R = R_d + R_f) on the
product's 400–700 nm grid at 10 nm, so the light booth can set a predicted trial beside a measured
standard under any illuminant. The colorants are SYNTHETIC (the built-in database).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.formulate.colorants import (
    WAVELENGTHS_NM,
    ColorantDatabase,
    default_database,
    predict_reflectance,
)
from station.formulate.errors import FormulateInputError

__all__ = ["WAVELENGTHS_NM", "is_recipe_document", "recipe_from_document", "recipe_spectra"]


def _fractions(value: Any) -> bool:
    return (
        isinstance(value, Mapping)
        and bool(value)
        and all(
            isinstance(k, str) and isinstance(v, (int, float)) and not isinstance(v, bool)
            for k, v in value.items()
        )
    )


def is_recipe_document(data: Any) -> bool:
    """Whether *data* (parsed JSON) is a recipe: ``{"recipe": {colorant: fraction, …}, …}`` (the
    formulation's output or a stored job's recipe) or a bare ``{colorant: fraction}`` mapping whose
    names are all colorants of the built-in database."""
    if not isinstance(data, Mapping):
        return False
    if "recipe" in data:
        return _fractions(data["recipe"])
    return _fractions(data) and set(data) <= set(default_database().names)


def recipe_from_document(data: Any, where: str = "recipe") -> dict[str, float]:
    """The ``{colorant: fraction}`` of a recipe document (see :func:`is_recipe_document`).

    Raises
    ------
    FormulateInputError
        Naming *where* when *data* holds no recipe (a formulation that found none, a job without one).
    """
    if not is_recipe_document(data):
        raise FormulateInputError(where, 'a recipe: {"recipe": {colorant: mass fraction, ...}}', "no recipe")
    body = data["recipe"] if "recipe" in data else data
    return {str(k): float(v) for k, v in body.items()}


def recipe_spectra(
    recipe: Mapping[str, float],
    aspecular_deg: Sequence[float],
    db: ColorantDatabase | None = None,
    where: str = "recipe",
) -> NDArray[np.float64]:
    """Predicted reflectance of *recipe* at each aspecular angle, shape (n, 31) on 400–700 nm / 10 nm.

    Parameters
    ----------
    recipe
        ``{colorant: mass fraction}`` (fractions 0–1 of the coat; names from *db*).
    aspecular_deg
        Aspecular angles, degrees (45° illumination), at least one.
    db
        The colorant database (the built-in SYNTHETIC one by default).

    Raises
    ------
    FormulateInputError
        An unknown colorant, a fraction outside its bound or a total over the limit (naming *where*),
        or no angle.
    """
    db = db or default_database()
    angles = tuple(float(a) for a in aspecular_deg)
    if not angles or not all(np.isfinite(angles)):
        raise FormulateInputError(
            f"{where}.geometries", "at least one aspecular angle (finite degrees)", angles
        )
    try:
        c = db.check(db.vector(dict(recipe)), where)
    except FormulateInputError as exc:
        raise FormulateInputError(where, exc.accepted, exc.got) from exc
    return np.asarray(predict_reflectance(c, angles, db), dtype=np.float64)
