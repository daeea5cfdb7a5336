"""Variations rendered on the object of the main view (thesis §3.4.4), driven by clicks on the real
main window.

Each swatch is the main view's cached basis images re-weighted for the cell's design. The independent
expectation is the core's direct NumPy renderer (``numpy_renderer.render_linear``, no basis images) of
the same scene at the main view's size, cropped to the same square around the object (its own G-buffer
mask) and box-filtered over every pixel of each swatch cell (not the grid samples); the mean colours
agree within ΔE*ab 0.3 (whole swatch) and 0.5 (the cells wholly on the object; measured 0.005 and 0.06
on the speed shape), the difference being the swatch's nearest-sample grid against the full area mean.
"""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

from station.model.colorimetry import linear_srgb_to_lab, srgb_decode
from station.render.numpy_renderer import gbuffer, render_linear
from station.render.tonemap import to_display
from ui.app import MainWindow
from ui.models.designer import SWATCH_MARGIN
from ui.models.measure_db import LocalSink
from ui.models.view import environment_basis, paint_weights
from ui.widgets.designer_panel import VARIATION_PX, DesignerPanel

pytestmark = [pytest.mark.qt]
LEFT = Qt.MouseButton.LeftButton
WHOLE_DE, OBJECT_DE = 0.3, 0.5


