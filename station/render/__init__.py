"""Lobe-blend rendering of designed car paints in lighting environments (thesis ch. 2, issue 3).

Environments and renderers (see docs/render.md):

* :mod:`~station.render.hdr_io`, :mod:`~station.render.environment` — .hdr/.exr loading with typed
  errors; :mod:`~station.render.procedural` — booth, sunny sky (Preetham), CIE overcast;
  :mod:`~station.render.cubemap` — cube maps and the direction conventions.
* :mod:`~station.render.prefilter` (+ :mod:`~station.render.sh`, :mod:`~station.render.envcache`) —
  one normalised-Phong-lobe map per exponent, diffuse map, SH irradiance, disk cache.
* :mod:`~station.render.numpy_renderer` (reference) and :mod:`~station.render.gl_renderer` (moderngl,
  EGL) over the analytic :mod:`~station.render.shapes`, with :mod:`~station.render.camera` and
  :mod:`~station.render.tonemap`.
* :mod:`~station.render.basis_images` (cached per-lobe images: paint edits), :mod:`~station.render.buffers`
  (aspecular / light-direction buffers), :mod:`~station.render.anisotropy` (Ward, eqs 2.5.4–2.5.7).

Lobe basis, weight fits, ground truth and level of detail: :mod:`~station.render.lobes`,
:mod:`~station.render.lobe_fit`, :mod:`~station.render.truth`, :mod:`~station.render.lod`;
the hand-off between the two halves is :class:`~station.render.weights.LobeWeights`.
"""
