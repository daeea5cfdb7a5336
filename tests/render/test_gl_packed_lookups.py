"""The GL frame's packed lookups: the horizon table's rows of g alone (four wide lobes a lookup) and the
clear coat's diffuse base pre-mixed per paint into one atlas (one lookup instead of two) draw what the
per-lobe, per-map lookups draw, checked against a closed form, the NumPy renderer and the GL renderer
without the pre-summed maps."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from station.model.fresnel import ClearCoat
from station.render import gl_textures as tx
from station.render import numpy_renderer as nr
from station.render import prefilter, procedural, shapes
from station.render.environment import Environment
from station.render.weights import LobeWeights
from tests.render.test_renderers import EXPS
from tests.render.test_renderers import _weights as lobe_weights

assert EXPS == (1.0, 8.0, 64.0, 512.0)  # three wide lobes (horizon table, bound first) and a narrow one
SIZE = 40
RADIANCE = 2.0


def _weights(k_d, k_dd=None, k_g=None, k_a=(0.0, 0.0, 0.0)) -> LobeWeights:
    """test_renderers' paint of EXPS's lobes, with an aspecular fall-off K_A."""
    return dataclasses.replace(lobe_weights(k_d, k_dd, k_g), k_a=np.array(k_a, float))


@pytest.fixture(scope="module")
def const_basis():
    return prefilter.prefilter_basis(
        Environment("c", np.full((32, 64, 3), RADIANCE, np.float32)), EXPS, engine="numpy"
    )


@pytest.fixture(scope="module")
def sky_basis():
    return prefilter.prefilter_basis(procedural.sunny_sky(256), EXPS)


@pytest.mark.gl
def test_horizon_texture_holds_g_rows_then_pair_rows(gl_ctx) -> None:
    """Rows 0..⌈m/4⌉−1: g of lobes 4k..4k+3 in RGBA; then (g, h) of lobes 2k, 2k+1 in (.rg, .ba);
    read back texel by texel against the table itself."""
    rng = np.random.default_rng(7)
    m, n = 5, 9
    table = rng.random((m, n, 2)).astype(np.float32)
    tex = tx.horizon_texture(gl_ctx, table)
    try:
        rows = np.frombuffer(tex.read(), np.float32).reshape(tex.height, n, 4)
    finally:
        tex.release()
    assert rows.shape[0] == 2 + 3  # ⌈5/4⌉ rows of g, ⌈5/2⌉ rows of pairs
    for i in range(m):
        assert np.array_equal(rows[i // 4, :, i % 4], table[i, :, 0])
        assert np.array_equal(rows[2 + i // 2, :, 2 * (i % 2) : 2 * (i % 2) + 2], table[i])
    assert np.all(rows[1, :, 1:] == 0.0) and np.all(rows[4, :, 2:] == 0.0)  # the unused slots


@pytest.mark.gl
def test_coated_diffuse_base_of_two_paints_is_the_closed_form(gl_ctx, const_basis) -> None:
    """In a furnace of radiance L a Lambertian base ρ under the coat sends (1 − F(N·V)) ρ L (the coat map
    of a uniform environment is the environment: its entry weight's cosine mean is 1); each half of the
    sphere has its own paint, so the atlas's two tiles are both checked."""
    from station.render.gl_renderer import GLRenderer

    rho = (np.array([0.8, 0.5, 0.2]), np.array([0.1, 0.4, 0.7]))
    pair = [_weights(r / np.pi) for r in rho]
    scene = shapes.Scene("sphere")
    g = nr.gbuffer(scene, SIZE, SIZE)
    coat = ClearCoat()
    with GLRenderer(const_basis, SIZE, SIZE, ctx=gl_ctx) as gl:
        img = gl.render_linear(scene, pair, coat=coat)
    for p in (0, 1):
        sel = g.mask & (g.paint == p)
        assert sel.sum() > 100
        expect = coat.base_scale(g.n_dot_v[sel])[:, None] * rho[p] * RADIANCE
        assert img[sel] == pytest.approx(expect, rel=5e-3, abs=2e-3)


#: Wide-lobe gloss weights (bound order: lobes 0, 1, 2 wide; 3 narrow): none (g from the row of g alone),
#: one lobe of a pair (that pair row read), the odd lobe (its pair row alone), every lobe.
GLOSS = {
    "none": [0.0, 0.0, 0.0, 3.0],
    "lobe 0": [0.3, 0.0, 0.0, 3.0],
    "lobe 1": [0.0, 0.6, 0.0, 3.0],
    "lobe 2": [0.0, 0.0, 2.0, 3.0],
    "all": [0.3, 0.6, 2.0, 3.0],
}
DD = [[0.2, 0.05, 0.03], [0.5, 0.1, 0.05], [1.0, 0.3, 0.1], [0.0, 0.0, 0.0]]


@pytest.mark.gl
@pytest.mark.parametrize("gloss", list(GLOSS))
@pytest.mark.parametrize("coated", [False, True])
def test_packed_horizon_rows_draw_numpys_frame_in_a_furnace(
    gl_ctx, const_basis, gloss: str, coated: bool
) -> None:
    """Every mix of wide lobes with and without gloss reads its (g, h) from the right row: the GL frame
    equals the NumPy renderer's, which interpolates the horizon table itself, in a uniform environment
    (no lights, no sun: the maps are constant, so only the horizon factors shape the frame)."""
    from station.render.gl_renderer import GLRenderer

    a = _weights((0.05, 0.03, 0.02), DD, GLOSS[gloss])
    b = _weights((0.02, 0.03, 0.05), [list(reversed(row)) for row in DD], GLOSS[gloss])
    scene = shapes.Scene("sphere")
    coat = ClearCoat() if coated else None
    g = nr.gbuffer(scene, SIZE, SIZE)
    with GLRenderer(const_basis, SIZE, SIZE, ctx=gl_ctx) as gl:
        img = gl.render_linear(scene, [a, b], coat=coat)[g.mask]
    ref = nr.render_linear(scene, const_basis, [a, b], SIZE, SIZE, coat=coat)[g.mask]
    assert img == pytest.approx(ref, rel=5e-3, abs=2e-3)
    # the dd terms shape the frame: without their horizon factors it would differ by far more
    flat = nr.render_linear(scene, const_basis, [a, b], SIZE, SIZE, horizon="none", coat=coat)[g.mask]
    assert np.abs(flat - ref).max() > 0.05


@pytest.mark.gl
@pytest.mark.parametrize("horizon", ["lut", "none"])
def test_coated_frame_with_the_premixed_base_is_the_per_map_frame(gl_ctx, sky_basis, horizon: str) -> None:
    """Under the sky and its sun, with a coat and K_A (its fall-off compiled in with the horizon tables,
    where the base reads both maps; without them the atlas holds π K_A D + π K_D D_coat), two paints:
    the GL frame with the pre-summed maps against the one looking up every lobe and map per pixel."""
    from station.render.gl_renderer import GLRenderer

    a = _weights((0.1, 0.03, 0.02), DD, GLOSS["lobe 1"], k_a=(0.05, 0.02, 0.01))
    b = _weights((0.02, 0.03, 0.1), [list(reversed(row)) for row in DD], GLOSS["none"])
    scene = shapes.Scene("sphere")
    coat = ClearCoat(1.6)
    with (
        GLRenderer(sky_basis, 48, 48, ctx=gl_ctx, horizon=horizon) as packed,
        GLRenderer(sky_basis, 48, 48, ctx=gl_ctx, horizon=horizon, combined=False) as per_map,
    ):
        img = packed.render_linear(scene, [a, b], coat=coat)
        ref = per_map.render_linear(scene, [a, b], coat=coat)
        no_coat = per_map.render_linear(scene, [a, b])
    g = nr.gbuffer(scene, 48, 48)
    # combined maps resample the smaller maps at the larger size (bilinear of bilinear), as without a coat
    assert img[g.mask] == pytest.approx(ref[g.mask], rel=0.02, abs=2e-3)
    assert np.abs(ref[g.mask] - no_coat[g.mask]).max() > 0.02  # the coat changes the frame
