"""Misalignment analysis (thesis ch. 4): goniogeometric index, seam sweeps, inverse trompe l'oeil, QA.

Plain functions returning dataclasses; the CLI (``station analysis …``) and the service call them.
This package builds on :mod:`station.model` only (it never imports :mod:`station.render`): environment
lighting arrives as plain samples (:class:`Environment`), converted by the caller.
"""

from typing import TYPE_CHECKING

from station.analysis.errors import AnalysisError, AnalysisInputError
from station.analysis.options import DEFAULT_ASPECULAR_DEG, DEFAULT_LIGHTS_DEG, OBJECTIVES
from station.lazy import lazy_getattr

if TYPE_CHECKING:
    from station.analysis.geometry import SeamGeometry, aspecular_deg, direction, rotated_normals
    from station.analysis.index import JND_CIE76, GeometryIndex, IndexResult, goniogeometric_index
    from station.analysis.qa import SeamReport, as_paint, measurements_under, seam_qa
    from station.analysis.seam_model import DE_METHODS, SeamModel
    from station.analysis.shading import Environment, environment_colour, point_colour, shade_lab
    from station.analysis.sweep import SweepResult, plot_sweep, seam_sweep
    from station.analysis.trompe import SUBSETS, TrompeResult, inverse_trompe_loeil

#: Names loaded on first use (PEP 562), by module: the analysis imports colour-science and SciPy, which
#: take a second or more; its errors and the options its fronts list stay cheap for a command line's
#: ``--help``.
_LAZY = {
    "station.analysis.geometry": ("SeamGeometry", "aspecular_deg", "direction", "rotated_normals"),
    "station.analysis.seam_model": ("DE_METHODS", "SeamModel"),
    "station.analysis.index": ("JND_CIE76", "GeometryIndex", "IndexResult", "goniogeometric_index"),
    "station.analysis.qa": ("SeamReport", "as_paint", "measurements_under", "seam_qa"),
    "station.analysis.shading": ("Environment", "environment_colour", "point_colour", "shade_lab"),
    "station.analysis.sweep": ("SweepResult", "plot_sweep", "seam_sweep"),
    "station.analysis.trompe": ("SUBSETS", "TrompeResult", "inverse_trompe_loeil"),
}

__getattr__ = lazy_getattr(__name__, _LAZY)


__all__ = [
    "DEFAULT_ASPECULAR_DEG",
    "DEFAULT_LIGHTS_DEG",
    "DE_METHODS",
    "JND_CIE76",
    "OBJECTIVES",
    "SUBSETS",
    "AnalysisError",
    "AnalysisInputError",
    "Environment",
    "GeometryIndex",
    "IndexResult",
    "SeamGeometry",
    "SeamModel",
    "SeamReport",
    "SweepResult",
    "TrompeResult",
    "as_paint",
    "aspecular_deg",
    "direction",
    "environment_colour",
    "goniogeometric_index",
    "inverse_trompe_loeil",
    "measurements_under",
    "plot_sweep",
    "point_colour",
    "rotated_normals",
    "seam_qa",
    "seam_sweep",
    "shade_lab",
]
