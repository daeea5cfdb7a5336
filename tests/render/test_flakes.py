"""Metallic flakes: parameters, design files, level of detail, sparkle with the mean colour kept (GL)."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from station.model import FaceFlopTravelGloss
from station.model.colorimetry import linear_srgb_to_lab
from station.model.design_io import default_flakes, flakes_from_dict, load_design_flakes, save_design
from station.model.difference import delta_e
from station.model.errors import ModelInputError
from station.model.flakes import METALLIC_FLAKES, FlakeLayer, sparkle_amplitude
from station.render import flakes as fr
from station.render import prefilter, procedural, shapes
from station.render.camera import Camera

SILVER = FaceFlopTravelGloss((90.0, 0.0, -1.0), (30.0, 0.0, -2.0), 60.0, 88.0, "silver")
SOLID = FaceFlopTravelGloss((50.0, 40.0, 20.0), (50.0, 40.0, 20.0), None, 85.0, "solid red")


def test_layer_validation_and_design_files(tmp_path) -> None:
    for field, bad in (
        ("size_um", 0.0),
        ("density_per_mm2", -1.0),
        ("spread_deg", 90.0),
        ("reflectance", 1.5),
    ):
        with pytest.raises(ModelInputError, match=re.escape(f"flakes.{field}")):
            FlakeLayer(**{field: bad})
    with pytest.raises(ModelInputError, match="flakes"):
        FlakeLayer.from_dict({"size": 3})
    # σ = 8° → reflected spread 16° → E = 1/(2σ)² = 1/0.2793² = 12.8.
    assert METALLIC_FLAKES.reflected_exponent == pytest.approx(1.0 / (2 * math.radians(8.0)) ** 2)
    assert sparkle_amplitude(FlakeLayer(density_per_mm2=400.0), 0.25) == pytest.approx(0.1)  # N = 100
    assert default_flakes(SOLID) is None and default_flakes(SILVER) == METALLIC_FLAKES
    # Files: absent → the paint type's default; null → none; an object → those values (defaults for the rest).
    p = save_design(SILVER, tmp_path / "a.json")
    assert load_design_flakes(p) == (SILVER, METALLIC_FLAKES)
    p = save_design(SILVER, tmp_path / "b.json", flakes=None)
    assert load_design_flakes(p)[1] is None
    p = save_design(SILVER, tmp_path / "c.json", flakes={"size_um": 40.0, "spread_deg": 4.0})
    assert load_design_flakes(p)[1] == FlakeLayer(size_um=40.0, spread_deg=4.0)
    assert json.loads(p.read_text())["flakes"]["size_um"] == 40.0
    with pytest.raises(ModelInputError, match=re.escape("flakes.reflectance")):
        flakes_from_dict({**json.loads(p.read_text()), "flakes": {"reflectance": 2.0}})


def test_level_of_detail_hand_values() -> None:
    cam = Camera((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), fov_deg=30.0)
    # pixel = 2 · 4 · tan 15° / 400 · 100 mm = 0.5359 mm; N = 400 · 0.5359² = 114.9; 1/√N = 9.3 %.
    choice = fr.flake_lod(METALLIC_FLAKES, cam, 400)
    px = 2 * 4 * math.tan(math.radians(15)) / 400 * fr.UNIT_MM
    assert choice.pixel_mm == pytest.approx(px)
    assert choice.flakes_per_pixel == pytest.approx(400 * px * px)
    assert choice.on and "smaller than a pixel" in choice.reason
    # Far away and at low resolution: thousands of flakes per pixel, sparkle under 2 % → off, and said.
    far = fr.flake_lod(METALLIC_FLAKES, cam, 40)
    assert not far.on and far.amplitude < fr.SPARKLE_MIN and "off" in far.reason
    # Close: flakes larger than a pixel, one flake per cell.
    # 200 µm flakes at 25 per mm²: one per 0.2 × 0.2 mm cell (N = 25 · 0.04 = 1).
    close = fr.flake_lod(
        FlakeLayer(size_um=200.0, density_per_mm2=25.0), Camera((0, 0, 0.1), (0, 0, 0), fov_deg=10), 1000
    )
    assert close.on and "larger than a pixel" in close.reason and close.amplitude == pytest.approx(1.0)
    assert fr.flake_lod(None, cam, 400).reason == "no flake layer"


@pytest.fixture(scope="module")
def booth_basis():
    from station.render.lobe_fit import fit_design

    w = fit_design(SILVER)
    return w, prefilter.prefilter_basis(procedural.light_booth(128), w.exponents, max_size=64)


@pytest.mark.gl
@pytest.mark.parametrize("eye", [(0.0, 0.0, 1.2), (0.75, 0.0, 0.85)], ids=["head-on", "45deg"])
def test_sparkle_keeps_the_mean_colour(gl_ctx, booth_basis, eye) -> None:
    """Flakes on vs off: ΔE00 ≤ 0.5 between 16 × 16-pixel averages; visible sparkle pixel to pixel."""
    from station.render.gl_renderer import GLRenderer

    weights, basis = booth_basis
    scene = shapes.Scene("panels", camera=Camera(eye, (-0.5, 0.0, 0.0), fov_deg=20.0))
    layer = FlakeLayer(size_um=30.0, density_per_mm2=60.0, spread_deg=8.0, reflectance=0.6)
    with GLRenderer(basis, 128, 128, ctx=gl_ctx) as gl:
        off = gl.render_linear(scene, [weights]).astype(float)
        on = gl.render_linear(scene, [weights], flakes=layer).astype(float)
        assert gl.last_flakes is not None and gl.last_flakes.on
    block = 16
    inner = slice(16, 112)  # on the left panel
    a = on[inner, inner].reshape(6, block, 6, block, 3).mean(axis=(1, 3)).reshape(-1, 3)
    b = off[inner, inner].reshape(6, block, 6, block, 3).mean(axis=(1, 3)).reshape(-1, 3)
    de = delta_e(linear_srgb_to_lab(a), linear_srgb_to_lab(b), method="cie2000")
    assert de.max() <= 0.5, de.max()
    px = delta_e(
        linear_srgb_to_lab(on[inner, inner].reshape(-1, 3)),
        linear_srgb_to_lab(off[inner, inner].reshape(-1, 3)),
        method="cie2000",
    )
    # sparkle: single pixels differ (the booth is smooth: faint; cells of four pixels or more carry the
    # fluctuation of their flakes, 1/√N of a cell, station.render.flakes.CELL_PIXELS: 0.20–0.25 here, half
    # what cells of two pixels gave)
    assert np.percentile(px, 99) > 0.15


@pytest.mark.gl
def test_sun_glints_and_lod_off(gl_ctx) -> None:
    from station.render.gl_renderer import GLRenderer
    from station.render.lobe_fit import fit_design

    w = fit_design(SILVER)
    basis = prefilter.prefilter_basis(procedural.sunny_sky(128), w.exponents, max_size=32)
    close = shapes.Scene("speedshape", camera=Camera((0.6, 0.35, 1.2), (0.3, 0.0, 0.0), fov_deg=30.0))
    with GLRenderer(basis, 288, 192, ctx=gl_ctx) as gl:  # cells of four pixels: glints need the pixels
        off = gl.render_linear(close, [w])
        on = gl.render_linear(close, [w], flakes=METALLIC_FLAKES)
        assert gl.last_flakes is not None
        assert gl.last_flakes.on
        glints = (on - off).max(axis=-1) > 1.0  # flakes that catch the sun: radiance far above the sky's
        assert 3 <= glints.sum() < 0.2 * glints.size
        far = gl.render_linear(shapes.Scene("speedshape"), [w], flakes=FlakeLayer(density_per_mm2=1e5))
        assert not gl.last_flakes.on and "off" in gl.last_flakes.reason
        np.testing.assert_array_equal(far, gl.render_linear(shapes.Scene("speedshape"), [w]))


@pytest.fixture(scope="module")
def sky_basis():
    from station.render.lobe_fit import fit_design

    w = fit_design(SILVER)
    return w, prefilter.prefilter_basis(procedural.sunny_sky(128), w.exponents, max_size=32)


CLOSE = shapes.Scene("speedshape", camera=Camera((0.6, 0.35, 1.2), (0.3, 0.0, 0.0), fov_deg=30.0))


@pytest.mark.gl
def test_numpy_sparkle_is_the_gl_sparkle(gl_ctx, sky_basis) -> None:
    """The same cells, flake normals and maps: the NumPy sparkle equals the shader's (float32 rounding)."""
    from station.render.gl_renderer import GLRenderer
    from station.render.numpy_renderer import render_linear

    w, basis = sky_basis
    with GLRenderer(basis, 288, 192, ctx=gl_ctx) as gl:
        gl_s = gl.render_linear(CLOSE, [w], flakes=METALLIC_FLAKES) - gl.render_linear(CLOSE, [w])
    np_s = render_linear(CLOSE, basis, [w], 288, 192, flakes=METALLIC_FLAKES) - render_linear(
        CLOSE, basis, [w], 288, 192
    )
    rms = float(np.sqrt(np.mean(np_s**2)))
    assert rms > 0.02  # there is sparkle to compare
    assert np.sqrt(np.mean((gl_s - np_s) ** 2)) < 0.02 * rms
    # the same sun glints (a pixel within float32 rounding of the threshold may fall either side)
    assert not ((gl_s.max(axis=-1) > 1.05) & (np_s.max(axis=-1) < 0.95)).any()
    assert not ((np_s.max(axis=-1) > 1.05) & (gl_s.max(axis=-1) < 0.95)).any()
    assert (gl_s.max(axis=-1) > 1.0).sum() >= 3


