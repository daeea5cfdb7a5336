"""What every front exports for a design: the design at both 3-angle sets (optionally 5), and, when a
library is given, its nearest ColorSnap paint (thesis §3.3.3, §3.6); a formulated recipe as a
``prediction`` colour with its recipe and predicted spectra (:func:`recipe_export`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from station.formulate.batch import DEFAULT_BATCH_G
from station.formulate.color_xml import ColorSpec, spec_from_design, spec_from_lab
from station.formulate.colorants import lab_from_reflectance
from station.model import FaceFlopTravelGloss
from station.model.domain import ANGLES_3, ANGLES_3_ALT, ANGLES_5

#: Name of the binder (the base) in an exported recipe.
BINDER_NAME = "binder"

if TYPE_CHECKING:
    from station.formulate.cxf import ObjectExtras
    from station.formulate.formulation import FormulationResult
    from station.formulate.library import Library
    from station.formulate.snap import SnapIndex


def spec_from_library(library: Library, index: int, *, five_angles: bool = False) -> ColorSpec:
    """Library paint *index* as an export spec (role ``match``): its Lab at every library angle, its gloss
    (GU), type, code and the library's synthetic flag."""
    code = str(library.codes[index])
    row = library.lab[index]
    return spec_from_lab(
        code,
        {a: tuple(row[j]) for j, a in enumerate(library.angles_deg)},
        float(library.gloss_gu[index]),
        role="match",
        paint_type=str(library.types[index]),
        code=code,
        synthetic=library.synthetic,
        five_angles=five_angles,
    )


def export_specs(
    design: FaceFlopTravelGloss,
    library: Library | None = None,
    *,
    method: str = "cie76",
    five_angles: bool = False,
    index: SnapIndex | None = None,
) -> tuple[list[ColorSpec], str | None]:
    """The design's spec, then (with *library*) the ColorSnap top-1 match by *method* ΔE summed over
    15°/45°/110° (*index*: a prebuilt index of that library); returns the specs and the match code."""
    from station.formulate.snap import color_snap

    specs = [spec_from_design(design, name=design.name or "design", five_angles=five_angles)]
    if library is None:
        return specs, None
    match = color_snap(library, design.lab_at(np.asarray(ANGLES_3)), k=1, method=method, index=index).matches[
        0
    ]
    specs.append(spec_from_library(library, match.index, five_angles=five_angles))
    return specs, match.code


def recipe_export(
    result: FormulationResult, *, name: str, five_angles: bool = False, batch_g: float = DEFAULT_BATCH_G
) -> tuple[ColorSpec, ObjectExtras]:
    """A formulated recipe as an export colour (role ``prediction``): the colorant model's Lab at both
    3-angle sets (and 5 angles with *five_angles*), and, for CxF3, the recipe weighed out for a batch of
    *batch_g* grams (:func:`station.formulate.batch.batch_masses`; the binder is the base component
    :data:`BINDER_NAME`) with the predicted reflectance per geometry
    (:func:`station.formulate.colorants.predict_reflectance`)."""
    from station.formulate.batch import batch_masses
    from station.formulate.colorants import predict_reflectance
    from station.formulate.cxf import ObjectExtras

    angles = tuple(sorted(set(ANGLES_3) | set(ANGLES_3_ALT) | (set(ANGLES_5) if five_angles else set())))
    refl = predict_reflectance(result.concentrations, angles)
    lab = lab_from_reflectance(refl)
    spec = spec_from_lab(
        name,
        {a: (float(v[0]), float(v[1]), float(v[2])) for a, v in zip(angles, lab, strict=True)},
        result.gloss_gu,
        role="prediction",
        synthetic=result.synthetic,
        five_angles=five_angles,
    )
    batch = batch_masses(result.recipe, batch_g)
    extras = ObjectExtras(
        spectra=tuple((a, tuple(float(x) for x in r)) for a, r in zip(angles, refl, strict=True)),
        recipe=((BINDER_NAME, batch.binder_g), *((k, float(v)) for k, v in batch.colorants_g.items())),
        recipe_units="g",
        binder=BINDER_NAME,
    )
    return spec, extras
