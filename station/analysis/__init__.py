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

#: Names loaded on first use (PEP 562): the analysis imports colour-science and SciPy, which take a
#: second or more; its errors and the options its fronts list stay cheap for a command line's ``--help``.
_LAZY = {
    "SeamGeometry": "station.analysis.geometry",
    "aspecular_deg": "station.analysis.geometry",
    "direction": "station.analysis.geometry",
    "rotated_normals": "station.analysis.geometry",
    "DE_METHODS": "station.analysis.seam_model",
    "JND_CIE76": "station.analysis.index",
    "GeometryIndex": "station.analysis.index",
    "IndexResult": "station.analysis.index",
    "SeamModel": "station.analysis.seam_model",
    "goniogeometric_index": "station.analysis.index",
    "SeamReport": "station.analysis.qa",
    "as_paint": "station.analysis.qa",
    "measurements_under": "station.analysis.qa",
    "seam_qa": "station.analysis.qa",
    "Environment": "station.analysis.shading",
    "environment_colour": "station.analysis.shading",
    "point_colour": "station.analysis.shading",
    "shade_lab": "station.analysis.shading",
    "SweepResult": "station.analysis.sweep",
    "plot_sweep": "station.analysis.sweep",
    "seam_sweep": "station.analysis.sweep",
    "SUBSETS": "station.analysis.trompe",
    "TrompeResult": "station.analysis.trompe",
    "inverse_trompe_loeil": "station.analysis.trompe",
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