def _block_de(on: np.ndarray, off: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CIEDE2000 between 16 × 16-pixel averages and between single pixels, on the left panel."""
    inner = slice(16, 112)
    a = on[inner, inner].reshape(6, 16, 6, 16, 3).mean(axis=(1, 3)).reshape(-1, 3)
    b = off[inner, inner].reshape(6, 16, 6, 16, 3).mean(axis=(1, 3)).reshape(-1, 3)
    block = delta_e(linear_srgb_to_lab(a), linear_srgb_to_lab(b), method="cie2000")
    px = delta_e(
        linear_srgb_to_lab(on[inner, inner].reshape(-1, 3)),
        linear_srgb_to_lab(off[inner, inner].reshape(-1, 3)),
        method="cie2000",
    )
    return block, px


@pytest.mark.parametrize("env", ["booth", "sky"])
@pytest.mark.parametrize("eye", [(0.0, 0.0, 1.2), (0.75, 0.0, 0.85)], ids=["head-on", "45deg"])
def test_numpy_sparkle_keeps_the_mean_colour(booth_basis, sky_basis, env, eye) -> None:
    from station.render.numpy_renderer import render_linear

    weights, basis = booth_basis if env == "booth" else sky_basis
    scene = shapes.Scene("panels", camera=Camera(eye, (-0.5, 0.0, 0.0), fov_deg=20.0))
    layer = FlakeLayer(size_um=30.0, density_per_mm2=60.0, spread_deg=8.0, reflectance=0.6)
    off = render_linear(scene, basis, [weights], 128, 128).astype(float)
    on = render_linear(scene, basis, [weights], 128, 128, flakes=layer).astype(float)
    block, px = _block_de(on, off)
    assert block.max() <= 0.5, block.max()
    assert np.percentile(px, 99) > 0.15  # as in test_sparkle_keeps_the_mean_colour


def test_numpy_level_of_detail_turns_flakes_off(sky_basis) -> None:
    from station.render.numpy_renderer import render_linear

    w, basis = sky_basis
    dense = FlakeLayer(density_per_mm2=1e5)
    far = shapes.Scene("speedshape")
    choice = fr.flake_lod(dense, far.view_camera, 48)
    assert not choice.on and "smaller than a pixel" in choice.reason and "off" in choice.reason
    np.testing.assert_array_equal(
        render_linear(far, basis, [w], 64, 48, flakes=dense), render_linear(far, basis, [w], 64, 48)
    )
    assert fr.flake_lod(METALLIC_FLAKES, CLOSE.view_camera, 64).on


def test_truth_sparkle_has_zero_mean_beside_the_sun() -> None:
    """One normal and view for 40 000 cells, the reflection 6° from the sun: the truth's exact expected
    flake reflection (residual map by stratified normals, the sun in closed form) makes the area mean of
    the sparkle vanish within its sampling error, although single cells glint with the sun."""
    from station.render.cubemap import equirect_directions
    from station.render.truth import prepare_lighting
    from station.render.truth_flakes import flake_sparkle_truth

    env = procedural.sunny_sky(256)
    lum = env.equirect @ np.array([0.2126, 0.7152, 0.0722])
    j, i = np.unravel_index(np.argmax(lum), lum.shape)
    sun = equirect_directions(*lum.shape)[j, i]
    a = math.radians(6.0)
    side = np.cross(sun, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    r = math.cos(a) * sun + math.sin(a) * side  # the mirror direction, 6° off the sun
    v = np.array([0.0, 0.3, 1.0]) / np.linalg.norm([0.0, 0.3, 1.0])
    n = (r + v) / np.linalg.norm(r + v)
    p = 200
    xs, zs = np.meshgrid(np.arange(p), np.arange(p))
    pos = np.stack([xs.ravel() * 0.01, np.zeros(p * p), zs.ravel() * 0.01], axis=-1)  # one 1 mm cell each
    layer = FlakeLayer(size_um=500.0, density_per_mm2=4.0, spread_deg=4.0, reflectance=1.0)  # N = 1
    lighting = prepare_lighting(env)
    assert lighting.point_dirs.shape[0] > 0  # the sun is a point light: its closed form is exercised
    got = flake_sparkle_truth(
        env,
        layer,
        np.ones(3),
        pos,
        np.broadcast_to(n, pos.shape),
        np.broadcast_to(v, pos.shape),
        np.full(p * p, 1e-3),
        0.1,
        100,
        lighting=lighting,
    )
    assert got.max() > 100 * np.abs(got.mean(axis=0)).max()  # single cells catch the sun
    err = got.std(axis=0) / math.sqrt(p * p)
    assert np.all(np.abs(got.mean(axis=0)) < 4.0 * err), (got.mean(axis=0), err)


def test_truth_sparkle_against_the_renderer(sky_basis) -> None:
    """The renderers' sparkle (sharpest map, lobe-map mean) follows the truth's cell by cell; both average
    to the design's colour."""
    from station.render.flakes import flake_tint, sparkle_pixels
    from station.render.numpy_renderer import gbuffer
    from station.render.truth_flakes import flake_sparkle_truth

    w, basis = sky_basis
    layer = FlakeLayer(size_um=30.0, density_per_mm2=60.0, spread_deg=8.0, reflectance=0.6)
    cam = Camera((0.75, 0.0, 0.85), (-0.5, 0.0, 0.0), fov_deg=20.0)
    g = gbuffer(shapes.Scene("panels", camera=cam), 96, 96)
    m = g.mask & (g.paint == 0)
    dist = np.linalg.norm(g.position[m] - np.array(cam.eye), axis=-1)
    tan = math.tan(math.radians(10.0))
    tint = flake_tint(w.map_weights()[1])
    truth = flake_sparkle_truth(
        procedural.sunny_sky(128), layer, tint, g.position[m], g.normal[m], g.view[m], dist, tan, 96
    )
    ours = sparkle_pixels(
        basis, layer, tint, g.position[m], dist, g.normal[m], g.view[m], g.reflect[m], tan, 96
    )
    assert np.corrcoef(truth[:, 1], ours[:, 1])[0, 1] > 0.95
    assert np.sqrt(np.mean((truth - ours) ** 2)) < 0.3 * np.sqrt(np.mean(truth**2))
    assert np.abs(truth.mean(axis=0)).max() < 0.05 * truth.std(axis=0).max()
