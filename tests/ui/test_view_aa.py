"""Anti-aliasing in the viewer: the silhouette pixels of the view's final frame hold the disc's pixel
coverage.

A Lambertian paint under a uniform environment (an .hdr file of one radiance, loaded as the user does) has
one radiance L₀ over the sphere's whole disc, so an anti-aliased edge pixel of the linear frame reads
B + c·(L₀ − B), c the share of the pixel the disc covers. The unit sphere at the target seen from distance
d projects to a circle of radius tan(asin(1/d)) / tan(fov/2) · H/2 pixels around the image centre; the
exact coverage of each pixel is the closed form of ``tests/render/test_gl_aa.py``. A regular s × s grid
misjudges a straight edge through a pixel by at most 1/s of its area (0.5 at s = 2, 0.25 at s = 4), and such
errors cancel around the circle, so the mean signed error over the edge pixels is held to 0.03.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.render.hdr_io import write_hdr
from station.render.numpy_renderer import BACKGROUND
from station.render.shapes import DEFAULT_CAMERAS
from station.render.weights import LobeWeights
from tests.render.test_gl_aa import _coverage
from ui.models.document import DEFAULT_DESIGN
from ui.models.view import VIEW_AA, ViewModel
from ui.widgets.render_view import ImageRenderView

pytestmark = [pytest.mark.qt]

SIZE = 160  # the views' minimum width
RADIANCE = 1.5


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CACAD_CACHE_DIR", str(tmp_path / "cache"))


def _final_linear(qtbot, tmp_path, aa: int) -> np.ndarray:
    """The view's final linear frame (SIZE², green) of a Lambertian paint under a uniform .hdr file."""
    env = tmp_path / "uniform.hdr"
    if not env.exists():
        write_hdr(env, np.full((32, 64, 3), RADIANCE, np.float32))
    model = ViewModel()
    model.load_environment(env)
    model.show(DEFAULT_DESIGN)
    view = ImageRenderView(model)
    view.aa = aa
    qtbot.addWidget(view)
    view.resize(SIZE, SIZE)
    view.show()
    qtbot.waitExposed(view)
    qtbot.waitUntil(lambda: view.basis_current, timeout=60000)
    basis = view.basis
    assert basis is not None and basis.size == (SIZE, SIZE)
    m = len(basis.exponents)
    lambert = LobeWeights(basis.exponents, np.full(3, 0.3), np.zeros((m, 3)), np.zeros(m))
    return basis.composite_linear((lambert, lambert))[..., 1]


def test_view_edges_take_the_disc_coverage(qtbot, tmp_path, own_cache) -> None:
    assert VIEW_AA > 1  # the viewer anti-aliases by default
    plain = _final_linear(qtbot, tmp_path, 1)
    smooth = _final_linear(qtbot, tmp_path, VIEW_AA)
    cam = DEFAULT_CAMERAS["sphere"]
    d = float(np.linalg.norm(np.subtract(cam.eye, cam.target)))
    radius_px = math.tan(math.asin(1.0 / d)) / math.tan(math.radians(cam.fov_deg) / 2.0) * SIZE / 2.0
    cov = _coverage(SIZE, radius_px)
    inside = float(np.median(plain[cov >= 1.0]))
    assert np.ptp(plain[cov >= 1.0]) < 0.02 * inside  # one radiance over the disc
    measured = (smooth - BACKGROUND) / (inside - BACKGROUND)
    edge = (cov > 0.0) & (cov < 1.0)
    # shaded once per pixel every pixel is background or object; anti-aliased the edge takes values between
    plain_c = (plain - BACKGROUND) / (inside - BACKGROUND)
    assert np.all((np.abs(plain_c) < 0.02) | (np.abs(plain_c - 1.0) < 0.02))
    half = (cov > 0.25) & (cov < 0.75)
    assert half.sum() >= 20 and np.all((measured[half] > 0.05) & (measured[half] < 0.95))
    assert abs(float(np.mean(measured[edge] - cov[edge]))) <= 0.03
    side = math.isqrt(VIEW_AA)
    assert float(np.max(np.abs(measured[edge] - cov[edge]))) <= 1.0 / side + 0.02
    # pixels away from the silhouette are unchanged
    far = (cov >= 1.0) | (cov <= 0.0)
    np.testing.assert_allclose(smooth[far], plain[far], rtol=2e-3, atol=2e-3)


@pytest.mark.gl
def test_gl_frame_of_a_still_model_is_supersampled(qtbot, tmp_path, own_cache) -> None:
    # An own model is drawn by the core's GL renderer in every frame: once the view has been still for
    # SETTLE_MS that frame is redrawn at VIEW_AA samples per pixel. Against the same view shaded once per
    # pixel, the frames differ along the silhouette (pixels between box and background) and nowhere
    # else beyond the shading's own sub-pixel variation.
    import trimesh

    from station.render.basis_images import edge_pixels
    from ui.widgets.render_view import GLRenderView

    box = tmp_path / "box.glb"
    trimesh.creation.box(extents=(1.6, 0.8, 1.0)).export(box)
    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    model.load_model(box)
    view = GLRenderView(model)
    qtbot.addWidget(view)
    view.resize(240, 180)
    view.show()
    qtbot.waitExposed(view)
    qtbot.waitUntil(lambda: view._core is not None and view._core.targets.aa == VIEW_AA, timeout=30000)
    smooth = view.grab_image().astype(int)
    view.aa = 1
    assert view._core is not None
    view._core.set_aa(1)
    plain = view.grab_image().astype(int)
    assert smooth.shape == plain.shape == (180, 240, 3)
    background = plain[0, 0]
    obj = np.abs(plain - background).max(axis=-1) > 2
    assert 0.05 < obj.mean() < 0.9
    # the pixels next to a jump in the plain frame: the silhouette and the box's own edges between faces
    pad = np.pad(plain, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = obj.shape
    jump = np.zeros(obj.shape, bool)
    for dy in (0, 1, 2):
        for dx in (0, 1, 2):
            jump |= np.abs(pad[dy : dy + h, dx : dx + w] - plain).max(axis=-1) > 8
    edge = edge_pixels(obj.astype(np.int8))
    diff = np.abs(smooth - plain).max(axis=-1)
    assert np.count_nonzero(diff[edge] > 8) >= 20  # the silhouette is smoothed
    assert np.all(diff[~jump] <= 8)  # elsewhere only the shading's sub-pixel variation
    # an edge pixel outside the box takes some of its colour: coverage between 0 and 1
    outside = edge & ~obj
    assert np.count_nonzero(np.abs(smooth[outside] - background).max(axis=-1) > 8) >= 10
    view.close_view()
