"""Anti-aliasing of the GL renderer: a sphere's silhouette against the analytic pixel coverage of a disc.

A Lambertian sphere under a constant environment has one radiance L₀ over its whole disc, so an
anti-aliased edge pixel reads B + c·(L₀ − B) with c the fraction of the pixel the disc covers. The
sphere (radius 1, centred on the optical axis at distance d) projects to a circle of radius tan(asin(1/d))
on the image plane; the covered area of each pixel square is computed in closed form
(:func:`_disc_area_below`, the integral of the disc's chord ∫√(R² − x²) dx). Tolerances: a regular s × s
grid misjudges a straight edge through a pixel by at most 1/s of its area, and such errors of opposite
sign cancel around the circle, so the mean signed error over the edge pixels is held to 0.02 (s = 4).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.render import prefilter
from station.render.camera import Camera
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.gl_renderer import GLRenderer
from station.render.gl_targets import AA_SAMPLES
from station.render.shapes import Scene
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)
SIZE = 32
DISTANCE = 4.0
FOV = 30.0


def _F(x: float, r: float) -> float:
    """∫₀ˣ √(r² − t²) dt (|x| ≤ r)."""
    return 0.5 * (x * math.sqrt(max(r * r - x * x, 0.0)) + r * r * math.asin(x / r))


def _disc_area_below(x: float, y: float, r: float) -> float:
    """Area of the disc of radius *r* at the origin with X ≤ *x* and Y ≤ *y* (closed form)."""
    x = min(max(x, -r), r)
    if y <= -r:
        return 0.0
    if y >= r:
        return 2.0 * (_F(x, r) - _F(-r, r))
    c = math.sqrt(r * r - y * y)

    def chord(a: float, b: float) -> float:  # ∫ₐᵇ √(r² − t²) dt
        return _F(b, r) - _F(a, r) if b > a else 0.0

    def band(a: float, b: float) -> float:  # ∫ₐᵇ (y + √(r² − t²)) dt: the chord cut at Y = y
        return y * (b - a) + chord(a, b) if b > a else 0.0

    inner = band(-c, min(x, c))
    if y < 0.0:
        return inner
    return 2.0 * chord(-r, min(x, -c)) + inner + 2.0 * chord(c, x)


def _coverage(size: int, radius_px: float) -> np.ndarray:
    """(size, size) exact fraction of each pixel covered by a disc at the image centre."""
    cov = np.zeros((size, size))
    h = size / 2.0
    for j in range(size):
        for i in range(size):
            x0, x1, y0, y1 = i - h, i + 1 - h, j - h, j + 1 - h
            cov[j, i] = (
                _disc_area_below(x1, y1, radius_px)
                - _disc_area_below(x0, y1, radius_px)
                - _disc_area_below(x1, y0, radius_px)
                + _disc_area_below(x0, y0, radius_px)
            )
    return cov


@pytest.fixture(scope="module")
def frames(gl_ctx):
    basis = prefilter.prefilter_basis(
        Environment("c", np.full((32, 64, 3), 2.0, np.float32)), EXPS, engine="numpy"
    )
    m = len(EXPS)
    paint = LobeWeights(EXPS, np.array([0.3, 0.3, 0.3]), np.zeros((m, 3)), np.zeros(m))
    scene = Scene("sphere", camera=Camera((0.0, 0.0, DISTANCE), (0.0, 0.0, 0.0), fov_deg=FOV))
    out = {}
    for aa in (1, 16):
        with GLRenderer(basis, SIZE, SIZE, ctx=gl_ctx, aa=aa) as gl:
            out[aa] = (gl.render_linear(scene, [paint, paint])[..., 1], gl.render(scene, [paint, paint]))
    return out


def test_disc_area_closed_form_against_whole_disc_and_quadrant():
    assert _disc_area_below(5.0, 5.0, 2.0) == pytest.approx(math.pi * 4.0, rel=1e-12)
    assert _disc_area_below(0.0, 0.0, 2.0) == pytest.approx(math.pi, rel=1e-12)
    assert _disc_area_below(5.0, 0.0, 1.0) == pytest.approx(math.pi / 2, rel=1e-12)
    # a square pixel well inside, and the total over the pixel grid
    assert _coverage(8, 10.0).sum() == pytest.approx(64.0, rel=1e-12)
    assert _coverage(16, 5.0).sum() == pytest.approx(math.pi * 25.0, rel=1e-9)


def test_edges_take_the_pixel_coverage_of_the_disc(frames):
    no_aa, aa = frames[1][0], frames[16][0]
    background = float(no_aa[0, 0])
    inside = float(no_aa[SIZE // 2, SIZE // 2])
    t = math.tan(math.radians(FOV) / 2.0)
    radius_px = math.tan(math.asin(1.0 / DISTANCE)) / t * SIZE / 2.0
    cov = _coverage(SIZE, radius_px)
    edge = (cov > 0.0) & (cov < 1.0)
    measured = (aa - background) / (inside - background)
    # without anti-aliasing every pixel is background or sphere; with it the edge takes values between
    assert np.all(np.isclose(no_aa, background, atol=1e-4) | np.isclose(no_aa, inside, rtol=1e-4))
    half = (cov > 0.25) & (cov < 0.75)
    assert half.sum() >= 8 and np.all((measured[half] > 0.02) & (measured[half] < 0.98))
    assert abs(float(np.mean(measured[edge] - cov[edge]))) <= 0.02
    assert float(np.max(np.abs(measured[edge] - cov[edge]))) <= 0.25 + 1e-3
    # interior and outside pixels unchanged
    full, empty = cov >= 1.0, cov <= 0.0
    np.testing.assert_allclose(aa[full], no_aa[full], rtol=1e-5)
    np.testing.assert_allclose(aa[empty], no_aa[empty], atol=1e-6)


def test_display_frame_is_resolved_too(frames):
    img1, img16 = frames[1][1].astype(int), frames[16][1].astype(int)
    assert img16.shape == img1.shape == (SIZE, SIZE, 3)
    levels1 = len(np.unique(img1[..., 1]))
    assert len(np.unique(img16[..., 1])) > levels1 + 5
    assert np.array_equal(img16[SIZE // 2, SIZE // 2], img1[SIZE // 2, SIZE // 2])


@pytest.mark.parametrize("aa", [0, 2, 3, 8, 25, 4.0, True])
def test_unsupported_sample_counts_are_refused(gl_ctx, aa):
    basis = prefilter.prefilter_basis(
        Environment("c", np.full((8, 16, 3), 1.0, np.float32)), EXPS, engine="numpy"
    )
    with pytest.raises(RenderInputError) as err:
        GLRenderer(basis, 16, 16, ctx=gl_ctx, aa=aa)
    assert err.value.field == "aa"
    assert aa not in AA_SAMPLES or isinstance(aa, (bool, float))
