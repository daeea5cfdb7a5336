"""What every front exports for a design: the design at both 3-angle sets (optionally 5), and, when a
library is given, its nearest ColorSnap paint (thesis §3.3.3, §3.6)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from station.formulate.color_xml import ColorSpec, spec_from_design, spec_from_lab
from station.model import FaceFlopTravelGloss
from station.model.domain import ANGLES_3

if TYPE_CHECKING:
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
