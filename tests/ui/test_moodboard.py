"""Mood board: moving the face eyedropper changes the design and the rendered picture; images drag and zoom;
one eyedropper drag is one undo step."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

from station.design.moodboard import eyedrop_lab
from ui.demo import patch_image
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.models.moodboard import MoodBoardModel
from ui.models.view import ViewModel
from ui.widgets.moodboard_screen import MoodBoardScreen
from ui.widgets.render_view import GLRenderView

pytestmark = [pytest.mark.qt]
RED, GREEN = (0.8, 0.1, 0.1), (0.1, 0.6, 0.2)


@pytest.fixture
def board(tmp_path):
    doc = DesignDocument()
    model = MoodBoardModel(doc)
    path = patch_image(tmp_path / "patches.png", (RED, GREEN), size=40)
    model.add_image(str(path), 0.0, 0.0, 2.0)  # 160 × 80 board pixels
    return doc, model, str(path)


@pytest.mark.gl
def test_face_eyedropper_changes_design_and_picture(qtbot, board):
    doc, model, path = board
    vm = ViewModel()
    vm.show(doc.design)
    doc.events.changed.connect(vm.show)
    screen = MoodBoardScreen(model)
    view = GLRenderView(vm)
    for w in (screen, view):
        qtbot.addWidget(w)
    screen.resize(640, 400)
    view.resize(160, 120)
    screen.show()
    view.show()
    qtbot.waitExposed(view)
    view.wait_idle()
    before = view.grab_image().astype(int)
    screen.set_tool("face")
    canvas = screen.canvas
    qtbot.mousePress(canvas, Qt.MouseButton.LeftButton, pos=QPoint(20, 40))  # red patch
    qtbot.mouseMove(canvas, QPoint(40, 40))
    red_lab = eyedrop_lab(model.pixels[path], (20, 20), 3)
    assert doc.design.face == pytest.approx(tuple(red_lab), abs=1e-9)
    assert doc.design.flop == DEFAULT_DESIGN.flop
    mid = view.grab_image().astype(int)
    qtbot.mouseMove(canvas, QPoint(120, 40))  # drag onto green
    qtbot.mouseRelease(canvas, Qt.MouseButton.LeftButton, pos=QPoint(120, 40))
    green_lab = eyedrop_lab(model.pixels[path], (60, 20), 3)
    assert doc.design.face == pytest.approx(tuple(green_lab), abs=1e-9)
    after = view.grab_image().astype(int)
    assert view.basis is not None
    obj = view.basis.paint >= 0
    assert (mid[obj][:, 0] - before[obj][:, 0]).mean() > 5  # the sphere turned redder
    assert (after[obj][:, 1] - mid[obj][:, 1]).mean() > 5  # then greener
    assert model.eyedroppers["face"] == (120.0, 40.0)
    # the whole drag is one undo step back to the exact starting design
    doc.undo()
    assert doc.design is DEFAULT_DESIGN
    screen.close()
    view.close()


def test_move_and_zoom_image_and_gloss_eyedropper(qtbot, board):
    doc, model, _ = board
    screen = MoodBoardScreen(model)
    qtbot.addWidget(screen)
    screen.resize(640, 400)
    screen.show()
    canvas = screen.canvas
    qtbot.mousePress(canvas, Qt.MouseButton.LeftButton, pos=QPoint(10, 10))
    qtbot.mouseMove(canvas, QPoint(40, 30))
    qtbot.mouseRelease(canvas, Qt.MouseButton.LeftButton, pos=QPoint(40, 30))
    im = model.board.images[0]
    assert (im.x, im.y) == (30.0, 20.0)
    model.zoom_image(0, 1.0)
    assert model.image_rect(0) == (30.0, 20.0, 80.0, 40.0)
    screen.set_tool("gloss")
    # on the red/green edge (image x = 40 at board 70): contrast between the patches → non-zero gloss
    qtbot.mousePress(canvas, Qt.MouseButton.LeftButton, pos=QPoint(70, 40))
    qtbot.mouseRelease(canvas, Qt.MouseButton.LeftButton, pos=QPoint(70, 40))
    assert 0.0 < doc.design.gloss_gu <= 100.0 and doc.design.gloss_gu != DEFAULT_DESIGN.gloss_gu
    # off the images nothing changes
    g = doc.design
    assert not model.drop("face", 600.0, 390.0)
    assert doc.design is g
    model.add_board("second")
    assert screen.tabs.count() == 2 and screen.tabs.currentIndex() == 1
    screen.close()


def test_pixels_round_trip_through_png(board):
    _, model, path = board
    np.testing.assert_allclose(model.pixels[path][5, 5], np.round(np.array(RED) * 255) / 255, atol=1e-12)
