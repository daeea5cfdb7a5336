"""File → Open model: an own glTF/GLB, OBJ or STL model joins the 3D view's shape picker and is drawn by the
core's GL renderer; a file that cannot be used is named in a visible message and changes nothing."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QLineEdit, QMessageBox

from station.render.errors import RenderInputError
from tests.ui.dialogs import enter_file_name
from ui.models.view import ViewModel
from ui.widgets.render_view import GLRenderView

pytestmark = [pytest.mark.qt]


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("CACAD_CACHE_DIR", str(tmp_path / "cache"))


@pytest.fixture
def box_glb(tmp_path):
    """A tiny model written by trimesh: a 1.6 × 0.8 × 1.0 box (12 triangles)."""
    path = tmp_path / "box.glb"
    trimesh.creation.box(extents=(1.6, 0.8, 1.0)).export(path)
    return path


def test_view_model_loads_a_model_and_refuses_a_bad_file(tmp_path, box_glb) -> None:
    model = ViewModel()
    bad = tmp_path / "broken.stl"
    bad.write_bytes(b"solid nothing\nthis is not an stl\n")
    with pytest.raises(RenderInputError, match=r"broken\.stl"):
        model.load_model(bad)
    assert model.settings.model is None and model.mesh() is None
    mesh = model.load_model(box_glb)
    assert model.settings.model == str(box_glb) and model.mesh() is mesh
    assert len(mesh.faces) == 12 and model.models == (str(box_glb),)
    assert model.settings.camera() != ViewModel().settings.camera()  # framed by the model camera
    model.update(model=None)
    assert model.mesh() is None


def test_view_model_shows_the_procedural_car() -> None:
    from station.render.car import car_body
    from station.render.mesh_parts import GLASS, PAINT, TYRE
    from ui.models.view import ViewInputError

    model = ViewModel()
    mesh = model.load_model("car")
    assert model.settings.model == "car" and model.mesh() is mesh and model.model_parts() == ()
    # the same body, wheels and glass as `station render --mesh car` draws (counted on an independent build)
    expected = car_body()
    assert np.array_equal(mesh.faces, expected.faces) and np.array_equal(mesh.painted, expected.painted)
    assert {PAINT, TYRE, GLASS} <= set(np.unique(mesh.painted).tolist())
    assert model.settings.camera() != ViewModel().settings.camera()  # framed by the model camera
    with pytest.raises(ViewInputError, match="paint_part"):
        model.set_paint_part("body")
    assert model.set_paint_part(None) is mesh


def _open_model(qtbot, win, path) -> None:
    """File → Open model… through the menu action, the file dialog answered by typing *path*."""

    def answer() -> None:
        dlg = win.file_dialog
        if dlg is None or not dlg.isVisible():
            QTimer.singleShot(50, answer)
            return
        enter_file_name(dlg.findChild(QLineEdit, "fileNameEdit"), path)
        if dlg.isVisible():
            QTimer.singleShot(200, answer)

    QTimer.singleShot(50, answer)
    win.file_actions["Open model"].trigger()


@pytest.mark.gl
def test_file_open_model_shows_it_in_the_view(qtbot, tmp_path, box_glb, own_cache) -> None:
    from station.render.gl_renderer import GLRenderer
    from ui.app import MainWindow
    from ui.models.view import environment_basis_gl

    win = MainWindow(ask_on_close=False)
    qtbot.addWidget(win)
    win.resize(900, 700)
    win.show()
    qtbot.waitExposed(win)
    panel, view = win.view_panel, win.view_panel.view
    assert isinstance(view, GLRenderView)
    view.wait_idle(60000)
    bad = tmp_path / "broken.obj"
    bad.write_bytes(b"\x00\x01 not a model")
    before = win.view_model.settings
    _open_model(qtbot, win, bad)
    qtbot.waitUntil(lambda: win.error_box is not None and win.error_box.isVisible(), timeout=10000)
    assert win.error_box is not None
    assert "broken.obj" in win.error_box.text()
    assert win.view_model.settings == before
    win.error_box.button(QMessageBox.StandardButton.Ok).click()
    _open_model(qtbot, win, box_glb)
    qtbot.waitUntil(lambda: win.view_model.settings.model == str(box_glb), timeout=10000)
    assert panel.shape.currentText() == "box.glb (model)"
    assert f"model {box_glb}" in win.statusBar().currentMessage()
    frame = view.grab_image()
    h, w = frame.shape[:2]
    settings = win.view_model.settings
    # the core renderer of its own (own prefilter, own targets) on the widget's context: a standalone EGL
    # context in this process would break Qt's GLX contexts of later views (scripts/test.sh)
    assert view.ctx is not None
    view.makeCurrent()
    try:
        with GLRenderer(environment_basis_gl(settings.environment, view.ctx), w, h, ctx=view.ctx) as gl:
            shown = win.view_model.weights()
            assert shown is not None
            weights = list(shown)
            core = gl.render_mesh(win.view_model.mesh(), weights, camera=settings.camera())
    finally:
        view.doneCurrent()
    diff = np.abs(frame.astype(int) - core.astype(int))
    assert np.median(diff) <= 2 and np.percentile(diff, 99) <= 12
    background = core[0, 0].astype(int)
    box = np.abs(core.astype(int) - background).max(axis=-1) > 8
    assert 0.05 < box.mean() < 0.9  # the box covers part of the frame
    # picking a built-in shape again takes the model off; the model stays in the picker
    panel.shape.setCurrentIndex(0)
    assert win.view_model.settings.model is None and panel.shape.findData(str(box_glb)) >= 0
    # the procedural car (wheels, glass) is in the picker without a file
    panel.shape.setCurrentIndex(panel.shape.findData("car"))
    assert win.view_model.settings.model == "car" and panel.shape.currentText() == "procedural car (model)"
    mesh = win.view_model.mesh()
    assert mesh is not None and mesh.name == "car"
    win.close()
