"""Tweaker: the crosshair buttons apply eq 3.6.4's blend at θ under the crosshair, the ring and the
highlight edge drag travel and gloss, the highlight centre moves the light; each is undoable."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPointF, Qt
from PySide6.QtGui import QMouseEvent

from station.design.tweaker import adjust_at, highlight_edge_deg
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.widgets.tweaker_screen import SIZE as SIZE_FALLBACK
from ui.widgets.tweaker_screen import TweakerCanvas, TweakerScreen

pytestmark = [pytest.mark.qt]


def _release(c: TweakerCanvas) -> None:
    """End a drag as letting go of the left mouse button does."""
    at = QPointF(0.0, 0.0)
    left, none = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton
    c.mouseReleaseEvent(
        QMouseEvent(QEvent.Type.MouseButtonRelease, at, at, left, none, Qt.KeyboardModifier.NoModifier)
    )


def _pixel_at(canvas, theta: float) -> tuple[int, int]:
    t = np.where(canvas.scene.mask, canvas.scene.aspecular_deg, np.inf)
    y, x = np.unravel_index(np.argmin(np.abs(t - theta)), t.shape)
    return int(x), int(y)


def test_crosshair_buttons_ring_and_edge(qtbot):
    doc = DesignDocument()
    screen = TweakerScreen(doc)
    qtbot.addWidget(screen)
    screen.show()
    c = screen.canvas
    xy = _pixel_at(c, 30.0)
    assert c.press(xy) == "object" and c.crosshair == xy
    assert c.buttons["lighter"].isVisible()
    c.buttons["lighter"].click()
    expected = adjust_at(DEFAULT_DESIGN, c.scene.aspecular_deg, xy, "L", 3.0, c.scene.mask).design
    assert doc.design == expected
    # θ = 30° with θ_clamp = 70°: R = (70 − 30)/(70 − 15), the face moves by R·3, the flop by (1 − R)·3
    r = (70.0 - c.scene.aspecular_deg[xy[1], xy[0]]) / 55.0
    assert doc.design.face[0] - DEFAULT_DESIGN.face[0] == pytest.approx(3.0 * r)
    assert doc.design.flop[0] - DEFAULT_DESIGN.flop[0] == pytest.approx(3.0 * (1 - r))

    assert doc.design.travel_deg is not None
    ring = _pixel_at(c, doc.design.travel_deg)
    assert c.press(ring) == "travel-ring"
    c.drag(_pixel_at(c, 90.0))
    _release(c)
    assert doc.design.travel_deg == pytest.approx(90.0, abs=1.0)

    edge = _pixel_at(c, highlight_edge_deg(doc.design.gloss_gu))
    assert c.press(edge) == "highlight-edge"
    c.drag(_pixel_at(c, highlight_edge_deg(doc.design.gloss_gu) * 2))
    _release(c)
    assert doc.design.gloss_gu < DEFAULT_DESIGN.gloss_gu
    light = c.scene.light_dir.copy()
    assert c.press(_pixel_at(c, 0.0)) == "highlight-centre"
    c.drag(_pixel_at(c, 40.0))
    assert not np.allclose(c.scene.light_dir, light)
    _release(c)
    for _ in range(3):
        doc.undo()
    assert doc.design is DEFAULT_DESIGN
    screen.close()


def test_tweaker_on_the_main_scene_any_shape_environment_lit(qtbot):
    """The tweaker shows the 3D view's shape and environment; a click and the lighter button apply eq
    3.6.4 at θ against the environment's dominant light; a shape change in the view re-renders it."""
    from PySide6.QtCore import QPoint, Qt

    from station.render.buffers import angle_buffers, dominant_light_direction
    from station.render.numpy_renderer import gbuffer
    from ui.models.view import ViewModel, ViewSettings

    doc = DesignDocument()
    vm = ViewModel(ViewSettings(shape="speedshape"))
    screen = TweakerScreen(doc, vm)
    qtbot.addWidget(screen)
    screen.resize(700, 560)
    screen.show()
    qtbot.waitExposed(screen)
    c = screen.canvas
    c.wait_idle()
    assert c.main is not None and c.main.settings.shape == "speedshape"
    w, h = c.scene_size()
    assert c.scene.shape == (h, w) and w > SIZE_FALLBACK  # fills the tab, not a 400 px corner
    # geometry: the view's ray cast, θ against the dominant light of the environment's SH
    g = gbuffer(vm.settings.scene(), w, h)
    light = dominant_light_direction(c.main.basis.core.basis.sh)
    expected = angle_buffers(g, light)
    assert np.array_equal(c.scene.mask, g.mask)
    assert np.allclose(c.scene.aspecular_deg[g.mask], expected.aspecular_deg[g.mask], atol=1e-4)
    # the picture is the environment-lit composite of the design, not a point-lit shade
    img = c.grab().toImage()
    ys, xs = np.nonzero(g.mask)
    k = len(xs) // 2
    ref = c.main.image(doc.design)[ys[k], xs[k]]
    px = img.pixelColor(int(xs[k]), int(ys[k]))
    assert abs(px.red() - int(ref[0])) <= 1 and abs(px.green() - int(ref[1])) <= 1
    # click where θ ≈ 30°, then "lighter": ΔL* = 3 split by R = (θc − θ)/(θc − 15)
    t = np.where(c.scene.mask, c.scene.aspecular_deg, np.inf)
    y, x = np.unravel_index(np.argmin(np.abs(t - 30.0)), t.shape)
    qtbot.mouseClick(c, Qt.MouseButton.LeftButton, pos=QPoint(int(x), int(y)))
    assert c.crosshair == (int(x), int(y))
    qtbot.mouseClick(c.buttons["lighter"], Qt.MouseButton.LeftButton)
    theta = float(c.scene.aspecular_deg[y, x])
    r = (70.0 - theta) / 55.0
    assert doc.design.face[0] - DEFAULT_DESIGN.face[0] == pytest.approx(3.0 * r, abs=1e-6)
    assert doc.design.flop[0] - DEFAULT_DESIGN.flop[0] == pytest.approx(3.0 * (1 - r), abs=1e-6)
    # another shape in the 3D view → the tweaker follows
    vm.update(shape="cylinder")
    c.wait_idle()
    assert c.main.settings.shape == "cylinder"
    assert np.array_equal(c.scene.mask, gbuffer(vm.settings.scene(), w, h).mask)
    screen.close()
