"""The choices the renderer offers its fronts, in a module that imports nothing heavy, so a command line
can list them (``--help``) without loading colour-science."""

from __future__ import annotations

__all__ = ["CURVES"]

#: Tone curves from scene-referred linear RGB to the display (:func:`station.render.tonemap.tone_curve`);
#: the GL renderer indexes its shader's curve by position in this tuple.
CURVES = ("aces", "reinhard", "clip")
