"""Tweaker: the crosshair buttons apply eq 3.6.4's blend at θ under the crosshair, the ring and the
highlight edge drag travel and gloss, the highlight centre moves the light; each is undoable."""

from __future__ import annotations

import numpy as np
import pytest

from station.design.tweaker import adjust_at, highlight_edge_deg
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.widgets.tweaker_screen import TweakerScreen

pytestmark = [pytest.mark.qt]


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

    ring = _pixel_at(c, doc.design.travel_deg)
    assert c.press(ring) == "travel-ring"
    c.drag(_pixel_at(c, 90.0))
    c.mouseReleaseEvent(None)
    assert doc.design.travel_deg == pytest.approx(90.0, abs=1.0)

    edge = _pixel_at(c, highlight_edge_deg(doc.design.gloss_gu))
    assert c.press(edge) == "highlight-edge"
    c.drag(_pixel_at(c, highlight_edge_deg(doc.design.gloss_gu) * 2))
    c.mouseReleaseEvent(None)
    assert doc.design.gloss_gu < DEFAULT_DESIGN.gloss_gu
    light = c.scene.light_dir.copy()
    assert c.press(_pixel_at(c, 0.0)) == "highlight-centre"
    c.drag(_pixel_at(c, 40.0))
    assert not np.allclose(c.scene.light_dir, light)
    c.mouseReleaseEvent(None)
    for _ in range(3):
        doc.undo()
    assert doc.design is DEFAULT_DESIGN
    screen.close()
