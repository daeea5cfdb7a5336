"""The virtual light booth: adapted paint colour, the light's tint, cached views, the car's probed basis."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from station.errors import InputError
from station.model.booth import metameric_pair
from station.model.domain import ANGLES_5
from station.model.examples import RED_METALLIC, SILVER
from station.model.spectra import reflectance_from_lab, reflectance_to_lab
from station.render import booth
from station.render.errors import RenderInputError

ANGLES = ANGLES_5
SIZE = 96


@pytest.fixture(scope="module")
def pair() -> tuple[booth.BoothPaint, booth.BoothPaint]:
    std, smp = metameric_pair(reflectance_from_lab(SILVER.lab_at(ANGLES)), strength=0.3)
    return booth.BoothPaint(ANGLES, std, 85.0, "standard"), booth.BoothPaint(ANGLES, smp, 85.0, "trial")


@pytest.fixture(scope="module")
def renderer() -> booth.BoothRenderer:
    return booth.BoothRenderer(SIZE)


def test_grey_looks_grey_to_the_adapted_observer() -> None:
    grey = np.full((1, 31), 0.5)
    expected_l = 116.0 * 0.5 ** (1.0 / 3.0) - 16.0  # CIE L* of Y = 0.5, closed form
    for ill in ("D65", "A", "F11", "LED-B4"):
        lab = booth.adapted_lab(grey, ill)[0]
        assert lab[0] == pytest.approx(expected_l, abs=0.05)
        assert np.hypot(lab[1], lab[2]) < 0.3, ill


def test_adapted_lab_is_the_d65_colour_under_d65() -> None:
    sp = reflectance_from_lab(RED_METALLIC.lab_at(ANGLES))
    np.testing.assert_allclose(booth.adapted_lab(sp, "D65"), reflectance_to_lab(sp, "D65"), atol=1e-9)


def test_light_tint_d65_neutral_a_warm_luminance_one() -> None:
    np.testing.assert_allclose(booth.light_tint("D65"), 1.0, atol=1e-9)
    lum = np.array([0.2126, 0.7152, 0.0722])
    for ill in ("A", "F11", "D50"):
        t = booth.light_tint(ill)
        assert t @ lum == pytest.approx(1.0, abs=1e-9)
        assert t[0] > t[1] > t[2], ill  # all warmer than daylight
    a = booth.light_tint("A")
    assert a[0] / a[2] > booth.light_tint("D50")[0] / booth.light_tint("D50")[2]
    np.testing.assert_allclose(booth.light_tint("A", degree=1.0), 1.0, atol=1e-9)  # fully adapted: no tint
    # Less adaptation, warmer; none: near the light's own colour (A's white over D65's in linear sRGB,
    # colour-science; the two-step CAT16 keeps its equal-energy baseline, hence 10 %).
    import colour

    xyz_a = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1964 10 Degree Standard Observer"]["A"])
    xyz_d = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1964 10 Degree Standard Observer"]["D65"])
    m = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    ratio = (m @ xyz_a) / (m @ xyz_d)
    t0 = booth.light_tint("A", degree=0.0)
    assert t0[2] / t0[0] == pytest.approx(ratio[2] / ratio[0], rel=0.1)
    b_over_r = [
        booth.light_tint("A", degree=d)[2] / booth.light_tint("A", degree=d)[0] for d in (0, 0.5, 0.9)
    ]
    assert b_over_r == sorted(b_over_r)


def test_degree_of_adaptation_closed_form() -> None:
    assert booth.degree_of_adaptation(20.0) == pytest.approx(1 - np.exp(-62 / 92) / 3.6)
    assert booth.degree_of_adaptation(1e6) == pytest.approx(1.0)


def test_metameric_pair_designs_equal_under_d65_differ_under_a(pair) -> None:
    std, smp = pair
    d_std, d_smp = booth.booth_design(std, "D65"), booth.booth_design(smp, "D65")
    np.testing.assert_allclose(d_std.lab_at(ANGLES), d_smp.lab_at(ANGLES), atol=1e-6)
    a_std, a_smp = booth.booth_design(std, "A"), booth.booth_design(smp, "A")
    assert np.abs(a_std.lab_at(ANGLES) - a_smp.lab_at(ANGLES)).max() > 2.0


def test_frame_halves_match_under_d65_and_not_under_a(renderer, pair) -> None:
    """Same paint on both panels gives the same picture as the pair under D65 (they are metamers)."""
    std, smp = pair
    same = renderer.frame(std, std, "D65", shape="panels").image.astype(int)
    d65 = renderer.frame(std, smp, "D65", shape="panels").image.astype(int)
    assert np.abs(same - d65).max() <= 1
    same_a = renderer.frame(std, std, "A", shape="panels").image.astype(int)
    pair_a = renderer.frame(std, smp, "A", shape="panels").image.astype(int)
    assert np.abs(same_a - pair_a).max() > 5


def test_switch_reuses_the_cached_view(renderer, pair) -> None:
    std, smp = pair
    view = renderer.view("seam")
    assert renderer.cached("seam")
    first = renderer.frame(std, smp, "D65", shape="seam")
    second = renderer.frame(std, smp, "F11", shape="seam")
    assert renderer.view("seam") is view
    assert not np.array_equal(first.image, second.image)
    assert second.seconds < 2.0  # fits and one weighted sum (bench/booth.py measures ≤ 0.5 s)


def test_frame_is_linear_render_times_tint(renderer, pair) -> None:
    """The booth frame equals the NumPy renderer's picture of the fitted paints, tinted, tone-mapped."""
    from station.render import lobe_fit, tonemap
    from station.render.lobes import default_basis
    from station.render.numpy_renderer import render_linear
    from station.render.shapes import Scene
    from station.render.stage import Stage

    std, smp = pair
    f = renderer.frame(std, smp, "A", shape="panels")
    paints = [lobe_fit.fit_design(d, default_basis()) for d in f.designs]
    linear = render_linear(Scene("panels", stage=Stage()), renderer.basis, paints, SIZE, SIZE)
    expected = tonemap.to_display(linear * booth.light_tint("A").astype(np.float32), 0.0)
    assert np.abs(f.image.astype(int) - expected.astype(int)).max() <= 2


