"""The bright silver (L*15 = 125) in the viewer: QTest clicks and drags on the real designer panel and
tweaker, and a visible message for a value outside the domain's bound.

Expectations are the documented steps: the variations grid's default degree (5) moves face L* by ±5;
the brightness slider adds its value to L*; a tweaker ``lighter`` click at a face pixel (R = 1,
eq 3.6.4) adds 3 to the face L* only.
"""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest

from ui.models.designer import DesignerModel
from ui.models.document import DesignDocument
from ui.widgets.designer_panel import DesignerPanel
from ui.widgets.tweaker_screen import STEPS, TweakerScreen

pytestmark = [pytest.mark.qt]


@pytest.fixture
def panel(qtbot, bright_silver):
    doc = DesignDocument(bright_silver, "bright silver")
    p = DesignerPanel(DesignerModel(doc))
    qtbot.addWidget(p)
    p.resize(700, 900)
    p.show()
    qtbot.waitExposed(p)
    yield p
    p.close()


def _pt(p) -> QPoint:
    return QPoint(round(p.x()), round(p.y()))


def test_variations_grid_lighter_and_darker(panel, bright_silver) -> None:
    doc = panel.model.document
    assert panel.variations.buttons[0].text() == "lighter" and panel.variations.buttons[0].isEnabled()
    QTest.mouseClick(panel.variations.buttons[0], Qt.MouseButton.LeftButton)
    assert doc.design.face == pytest.approx((130.0, -0.6, -1.8))
    doc.undo()
    assert panel.variations.buttons[1].text() == "darker"
    QTest.mouseClick(panel.variations.buttons[1], Qt.MouseButton.LeftButton)
    assert doc.design.face == pytest.approx((120.0, -0.6, -1.8))


def test_brightness_slider_and_point_drag(panel, bright_silver) -> None:
    doc = panel.model.document
    panel.bright.setValue(5)  # HSB brightness: ΔL* = +5 on face and flop
    panel.bright.sliderReleased.emit()
    assert doc.design.face[0] == pytest.approx(130.0) and doc.design.flop[0] == pytest.approx(43.0)
    doc.undo()
    plot = panel.plots["L"]
    lo, hi = plot.axis()
    assert lo <= 38.0 and hi >= 125.0  # the L* axis shows the bright face
    angle, start = plot.point_positions()[0]
    assert angle == 15.0
    target = plot.to_px(15.0, 135.0)
    QTest.mousePress(plot, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, _pt(start))
    QTest.mouseMove(plot, _pt(target))
    QTest.mouseRelease(plot, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, _pt(target))
    # the refit through the moved 15° point lifts the face well above 125 (it was clamped at 100 before)
    assert doc.design.face[0] > 127.0 and panel.status.text() == ""


def test_face_drag_in_the_ab_plot(panel, bright_silver) -> None:
    doc = panel.model.document
    ab = panel.ab
    start = ab.handles()["face"]
    target = ab.to_px(6.0, 4.0)
    QTest.mousePress(ab, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, _pt(start))
    QTest.mouseMove(ab, _pt(target))
    QTest.mouseRelease(ab, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, _pt(target))
    px = 160.0 / ab.plot_rect().width()  # one pixel in a*/b* units
    assert doc.design.face[0] == 125.0
    np.testing.assert_allclose(doc.design.face[1:], (6.0, 4.0), atol=1.5 * px)


def test_out_of_range_shows_the_message(panel) -> None:
    assert not panel.model.set_hsb(0.0, 1.0, 80.0)  # 125 + 80 = 205 > 200
    assert panel.status.isVisible()
    assert "face.L: expected 0 <= L* <= 200" in panel.status.text()


def test_tweaker_buttons(qtbot, bright_silver) -> None:
    doc = DesignDocument(bright_silver, "bright silver")
    screen = TweakerScreen(doc)
    qtbot.addWidget(screen)
    screen.show()
    c = screen.canvas
    t = np.where(c.scene.mask, c.scene.aspecular_deg, np.inf)
    y, x = np.unravel_index(np.argmin(np.abs(t - 10.0)), t.shape)  # a face pixel: θ < 15° → R = 1
    assert c.press((int(x), int(y))) == "object"
    QTest.mouseClick(c.buttons["lighter"], Qt.MouseButton.LeftButton)
    assert (
        doc.design.face == pytest.approx((125.0 + STEPS["L"], -0.6, -1.8))
        and doc.design.flop == bright_silver.flop
    )
    QTest.mouseClick(c.buttons["darker"], Qt.MouseButton.LeftButton)
    QTest.mouseClick(c.buttons["darker"], Qt.MouseButton.LeftButton)
    assert doc.design.face[0] == pytest.approx(125.0 - STEPS["L"])
    QTest.mouseClick(c.buttons["chroma +"], Qt.MouseButton.LeftButton)
    assert doc.design.face[1:] == pytest.approx((-0.6 * (1 + STEPS["C"]), -1.8 * (1 + STEPS["C"])))
    screen.close()
