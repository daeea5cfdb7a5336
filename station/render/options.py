"""The choices the renderer offers its fronts, in a module that imports nothing heavy, so a command line
can list them (``--help``) without loading colour-science."""

from __future__ import annotations

__all__ = ["CURVES", "FRAME_ENGINES"]

#: Tone curves from scene-referred linear RGB to the display (:func:`station.render.tonemap.tone_curve`);
#: the GL renderer indexes its shader's curve by position in this tuple.
CURVES = ("aces", "reinhard", "clip")

#: The renderers a frame may be drawn by (``station.render.scene_image.FrameOptions``; a command line adds
#: ``auto``: the graphics card when there is one); the level of detail judges gl | numpy.
FRAME_ENGINES = ("gl", "numpy", "truth")
