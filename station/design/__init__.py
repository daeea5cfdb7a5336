"""Colour styling tools (thesis ch. 3, §3.4–§3.7).

Modules
-------
- :mod:`.scene` — a small NumPy point-light / environment scene generator and the per-pixel buffers
  (aspecular angle, Lambert term, normals, light direction, foreground mask) the other tools take.
- :mod:`.designer` — data-point editor, hue/saturation/brightness, face/flop/travel picker, gloss (§3.4.1–§3.4.5).
- :mod:`.variations` — the variations ring (§3.4.4).
- :mod:`.palette` — palette swatch and booklet thumbnail (§3.4.6).
- :mod:`.images` — safe PNG/JPEG loading with colour management.
- :mod:`.moodboard` — boards, face/flop/gloss eyedroppers (§3.5).
- :mod:`.tweaker` — the image-based BRDF tweaker (§3.6, docs/design.md erratum 1).
- :mod:`.sketch` — sketch fits under a point light and under environment lighting (§3.7).
- :mod:`.artwork` — synthetic concept-art edits and perturbations (tests, benchmarks).

Every operation takes plain NumPy buffers and immutable designs
(:class:`station.model.FaceFlopTravelGloss`) and returns a new design; nothing imports the renderer.
"""
