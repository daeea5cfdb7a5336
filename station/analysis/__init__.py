"""Misalignment analysis (thesis ch. 4): goniogeometric index, seam sweeps, inverse trompe l'oeil, QA.

Plain functions returning dataclasses; the CLI (``station analysis …``) and the service call them.
This package builds on :mod:`station.model` only (it never imports :mod:`station.render`): environment
lighting arrives as plain samples (:class:`Environment`), converted by the caller.
"""

from station.analysis.errors import AnalysisError, AnalysisInputError
from station.analysis.geometry import SeamGeometry, aspecular_deg, direction, rotated_normals
from station.analysis.index import (
    DE_METHODS,
    JND_CIE76,
    GeometryIndex,
    IndexResult,
    SeamModel,
    goniogeometric_index,
)
from station.analysis.qa import SeamReport, as_paint, measurements_under, seam_qa
from station.analysis.shading import Environment, environment_colour, point_colour, shade_lab
from station.analysis.sweep import SweepResult, plot_sweep, seam_sweep
from station.analysis.trompe import OBJECTIVES, SUBSETS, TrompeResult, inverse_trompe_loeil

__all__ = [
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
