"""The choices the styling tools offer their fronts, in a module that imports nothing heavy, so a command
line can list them (``--help``) without loading colour-science."""

from __future__ import annotations

from typing import Literal

__all__ = ["CATEGORIES", "GLOSS_MODES", "SCENE_NAMES", "Category"]

#: Gloss modes of :func:`station.design.sketch.fit_point_light` (that module's docstring).
GLOSS_MODES = ("highlight", "contrast", "default", "fit")
#: The rings of the variations tool (§3.4.4): face colour, flop colour, travel and gloss.
Category = Literal["face", "flop", "travel-gloss"]
CATEGORIES: tuple[Category, ...] = ("face", "flop", "travel-gloss")
#: The built-in point-lit scenes (:data:`station.design.scene.BUILTIN_SCENES` builds them by these names).
SCENE_NAMES = ("sphere-point", "panel-point")
