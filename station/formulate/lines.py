"""Toner lines: which colorants a recipe may use, chosen by the design's paint type (SYNTHETIC DATA).

A paint shop mixes a solid from a solid line and an effect paint from a metallic or pearl line; a solid
never receives aluminium, pearl or interference pigment. The lines, as families of the colorant
database, and an invented price per kg of every colorant and of the binder are data, in
``station/formulate/data/toner_lines.json``; the line names are :data:`station.model.domain.TONER_LINES`.

When no line is named the design's type picks it (:func:`lines_for_design`): a design whose colour
does not change with the angle (largest CIEDE2000 between its angles at most
:data:`SOLID_SPREAD_DE00`) is a solid; any other design is tried with the metallic line and, if that
cannot reach it, with the pearl line.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.colorants import ColorantDatabase
from station.formulate.de_kernels import cie2000
from station.formulate.errors import FormulateInputError
from station.model.domain import TONER_LINES

#: Largest CIEDE2000 between a design's angles for it to count as a solid (a solid in this colorant
#: model reads the same at every angle; 2 ΔE00 leaves room for measurement noise and small edits).
SOLID_SPREAD_DE00 = 2.0
#: Paint types of the libraries, mapped to the lines tried in order (a metallic the metallic line
#: cannot reach is tried with the pearl line, which adds pearl and interference pigments to it).
LINES_OF_TYPE: dict[str, tuple[str, ...]] = {
    "solid": ("solid",),
    "metallic": ("metallic", "pearl"),
    "pearl": ("pearl",),
}


@dataclass(frozen=True)
class TonerLine:
    """A toner line: its name, the colorant families it may use and what it is for."""

    name: str
    families: tuple[str, ...]
    doc: str

    def mask(self, db: ColorantDatabase) -> NDArray[np.bool_]:
        """Which colorants of *db* this line may use (the matting agent never: gloss sets it)."""
        return np.array([c.family in self.families and c.family != "matting" for c in db.colorants])


@functools.lru_cache(maxsize=1)
def _data() -> dict[str, Any]:
    text = resources.files("station.formulate").joinpath("data", "toner_lines.json").read_text("utf-8")
    data: dict[str, Any] = json.loads(text)
    return data


def toner_line(name: str) -> TonerLine:
    """The toner line called *name* (one of :data:`~station.model.domain.TONER_LINES`)."""
    if name not in TONER_LINES:
        raise FormulateInputError("line", f"one of {', '.join(TONER_LINES)}", name)
    rec = _data()["lines"][name]
    return TonerLine(name, tuple(rec["families"]), str(rec["doc"]))


def cost_per_kg(concentrations: ArrayLike, db: ColorantDatabase) -> float:
    """Price of 1 kg of paint of this recipe (mass fractions in *db* order): Σ c_i p_i + (1 − Σ c_i) p_binder
    with the invented prices of the data file (a tie-breaker between recipes, not a quotation)."""
    prices = _data()["cost_per_kg"]
    c = np.asarray(concentrations, dtype=np.float64)
    p = np.array([float(prices[n]) for n in db.names])
    return float(c @ p + max(0.0, 1.0 - float(c.sum())) * float(prices["binder"]))


def is_solid_design(design_lab: NDArray[np.float64]) -> bool:
    """True when the design's colour barely changes with the angle (see :data:`SOLID_SPREAD_DE00`)."""
    lab = np.asarray(design_lab, dtype=np.float64)
    spread = cie2000(lab[:, None, :], lab[None, :, :])
    return bool(np.max(spread) <= SOLID_SPREAD_DE00)


def lines_for_design(
    design_lab: NDArray[np.float64], line: str | None = None, paint_type: str | None = None
) -> tuple[str, ...]:
    """The lines to try, in order, until one reaches the design: the named *line*; else the lines of
    *paint_type* (:data:`LINES_OF_TYPE`); else those of the design's own type (module docstring)."""
    if line is not None:
        return (toner_line(line).name,)
    if paint_type is not None:
        if paint_type not in LINES_OF_TYPE:
            raise FormulateInputError("paint_type", f"one of {', '.join(LINES_OF_TYPE)}", paint_type)
        return LINES_OF_TYPE[paint_type]
    return LINES_OF_TYPE["solid" if is_solid_design(design_lab) else "metallic"]
