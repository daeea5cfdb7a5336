"""The choices and defaults the analysis offers its fronts, in a module that imports nothing heavy, so a
command line can list them (``--help``) without loading colour-science."""

from __future__ import annotations

from typing import Literal

__all__ = ["DEFAULT_ASPECULAR_DEG", "DEFAULT_LIGHTS_DEG", "OBJECTIVES", "Objective"]

#: Default seam-QA geometries: lights 30/45/60° (degrees from the normal) ...
DEFAULT_LIGHTS_DEG = (30.0, 45.0, 60.0)
#: ... and aspecular angles 15–75° (degrees), the range a seam is usually judged over.
DEFAULT_ASPECULAR_DEG = (15.0, 25.0, 45.0, 75.0)

#: What inverse trompe l'oeil minimises: one geometry, the RMS or the maximum over them, or each alone.
Objective = Literal["single", "rms", "minimax", "per_geometry"]
OBJECTIVES: tuple[Objective, ...] = ("single", "rms", "minimax", "per_geometry")
