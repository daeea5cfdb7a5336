"""The 3D view under Xvfb/xcb (llvmpipe): GL composite equals the NumPy composite, sliders and paint edits
change the picture, orbit moves the camera, the worker is joined."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

from station.model import FaceFlopTravelGloss
from ui.models.designer import DesignerModel
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.models.view import ViewModel
from ui.widgets.render_view import GLRenderView
from ui.widgets.view_panel import ViewPanel

pytestmark = [pytest.mark.qt]


def _gl_view(qtbot, model: ViewModel, w: int = 160, h: int = 120, mode: str = "cpu") -> GLRenderView:
    view = GLRenderView(model, mode=mode)
    qtbot.addWidget(view)
    view.resize(w, h)
    view.show()
    qtbot.waitExposed(view)
    view.wait_idle()
    return view


@pytest.mark.gl
@pytest.mark.parametrize("mode", ["cpu", "gpu"])
def test_gl_frame_matches_numpy_composite(qtbot, mode):
    model = ViewModel()
    model.show(DEFAULT_DESIGN, FaceFlopTravelGloss((45, 40, 25), (25, 30, 15), 60, 30))
    model.update(exposure_ev=0.5)
    view = _gl_view(qtbot, model, mode=mode)
    img = view.grab_image()
    assert view.gl_renderer
    assert view.basis is not None and view.basis.size == (160, 120)
    # exact display transform of the core's linear re-weighting (station.render.tonemap.to_display)
    ref = view.basis.composite_display(model.weights(), model.settings.exposure_ev)
    diff = np.abs(img.astype(int) - ref.astype(int))
    # cpu: the core's 64k-entry LUT → ≤ 1 level; gpu: RGB9_E5 storage (≤ 0.2 % relative) → ≤ 2 levels
    assert diff.max() <= (1 if mode == "cpu" else 2), diff.max()
    assert (diff > 0).mean() < 0.05
    if mode == "cpu":  # texel for texel the core's 8-bit frame
        np.testing.assert_array_equal(img, view.basis.core.edit(list(model.weights()), 0.5))
    view.close()


@pytest.mark.gl
@pytest.mark.parametrize("mode", ["cpu", "gpu"])
def test_paint_edit_and_exposure_change_the_picture(qtbot, mode):
    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    view = _gl_view(qtbot, model, mode=mode)
    before = view.grab_image().astype(int)
    basis_before = view.basis
    model.show(DEFAULT_DESIGN.replace(face=(55.0, 40.0, 10.0), flop=(28.0, 30.0, 5.0)))
    after = view.grab_image().astype(int)
    assert view.basis is basis_before  # a paint edit re-weights the cached basis images
    obj = view.basis.paint >= 0
    assert np.abs(after - before)[obj].mean() > 5
    assert (after[obj][:, 0] - before[obj][:, 0]).mean() > 5  # towards red
    np.testing.assert_array_equal(after[~obj], before[~obj])
    model.update(exposure_ev=1.0)
    brighter = view.grab_image().astype(int)
    assert brighter[obj].mean() > after[obj].mean() + 5
    view.close()


@pytest.mark.gl
def test_drag_orbits_and_wheel_zooms(qtbot):
    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    view = _gl_view(qtbot, model, 200, 150)
    qtbot.mousePress(view, Qt.MouseButton.LeftButton, pos=QPoint(100, 75))
    qtbot.mouseMove(view, QPoint(125, 75))
    qtbot.mouseRelease(view, Qt.MouseButton.LeftButton, pos=QPoint(125, 75))
    assert model.settings.yaw_deg == pytest.approx(360 - 25 * 0.4)
    view.wait_idle()
    assert view.basis.size == (200, 150)
    view.close()


def test_exposure_slider_in_panel_updates_model_and_render(qtbot):
    doc = DesignDocument()
    model = ViewModel()
    model.show(doc.design)
    panel = ViewPanel(model)
    qtbot.addWidget(panel)
    panel.resize(400, 300)
    panel.show()
    qtbot.waitExposed(panel)
    panel.view.wait_idle()
    frames = panel.view.frames
    panel.exposure.setValue(15)
    assert model.settings.exposure_ev == pytest.approx(1.5)
    qtbot.waitUntil(lambda: panel.view.frames > frames, timeout=5000)
    assert panel.exposure_label.text() == "+1.5 EV"
    panel.shape.setCurrentText("cylinder")
    assert model.settings.shape == "cylinder"
    panel.view.wait_idle()
    panel.close()


def test_designer_gloss_edit_reaches_view_model(qtbot):
    doc = DesignDocument()
    designer = DesignerModel(doc)
    model = ViewModel()
    model.show(doc.design)
    doc.events.changed.connect(model.show)
    w0 = model.weights()[0]
    designer.set_gloss(20.0)
    w1 = model.weights()[0]
    assert not np.allclose(w0.k_g, w1.k_g)


def test_image_view_paints_the_core_frame(qtbot):
    """The no-GL fallback shows the core's 8-bit frame of the same cached basis images."""
    from ui.widgets.render_view import ImageRenderView

    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    view = ImageRenderView(model)
    qtbot.addWidget(view)
    view.resize(160, 120)
    view.show()
    qtbot.waitExposed(view)
    view.wait_idle()
    img = view.render_image()
    assert img.shape == (120, 160, 3)
    ref = view.basis.composite_display(model.weights(), 0.0)
    assert np.abs(img.astype(int) - ref.astype(int)).max() <= 1
    view.close()


