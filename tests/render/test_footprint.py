"""The shape's screen footprint (station.render.footprint): the polygon holds every pixel the NumPy ray
caster says hits the shape, the inner polygon only hits, the triangles tile the viewport once, and the GL
frame drawn in passes over them equals the single full-screen pass pixel for pixel (GL)."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render import footprint as fp
from station.render import prefilter, procedural, shapes
from station.render.camera import orbit_camera
from station.render.stage import Stage
from station.render.weights import LobeWeights

W, H = 200, 150
CAMERAS = [
    None,
    orbit_camera((0.0, 0.0, 0.0), 35.0, 20.0, 3.2, fov_deg=40.0),
    orbit_camera((0.3, 0.1, 0.0), 200.0, -15.0, 2.4, fov_deg=30.0),
    orbit_camera((0.0, 0.0, 0.0), 95.0, 60.0, 6.0, fov_deg=25.0),
]


def _ndc_of_pixels(width: int, height: int) -> np.ndarray:
    """NDC (H, W, 2) of the pixel centres of a width × height frame, row 0 at the top."""
    x = 2.0 * (np.arange(width) + 0.5) / width - 1.0
    y = 1.0 - 2.0 * (np.arange(height) + 0.5) / height
    return np.stack(np.broadcast_arrays(x[None, :], y[:, None]), axis=-1)


def _inside(poly: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Whether points p (..., 2) lie in the convex counter-clockwise polygon *poly* (edges included)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    cross = (b[:, 0] - a[:, 0]) * (p[..., None, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (
        p[..., None, 0] - a[:, 0]
    )
    return np.all(cross >= 0.0, axis=-1)


@pytest.mark.parametrize("shape", shapes.SHAPES)
@pytest.mark.parametrize("cam", range(len(CAMERAS)))
def test_polygon_holds_every_hit_and_inner_only_hits(shape: str, cam: int) -> None:
    scene = shapes.Scene(shape, misalignment_deg=12.0 if shape == "panels" else 0.0, camera=CAMERAS[cam])
    foot = fp.shape_footprint(shape, scene.view_camera, W, H, scene.misalignment_deg)
    o, d = scene.view_camera.rays(W, H)
    hits = shapes.intersect(scene, o, d).mask
    ndc = _ndc_of_pixels(W, H)
    if foot is None:  # one full-screen pass: only when the shape's bound fills (most of) the frame
        box = fp.bound_points(shape, scene.misalignment_deg)
        assert hits.mean() > 0.2 or np.any(
            np.linalg.norm(box - np.asarray(scene.view_camera.eye), axis=1) < 3.0
        )
        return
    assert hits.any()
    assert np.all(_inside(foot.outer, ndc)[hits])
    assert _inside(foot.outer, ndc).mean() < fp.MAX_AREA_SHARE + 0.02  # a footprint, not the frame
    if foot.inner is not None:
        inner = _inside(foot.inner, ndc)
        assert np.all(hits[inner])
        assert inner.sum() > 0.9 * hits.sum()  # the ring is thin


@pytest.mark.parametrize("with_inner", [False, True])
def test_triangles_tile_the_viewport_once(with_inner: bool) -> None:
    cam = orbit_camera((0.0, 0.0, 0.0), 20.0, 10.0, 4.0)
    foot = fp.shape_footprint("sphere", cam, W, H)
    assert foot is not None and foot.inner is not None
    if not with_inner:
        foot = fp.Footprint(foot.outer)
    parts = fp.footprint_triangles(foot)
    if not with_inner:
        assert len(parts[0]) == 0
    rng = np.random.default_rng(3)
    p = rng.uniform(-1.0, 1.0, (20000, 2))  # random points: never on an edge
    count = np.zeros(len(p), int)
    for tri in (t.astype(np.float64).reshape(-1, 3, 2) for t in parts):
        inside = np.ones((len(p), len(tri)), bool)
        for k in range(3):
            u, v = tri[:, k], tri[:, (k + 1) % 3]
            edge = (v[:, 0] - u[:, 0]) * (p[:, None, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (
                p[:, None, 0] - u[:, 0]
            )
            inside &= edge > 0.0  # counter-clockwise: the inside is left of every edge
        count += inside.sum(axis=1)
    assert np.all(count == 1)


def test_no_footprint_when_the_bound_reaches_the_eye() -> None:
    assert fp.shape_footprint("sphere", orbit_camera((0.0, 0.0, 0.0), 0.0, 0.0, 1.01), W, H) is None
    assert fp.shape_footprint("cylinder", orbit_camera((0.0, 0.0, 0.0), 0.0, 0.0, 0.5), W, H) is None


EXPS = (3.0, 40.0, 400.0)


@pytest.fixture(scope="module")
def basis(gl_ctx):
    return prefilter.prefilter_basis(procedural.light_booth(64), EXPS, ctx=gl_ctx)


@pytest.mark.gl
@pytest.mark.parametrize(
    ("shape", "stage", "coat", "flakes"),
    [
        ("sphere", False, False, False),  # the viewer's default
        ("sphere", True, False, False),  # stage
        ("sphere", True, True, True),  # the stylist's scene
        ("speedshape", True, True, True),
        ("panels", False, True, False),
    ],
)
@pytest.mark.parametrize("aa", [1, 4])
def test_gl_frame_equals_the_full_screen_pass(gl_ctx, basis, shape, stage, coat, flakes, aa) -> None:
    from station.render.gl_renderer import GLRenderer

    paints = [
        LobeWeights(EXPS, np.array([0.3, 0.1, 0.05]), np.diag([0.2, 0.1, 0.05]), np.array([0.0, 0.3, 0.4])),
        LobeWeights(EXPS, np.array([0.05, 0.2, 0.3]), np.diag([0.05, 0.1, 0.2]), np.array([0.2, 0.1, 0.0])),
    ]
    layer = ClearCoat() if coat else None
    sparkle = METALLIC_FLAKES if flakes else None
    with GLRenderer(basis, W, H, ctx=gl_ctx, aa=aa) as gl:
        for cam in CAMERAS[:3]:
            scene = shapes.Scene(
                shape,
                misalignment_deg=8.0 if shape == "panels" else 0.0,
                camera=cam,
                stage=Stage() if stage else None,
            )
            frames = []
            for on in (False, True):
                gl.footprint = on
                for linear in (True, False):  # a pixel no pass draws would keep this colour
                    gl.targets.draw_target(linear).clear(0.9, 0.1, 0.7, 1.0)
                frames += [
                    gl.render_linear(scene, paints, coat=layer, flakes=sparkle),
                    gl.render(scene, paints, coat=layer, flakes=sparkle),
                ]
            assert np.array_equal(frames[0], frames[2])
            assert np.array_equal(frames[1], frames[3])
