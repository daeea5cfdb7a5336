"""The chemist's work on a design, as ``station snap`` / ``station formulate [--closed-loop]`` /
``station export`` do it (Qt-free; the screen runs these calls in a worker thread).

ColorSnap searches the library restricted to the chosen paint types (solid, metallic, pearl: the
library paint's ``type``); the recipe is formulated from the best matches' recipes
(``station.formulate.formulate_from_library``) and shown per colorant as mass fraction and as mass for
a batch; the closed loop sprays, measures (the SYNTHETIC spray-out panel model) and corrects until the
panel is within tolerance. The demo library and colorants are SYNTHETIC and every result says so.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from station.errors import InputError
from station.formulate.batch import DEFAULT_BATCH_G
from station.formulate.library import PAINT_TYPES, Library
from station.model import FaceFlopTravelGloss
from station.model.domain import ANGLES_3

BATCH_G_DEFAULT = DEFAULT_BATCH_G
"""Default batch size, grams (the CLI's and the service's)."""
BATCH_G_RANGE = (1.0, 1_000_000.0)
"""Batch sizes the screen's spin box offers, grams (the core accepts 0 < batch ≤ 1e6 g)."""
SPRAY_SEED = 7
"""Seed of the simulated spray-out panel (as ``station formulate --closed-loop``)."""


def filtered(library: Library, types: Iterable[str]) -> Library:
    """The paints of *library* whose type is one of *types*; :class:`InputError` naming ``types``
    when none is chosen or one is not a paint type."""
    chosen = sorted(set(types))
    bad = [t for t in chosen if t not in PAINT_TYPES]
    if not chosen or bad:
        raise InputError("types", f"one or more of {', '.join(PAINT_TYPES)}", chosen)
    if set(chosen) == set(PAINT_TYPES):
        return library
    sub = library.subset(np.isin(library.types, chosen), name=f"{library.name} ({'+'.join(chosen)})")
    if len(sub) == 0:
        raise InputError(
            "types", f"types the library holds ({', '.join(sorted(set(library.types)))})", chosen
        )
    return sub


def batch_rows(recipe: dict[str, float], batch_g: float) -> list[tuple[str, float, float]]:
    """(component, mass fraction, grams in a *batch_g* batch): the colorants, largest first, then the
    binder (``station.formulate.batch.batch_masses``: m_i = c_i·M, the binder the rest)."""
    from station.formulate.batch import batch_masses

    b = batch_masses(recipe, batch_g)  # FormulateInputError naming batch_g outside 0 < batch ≤ 1e6 g
    rows = [(name, recipe[name], b.colorants_g[name]) for name in sorted(recipe, key=lambda k: -recipe[k])]
    return [*rows, ("binder", b.binder_g / b.total_g, b.binder_g)]


@dataclass(frozen=True)
class Formulation:
    """A formulation of one design against a filtered library: ColorSnap result and recipe."""

    design: FaceFlopTravelGloss
    library: Library
    snap: Any  # station.formulate.SnapResult
    result: Any  # station.formulate.FormulationResult


def snap(design: FaceFlopTravelGloss, library: Library, k: int = 5) -> Any:
    """ColorSnap (CIEDE2000, as the formulation uses) of *design* at 15/45/110° in *library*."""
    from station.formulate.snap import color_snap

    return color_snap(library, design.lab_at(np.array(ANGLES_3)), k=k, method="cie2000")


def formulate(design: FaceFlopTravelGloss, library: Library) -> Formulation:
    """The recipe from the ColorSnap matches' recipes (``formulate_from_library``)."""
    from station.formulate.formulation import formulate_from_library

    result, found = formulate_from_library(
        design.lab_at(np.array(ANGLES_3)), library, gloss_gu=design.gloss_gu
    )
    return Formulation(design, library, found, result)


def closed_loop(f: Formulation, seed: int = SPRAY_SEED) -> Any:
    """Spray, measure and correct (``station.formulate.closed_loop`` on the SYNTHETIC spray-out model)."""
    from station.formulate.closed_loop import closed_loop as run
    from station.formulate.sprayout import SprayOutModel

    spray = SprayOutModel(seed=seed)
    recipes = f.library.recipes
    if recipes is None:
        raise InputError("library", "a library with recipes (e.g. the demo library)", f.library.name)
    starts = [(m.code, recipes[m.index]) for m in f.snap.matches]
    return run(
        f.design.lab_at(np.array(ANGLES_3)),
        spray.measure,
        starts=starts,
        gloss_gu=f.design.gloss_gu,
        tolerance=f.result.tolerance,
    )


def export(design: FaceFlopTravelGloss, library: Library, path: Path) -> tuple[Path, str | None]:
    """Write the design and its ColorSnap match as thesis XML (``.xml``) or CxF3 (``.cxf``); returns the
    path and the match code."""
    from station.formulate.color_xml import write_color_xml
    from station.formulate.cxf import specs_to_cxf
    from station.formulate.export import export_specs

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".xml", ".cxf"):
        raise InputError("file", "a name ending in .xml (thesis XML) or .cxf (CxF3)", path.name)
    specs, code = export_specs(design, library, method="cie76")
    if suffix == ".xml":
        write_color_xml(specs, path)
    else:
        path.write_bytes(specs_to_cxf(specs))
    return path, code