def mean_lab(pixels8: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of the mean 8-bit sRGB colour of *pixels8* (..., 3)."""
    rgb = pixels8.reshape(-1, 3).astype(float).mean(axis=0) / 255.0
    return linear_srgb_to_lab(srgb_decode(rgb))


def reference_swatch(settings, design, width: int, height: int, size: int) -> tuple[np.ndarray, np.ndarray]:
    """(swatch (size, size, 3) uint8, cells wholly on the object (size, size) bool) of *design* from the
    core's direct renderer: the view at width × height, the square around the object's mask, area mean."""
    basis = environment_basis(settings.environment)
    w = paint_weights(design)
    img = render_linear(settings.scene(), basis, [w, w], width, height, coat=settings.clear_coat())
    mask = gbuffer(settings.scene(), width, height).mask
    ys, xs = np.nonzero(mask)
    x0, x1, y0, y1 = xs.min(), xs.max() + 1, ys.min(), ys.max() + 1
    side = max(x1 - x0, y1 - y0) * (1 + 2 * SWATCH_MARGIN)
    py, px = np.mgrid[0:height, 0:width] + 0.5
    cx = np.floor((px - ((x0 + x1) / 2 - side / 2)) / side * size).astype(int)
    cy = np.floor((py - ((y0 + y1) / 2 - side / 2)) / side * size).astype(int)
    inside = (cx >= 0) & (cx < size) & (cy >= 0) & (cy < size)
    cell = (cy * size + cx)[inside]
    count = np.bincount(cell, minlength=size * size)
    on = np.bincount(cell, weights=mask[inside].astype(float), minlength=size * size)
    acc = np.stack(
        [np.bincount(cell, weights=img[..., c][inside], minlength=size * size) for c in range(3)], -1
    )
    lin = acc / np.maximum(count, 1)[:, None]
    return to_display(lin.reshape(size, size, 3), settings.exposure_ev), (on == count).reshape(size, size)


@pytest.fixture
def win(qtbot, tmp_path):
    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    w = MainWindow(sink=sink, ask_on_close=False)
    qtbot.addWidget(w)
    w.resize(1200, 800)
    w.show()
    qtbot.waitExposed(w)
    return w


def wait_main_source(qtbot, win: MainWindow) -> None:
    view = win.view_panel.view
    view.wait_idle(60000)
    grid = win.designer_panel.variations
    qtbot.waitUntil(
        lambda: (
            grid.source == "main view" and view.basis is not None and grid.swatches.source is view.basis.core
        ),
        timeout=60000,
    )


def test_variations_are_the_object_of_the_main_view_and_a_click_applies_one(qtbot, win: MainWindow) -> None:
    grid = win.designer_panel.variations
    view = win.view_panel.view
    win.view_panel.shape.setCurrentText("speedshape")
    wait_main_source(qtbot, win)
    settings = win.view_model.settings
    assert settings.shape == "speedshape"
    enabled = [i for i in range(9) if grid.cells[i] is not None]
    assert len(enabled) == 7  # the centre and the six face variations (lighter … hue −) at step 5
    # the icons shown are the swatches
    for i in enabled:
        icon = grid.buttons[i].icon().pixmap(grid.buttons[i].iconSize()).toImage()
        assert (icon.width(), icon.height()) == (VARIATION_PX, VARIATION_PX)
        c = icon.pixelColor(VARIATION_PX // 2, VARIATION_PX // 2)
        assert (c.red(), c.green(), c.blue()) == tuple(
            int(v) for v in grid.images[i][VARIATION_PX // 2, VARIATION_PX // 2]
        )
    # the images differ as the designs differ
    for i in enabled:
        for j in enabled:
            if i < j:
                assert not np.array_equal(grid.images[i], grid.images[j]), (
                    grid.buttons[i].text(),
                    grid.buttons[j].text(),
                )
    labels = {grid.buttons[i].text(): i for i in enabled}
    assert view.basis is not None
    w, h = view.basis.size
    refs = {}
    for name in ("lighter", "current", "darker", "hue +"):
        i = labels[name]
        ref, full = reference_swatch(settings, grid.cells[i], w, h, VARIATION_PX)
        refs[name] = ref
        de_whole = np.linalg.norm(mean_lab(grid.images[i]) - mean_lab(ref))
        de_object = np.linalg.norm(mean_lab(grid.images[i][full]) - mean_lab(ref[full]))
        assert full.sum() > 40, "the object covers whole swatch cells"
        assert de_whole < WHOLE_DE and de_object < OBJECT_DE, (name, de_whole, de_object)
    _, full = reference_swatch(settings, grid.cells[4], w, h, VARIATION_PX)
    L = {n: mean_lab(grid.images[labels[n]][full])[0] for n in ("lighter", "current", "darker")}
    assert L["lighter"] > L["current"] + 1.0 > L["darker"] + 2.0
    # a click on "lighter" applies it; the centre then shows exactly what "lighter" showed
    lighter, shown = grid.cells[labels["lighter"]], grid.images[labels["lighter"]].copy()
    qtbot.mouseClick(grid.buttons[labels["lighter"]], LEFT, pos=QPoint(10, 10))
    assert win.document.design == lighter
    assert np.array_equal(grid.images[4], shown)
    assert win.view_model.designs is not None and win.view_model.designs[0] == lighter
    # another shape: the swatches follow the main view
    win.view_panel.shape.setCurrentText("sphere")
    assert win.view_model.settings.shape == "sphere"
    wait_main_source(qtbot, win)
    assert not np.array_equal(grid.images[4], shown)
    ref, full = reference_swatch(win.view_model.settings, lighter, *view.basis.size, VARIATION_PX)
    assert np.linalg.norm(mean_lab(grid.images[4]) - mean_lab(ref)) < WHOLE_DE
    # another environment: lit by the sky, still the direct renderer's colour
    booth = grid.images[4].copy()
    combo = win.view_panel.environment
    combo.setCurrentIndex([combo.itemData(i) for i in range(combo.count())].index("sky"))
    assert win.view_model.settings.environment == "sky"
    wait_main_source(qtbot, win)
    assert not np.array_equal(grid.images[4], booth)
    ref, full = reference_swatch(win.view_model.settings, lighter, *view.basis.size, VARIATION_PX)
    assert np.linalg.norm(mean_lab(grid.images[4][full]) - mean_lab(ref[full])) < OBJECT_DE


def test_a_panel_without_a_view_renders_on_its_own_sphere(qtbot) -> None:
    from ui.models.designer import DesignerModel
    from ui.models.document import DesignDocument

    panel = DesignerPanel(DesignerModel(DesignDocument()))
    qtbot.addWidget(panel)
    grid = panel.variations
    assert grid.source == "own"
    img = grid.images[4]
    background = img[0, 0]
    covered = (np.abs(img.astype(int) - background.astype(int)).sum(-1) > 6).mean()
    # a sphere: the object covers π/4 of its bounding square, shrunk by the margin
    assert covered == pytest.approx(np.pi / 4 / (1 + 2 * SWATCH_MARGIN) ** 2, abs=0.06)