@pytest.mark.gl
def test_car_basis_images_equal_a_direct_gl_render(gl_ctx, pair) -> None:
    from station.render import lobe_fit
    from station.render.gl_renderer import GLRenderer
    from station.render.lobes import default_basis
    from station.render.scene_image import builtin_mesh
    from station.render.stage import Stage

    r = booth.BoothRenderer(SIZE, gl_ctx=gl_ctx)
    std, smp = pair
    f = r.frame(std, smp, "A", shape="car")
    paints = [lobe_fit.fit_design(d, default_basis()) for d in f.designs]
    with GLRenderer(r.basis, SIZE, SIZE, ctx=gl_ctx) as gl:
        direct = gl.render_mesh(builtin_mesh("car"), paints, stage=Stage(), linear=True)
    cached = r.view("car").linear_image(paints)
    assert np.abs(cached - direct).max() < 2e-3 * max(1.0, float(direct.max()))
    view = r.view("car")
    assert 0 < view.split < view.pixels.size  # both halves on the picture


def test_render_booth_png_writes_the_picture(tmp_path, renderer, pair) -> None:
    std, smp = pair
    out = booth.render_booth_png(
        std, smp, "F11", shape="panels", out_path=tmp_path / "b.png", renderer=renderer
    )
    with Image.open(out) as im:
        assert im.size == (SIZE, SIZE) and im.mode == "RGB"
    strip = booth.booth_strip(std, smp, ["D65", "A"], renderer=renderer)
    assert strip.shape == (SIZE, 2 * SIZE, 3)


def test_bad_input_names_the_field(renderer, pair) -> None:
    std, _ = pair
    cases = [
        (lambda: renderer.view("cube"), "shape"),
        (lambda: booth.BoothRenderer(8), "size"),
        (lambda: booth.BoothPaint(ANGLES, np.ones((5, 30))), "paint.spectra"),
        (lambda: booth.BoothPaint((15.0, 45.0), np.ones((2, 31)), name="std"), "std.geometries"),
        (lambda: booth.light_tint("A", degree=1.5), "degree"),
        (lambda: booth.booth_strip(std, std, [], renderer=renderer), "illuminants"),
        (lambda: booth.write_png(np.zeros((4, 4, 3), np.uint8), "/nonexistent-dir/x.png"), "out"),
    ]
    for call, field in cases:
        with pytest.raises(RenderInputError) as err:
            call()
        assert err.value.field == field
    with pytest.raises(InputError) as bad:
        renderer.frame(std, std, "Z99", shape="panels")
    assert "illuminant" in str(bad.value)


@pytest.mark.gl
def test_isolated_car_images_equal_the_in_process_ones(gl_ctx, renderer) -> None:
    """The viewer's path (a spawned process draws the car) gives the same basis images."""
    here = booth.mesh_basis_images(renderer.basis, SIZE, gl_ctx)
    there = booth.BoothRenderer(SIZE, basis=renderer.basis, isolate_gl=True).view("car")
    np.testing.assert_array_equal(here.pixels, there.pixels)
    assert here.split == there.split and here.layout == there.layout
    np.testing.assert_allclose(here.images, there.images, atol=1e-5)
