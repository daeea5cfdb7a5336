"""Cached basis images (paint edit = weighted sum) and the aspecular/light-direction buffers."""

from __future__ import annotations

import numpy as np
import pytest

from station.render import basis_images, buffers, prefilter, procedural, shapes, tonemap
from station.render import numpy_renderer as nr
from station.render.errors import RenderInputError
from station.render.weights import LobeWeights

EXPS = (1.0, 16.0, 256.0)


@pytest.fixture(scope="module")
def basis():
    return prefilter.prefilter_basis(procedural.light_booth(128), EXPS, engine="numpy")


def _paint(seed: int) -> LobeWeights:
    rng = np.random.default_rng(seed)
    return LobeWeights(EXPS, rng.random(3) * 0.1, rng.random((3, 3)) * 0.3, rng.random(3))


def test_paint_edit_equals_full_render(basis):
    scene = shapes.Scene("cylinder")
    cache = basis_images.build_basis_images(scene, basis, 40, 30)
    for seed in (1, 2):
        pair = [_paint(seed), _paint(seed + 10)]
        ref = nr.render_linear(scene, basis, pair, 40, 30)
        assert cache.linear_image(pair) == pytest.approx(ref, rel=1e-5, abs=1e-6)
        frame = cache.edit(pair, exposure_ev=-0.5)
        expect = tonemap.to_display(ref, exposure_ev=-0.5)
        # the 64 k-entry LUT quantises the exposed value: at most one code value off
        assert np.abs(frame.astype(int) - expect).max() <= 1
    assert cache.edit_rgba([_paint(3)])[..., 3].min() == 255


def test_paint_edit_in_pixel_blocks_equals_the_full_render(basis, monkeypatch):
    """The edit runs in blocks of EDIT_CHUNK pixels: blocks that straddle the paint split and a short last
    block give the same frame as the full render (tone-mapped independently, at most one code off) and
    as one block over all pixels (bit-equal)."""
    scene = shapes.Scene("sphere")
    pair = [_paint(4), _paint(14)]
    whole = basis_images.build_basis_images(scene, basis, 48, 40)
    assert whole.pixels.size < basis_images.EDIT_CHUNK  # one block
    one_block = whole.edit_rgba(pair, exposure_ev=0.3)
    monkeypatch.setattr(basis_images, "EDIT_CHUNK", 37)
    cache = basis_images.build_basis_images(scene, basis, 48, 40)
    assert cache.split % 37 and cache.pixels.size % 37 and cache.pixels.size > 20 * 37
    frame = cache.edit_rgba(pair, exposure_ev=0.3)
    np.testing.assert_array_equal(frame, one_block)
    expect = tonemap.to_display(nr.render_linear(scene, basis, pair, 48, 40), exposure_ev=0.3)
    assert np.abs(frame[..., :3].astype(int) - expect).max() <= 1
    # a second edit into the same buffer (the viewer's path) overwrites every object pixel
    again = cache.edit_rgba([_paint(5), _paint(15)], exposure_ev=0.3, out=frame.copy())
    ref2 = tonemap.to_display(
        nr.render_linear(scene, basis, [_paint(5), _paint(15)], 48, 40), exposure_ev=0.3
    )
    assert np.abs(again[..., :3].astype(int) - ref2).max() <= 1


@pytest.mark.gl
def test_gl_built_basis_images_match_numpy_built(gl_ctx, basis):
    from station.render.gl_renderer import GLRenderer

    scene = shapes.Scene("sphere")
    a = basis_images.build_basis_images(scene, basis, 32, 32)
    with GLRenderer(basis, 32, 32, ctx=gl_ctx, half_float=False) as gl:
        b = basis_images.build_basis_images(scene, basis, 32, 32, gl_renderer=gl)
    assert np.array_equal(a.pixels, b.pixels)
    # GL filters across cube faces (seamless); NumPy clamps within a face: they differ near face edges
    # of the small, wide-lobe maps only.
    rel = np.abs(b.images - a.images) / (np.abs(a.images) + 1e-3)
    assert np.median(rel) < 0.005 and np.percentile(rel, 99) < 0.08


def test_aspecular_angle_closed_form_on_a_sphere():
    scene = shapes.Scene("sphere", camera=shapes.Camera((0.0, 0.0, 5.0), (0.0, 0.0, 0.0), fov_deg=30))
    g = nr.gbuffer(scene, 41, 41)
    light = np.array([0.0, 0.0, 1.0])  # light behind the camera
    ab = buffers.angle_buffers(g, light)
    # Centre pixel: N = V = L → the specular direction is V: aspecular 0°, incidence 0°.
    assert ab.aspecular_deg[20, 20] == pytest.approx(0.0, abs=0.5)
    assert ab.incidence_deg[20, 20] == pytest.approx(0.0, abs=0.5)
    # Independent check everywhere: aspecular = angle(2(N·L)N − L, V).
    n, v = g.normal[g.mask], g.view[g.mask]
    s = 2 * (n @ light)[:, None] * n - light
    expect = np.degrees(np.arccos(np.clip(np.sum(s * v, -1), -1, 1)))
    assert ab.aspecular_deg[g.mask] == pytest.approx(expect, abs=1e-3)
    assert (ab.aspecular_deg[~g.mask] == 0).all() and np.isfinite(ab.aspecular_deg).all()


def test_light_direction_buffer_and_dominant_light():
    g = nr.gbuffer(shapes.Scene("sphere"), 16, 16)
    assert np.allclose(buffers.light_direction_buffer(g)[g.mask], g.reflect[g.mask])
    assert np.allclose(buffers.light_direction_buffer(g, [0, 2, 0])[g.mask], [0, 1, 0])
    sky = procedural.sunny_sky(256, sun_elevation_deg=40, sun_azimuth_deg=90)
    from station.render.sh import sh_project

    d = buffers.dominant_light_direction(sh_project(sky.equirect))
    sun = procedural.sun_direction(40, 90)
    assert np.degrees(np.arccos(d @ sun)) < 25  # the sky and ground pull it off the sun a little
    with pytest.raises(RenderInputError):
        buffers.angle_buffers(g, [0, 0, 0])