def test_closing_during_a_basis_computation_joins_the_worker(qtbot):
    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    from ui.widgets.render_view import make_render_view

    view = make_render_view(model)
    qtbot.addWidget(view)
    view.resize(400, 300)
    view.show()
    model.update(shape="speedshape")  # starts a full-resolution worker
    assert view._worker is not None
    view.close()  # the autouse fixture fails the test if a QThread is still running
    assert view._worker is None


@pytest.fixture
def cold_prefilter_cache(tmp_path, monkeypatch):
    """An empty ``$CACAD_CACHE_DIR`` and no prefiltered environment in memory (the first start ever)."""
    from ui.models import view as view_models

    monkeypatch.setenv("CACAD_CACHE_DIR", str(tmp_path / "cold"))
    view_models._READY.clear()
    view_models._environment_basis.cache_clear()
    yield tmp_path / "cold" / "prefilter"
    view_models._READY.clear()
    view_models._environment_basis.cache_clear()


@pytest.mark.gl
def test_cold_cache_first_frame_from_coarse_prefilter_then_full_quality(qtbot, cold_prefilter_cache):
    """A view change is drawn at once, at full resolution, by the core's GL renderer (from the coarse
    prefilter while the full one is made), then paint edits run on the worker's cached basis."""
    from ui.models.view import PREFILTER_MAX_SIZE, environment_ready

    model = ViewModel()
    model.show(DEFAULT_DESIGN)
    view = GLRenderView(model)
    qtbot.addWidget(view)
    first: list = []

    def on_frame() -> None:
        if not first:
            w, h = view._pixel_size()
            pixels = np.frombuffer(view._screen.read(viewport=(0, 0, w, h), components=3), np.uint8)
            frame = pixels.reshape(h, w, 3)[::-1]
            first.append((view.gl_frames, view.full_quality, environment_ready("booth"), frame.copy()))

    view.frame_rendered.connect(on_frame)
    view.resize(160, 120)
    view.show()
    qtbot.waitUntil(lambda: view.frames > 0, timeout=20000)
    gl_frames0, full0, ready0, frame0 = first[0]
    # the first frame is the core's GL frame, before the full prefilter exists, at full resolution
    assert gl_frames0 == 1 and not full0 and not ready0
    assert frame0.shape == (120, 160, 3)
    qtbot.waitUntil(lambda: view.full_quality, timeout=60000)
    view.wait_idle()
    assert environment_ready("booth") and view.basis.prefilter_size == PREFILTER_MAX_SIZE
    assert view.basis.size == (160, 120)
    assert any(cold_prefilter_cache.glob("*-o64-*.npy"))  # the full maps were made and cached now
    img = view.grab_image()
    np.testing.assert_array_equal(img, view.basis.core.edit(list(model.weights()), 0.0))
    obj = view.basis.paint >= 0
    assert obj.mean() > 0.2  # the sphere is on screen, lit
    # the first frame is the same picture from coarser maps: mean object colour within a few levels
    assert np.abs(img[obj].astype(float).mean(axis=0) - frame0[obj].astype(float).mean(axis=0)).max() < 8
    # an orbit step is drawn by the GL renderer at once (full prefilter now: full quality), no preview
    n = view.gl_frames
    model.update(yaw_deg=20.0)
    orbit = view.grab_image()  # renders the frame
    assert view.gl_frames > n and view.full_quality and not view.basis_current
    assert np.abs(orbit.astype(int) - img.astype(int)).max() > 10  # the view moved
    view.wait_idle()
    view.close()
