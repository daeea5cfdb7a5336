"""Library browser: type check boxes and the hierarchy filter the list, every filtered paint gets a
thumbnail (made in the background, with the progress indicator and Cancel), double-clicking one makes
it the design, ColorSnap (in the background) finds the brute-force nearest paint, and a match becomes
the design (undoably)."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtTest import QTest

from station.formulate.library import Library
from ui.models.document import DesignDocument
from ui.models.library import THUMB_SIZE, LibraryModel
from ui.widgets.library_screen import LibraryScreen

pytestmark = [pytest.mark.qt]


def _library(n: int = 60) -> Library:
    rng = np.random.default_rng(7)
    L45 = rng.uniform(25, 75, n)
    a, b = rng.uniform(-50, 50, n), rng.uniform(-50, 50, n)
    lab = np.stack(
        [
            np.stack([L45 + 12, a * 1.1, b * 1.1], -1),
            np.stack([L45, a, b], -1),
            np.stack([L45 - 15, a * 0.8, b * 0.8], -1),
        ],
        axis=1,
    )
    types = np.array(["solid", "metallic", "pearl"])[np.arange(n) % 3]
    return Library(
        "test",
        np.array([f"P{i:03d}" for i in range(n)]),
        types,
        rng.uniform(20, 95, n),
        (15.0, 45.0, 110.0),
        lab,
    )


def _wait_idle(qtbot, screen, timeout: int = 120_000) -> None:
    qtbot.waitUntil(lambda: screen.idle, timeout=timeout)


def _click_box(box) -> None:
    QTest.mouseClick(box, Qt.MouseButton.LeftButton, pos=QPoint(8, box.height() // 2))


def test_filters_and_colorsnap(qtbot):
    lib = _library()
    doc = DesignDocument()
    screen = LibraryScreen(LibraryModel(lib), doc)
    qtbot.addWidget(screen)
    screen.resize(1000, 700)
    screen.show()
    _wait_idle(qtbot, screen)
    assert screen.thumbs.count() == 60
    _click_box(screen.type_boxes["pearl"])
    _wait_idle(qtbot, screen)
    assert screen.thumbs.count() == 40 and "40 paints" in screen.count.text()
    # hierarchy: click the "solids" node → only solids (and not pearls) remain
    top = screen.tree.topLevelItem(0)
    assert top is not None
    solids = next(
        k for k in map(top.child, range(top.childCount())) if k is not None and k.text(0) == "solids"
    )
    # every hierarchy name is shown whole, not elided ("more…roma" was a defect)
    fm = screen.tree.fontMetrics()
    items = [screen.tree.topLevelItem(0)]
    while items:
        item = items.pop()
        assert item is not None
        rect = screen.tree.visualItemRect(item)
        if not rect.isEmpty():
            assert fm.horizontalAdvance(item.text(0)) <= screen.tree.columnWidth(0) - rect.left() + 4, (
                item.text(0)
            )
        items.extend(item.child(i) for i in range(item.childCount()))
    _click_tree_item(qtbot, screen.tree, solids)
    _wait_idle(qtbot, screen)
    assert screen.thumbs.count() == int(np.sum(lib.types == "solid")) == int(solids.text(1))

    threads: list[threading.Thread] = []
    real = screen.model.compute_snap

    def compute_snap(design, *args):
        threads.append(threading.current_thread())
        return real(design, *args)

    screen.model.compute_snap = compute_snap  # type: ignore[method-assign]
    QTest.mouseClick(screen.snap_btn, Qt.MouseButton.LeftButton)
    _wait_idle(qtbot, screen)
    assert threads and threads[0] is not threading.main_thread()  # ColorSnap ran off the GUI thread
    design_lab = doc.design.lab_at(np.array([15.0, 45.0, 110.0]))
    brute = np.linalg.norm(lib.lab - design_lab[None], axis=-1).sum(axis=1)  # ΣΔE*ab over the 3 angles
    assert screen.model.snap_result is not None
    assert screen.model.snap_result.matches[0].code == lib.codes[np.argmin(brute)]
    assert screen.model.snap_result.matches[0].sum_de == pytest.approx(brute.min(), rel=1e-9)
    assert screen.matches.count() == 5 and screen.cloud.data is not None
    assert screen.compare_model.designs is not None and screen.compare_model.designs[0] == doc.design
    QTest.mouseClick(screen.use_btn, Qt.MouseButton.LeftButton)
    best = int(np.argmin(brute))
    got = doc.design.lab_at(np.array([15.0, 45.0, 110.0]))
    # the match design is the model's FFTG fit of the paint: its misses are the fit's reported residuals
    from station.model import AspecularMeasurements, fit_fftg

    fit = fit_fftg(AspecularMeasurements((15.0, 45.0, 110.0), lib.lab[best], float(lib.gloss_gu[best])))
    np.testing.assert_allclose(np.linalg.norm(got - lib.lab[best], axis=-1), fit.residual_de, atol=1e-6)
    assert max(fit.residual_de) < 2.0
    doc.undo()
    assert not doc.can_undo
    screen.close()


def _double_click_item(qtbot, view, item) -> None:
    """A user's double-click: press and release, then the second press (Qt's double-click event) and
    release at the same point (the item view acts on a double-click only on the item it saw pressed)."""
    view.scrollToItem(item)
    pos = view.visualItemRect(item).center()
    QTest.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=pos)
    QTest.mouseDClick(view.viewport(), Qt.MouseButton.LeftButton, pos=pos)


def test_double_clicking_a_thumbnail_makes_that_paint_the_design(qtbot):
    lib = _library()
    doc = DesignDocument()
    screen = LibraryScreen(LibraryModel(lib), doc)
    qtbot.addWidget(screen)
    screen.resize(1000, 700)
    screen.show()
    _wait_idle(qtbot, screen)
    item = screen.thumbs.item(37)
    row = screen.row_of(item)
    assert item.text().startswith(lib.codes[row])
    _double_click_item(qtbot, screen.thumbs, item)
    assert doc.undo_label == f"library {lib.codes[row]}"
    # the design is the paint's fit: it passes through the measured colours within the fit's residuals
    from station.model import AspecularMeasurements, fit_fftg

    fit = fit_fftg(AspecularMeasurements((15.0, 45.0, 110.0), lib.lab[row], float(lib.gloss_gu[row])))
    assert doc.design == fit.design
    got = doc.design.lab_at(np.array([15.0, 45.0, 110.0]))
    np.testing.assert_allclose(np.linalg.norm(got - lib.lab[row], axis=-1), fit.residual_de, atol=1e-9)
    doc.undo()
    assert not doc.can_undo
    screen.close()


def _click_tree_item(qtbot, tree, item) -> None:
    tree.scrollToItem(item)
    rect = tree.visualItemRect(item)
    QTest.mouseClick(tree.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())


def _find(tree, text: str):
    from PySide6.QtWidgets import QTreeWidgetItemIterator

    it = QTreeWidgetItemIterator(tree)
    while it.value() is not None:
        if it.value().text(0) == text:
            return it.value()
        it += 1
    raise AssertionError(f"no tree node {text!r}")


def test_demo_library_metallics_all_render(qtbot):
    """On the full demo library, clicking "metallics" lists every matching paint, each rendered, made in
    the background with the progress indicator showing; the paints whose unconstrained fit left the
    Lab bound render too."""
    from station.formulate.demo import demo_library

    lib = demo_library()
    screen = LibraryScreen(LibraryModel(lib), DesignDocument())
    qtbot.addWidget(screen)
    screen.resize(1000, 700)
    screen.show()
    assert screen.thumbs.count() < len(lib)  # the thumbnails come from the background task
    node = _find(screen.tree, "metallics+pearls")
    _click_tree_item(qtbot, screen.tree, node)
    for box in (screen.type_boxes["pearl"], screen.type_boxes["solid"]):  # metallics only
        _click_box(box)
        assert not box.isChecked()
    expected = int(np.sum(lib.types == "metallic"))
    assert int(np.sum(screen.model.mask)) == expected
    shown: list[bool] = []

    def idle_noting_busy() -> bool:
        shown.append(screen.thumb_busy.isVisible())
        return screen.idle

    qtbot.waitUntil(idle_noting_busy, timeout=180_000)
    assert any(shown)  # the indicator appeared while the thumbnails were made
    assert screen.count.text() == f"{expected} paints match"
    assert screen.thumbs.count() == expected
    rows = [screen.row_of(screen.thumbs.item(i)) for i in range(expected)]
    assert sorted(rows) == np.flatnonzero(lib.types == "metallic").tolist()
    texts = [screen.thumbs.item(i).text() for i in range(screen.thumbs.count())]
    assert not [t for t in texts if "cannot render" in t]
    assert any(t.startswith("SYN-NM0003") for t in texts)  # a neutral metallic is listed too
    assert all(not screen.thumbs.item(i).icon().isNull() for i in range(screen.thumbs.count()))
    screen.close()


def test_cancel_stops_the_thumbnails_and_a_new_filter_replaces_them(qtbot, monkeypatch):
    """All 6000 paints take seconds: Cancel appears after 2 s and stops the list where it is; a new
    filter while thumbnails are being made lists only the new filter's paints. A quiet machine renders
    the filter's 3000 in about 2 s, before Cancel would appear, so after the filter's first 250 the
    thumbnails wait for Cancel to be clicked (a gate, not a time): the list is still being made when it is."""
    from station.formulate.demo import demo_library
    from ui.widgets.tasks import CANCEL_AFTER_MS

    lib = demo_library()
    model = LibraryModel(lib)
    render = model.thumbnail
    clicked = threading.Event()  # set once Cancel was clicked
    after_filter: list[int] = []  # thumbnails asked for since the new filter

    def gated(i: int, size: int = THUMB_SIZE) -> np.ndarray:
        if filtered.is_set():
            after_filter.append(i)
            if len(after_filter) > 250:
                clicked.wait(timeout=120)
        return render(i, size)

    filtered = threading.Event()
    monkeypatch.setattr(model, "thumbnail", gated)
    screen = LibraryScreen(model, DesignDocument())
    qtbot.addWidget(screen)
    screen.resize(1000, 700)
    screen.show()
    filtered.set()
    _click_box(screen.type_boxes["solid"])  # a new filter at once: metallics and pearls
    qtbot.waitUntil(lambda: screen.thumb_busy.cancel_btn.isVisible(), timeout=CANCEL_AFTER_MS + 20_000)
    QTest.mouseClick(screen.thumb_busy.cancel_btn, Qt.MouseButton.LeftButton)
    clicked.set()
    _wait_idle(qtbot, screen)
    n = screen.thumbs.count()
    assert 0 < n < 3000 and "thumbnails stopped" in screen.count.text()
    rows = {screen.row_of(screen.thumbs.item(i)) for i in range(n)}
    assert all(lib.types[r] != "solid" for r in rows)  # nothing of the first filter
    qtbot.wait(300)
    assert screen.thumbs.count() == n  # stopped means stopped
    # pearls only: a new task, all of them listed
    _click_box(screen.type_boxes["metallic"])
    _wait_idle(qtbot, screen)
    assert screen.thumbs.count() == int(np.sum(lib.types == "pearl"))
    screen.close()


def test_unrenderable_paint_is_noted_and_the_list_continues(qtbot, monkeypatch):
    from station.model.errors import FitError

    lib = _library(12)
    model = LibraryModel(lib)
    real = LibraryModel.thumbnail

    def thumbnail(self, i: int, size: int = 40):
        if i == 3:
            raise FitError("travel_deg: test paint outside the model")
        return real(self, i, size)

    monkeypatch.setattr(LibraryModel, "thumbnail", thumbnail)
    screen = LibraryScreen(model, DesignDocument())
    qtbot.addWidget(screen)
    screen.show()
    _wait_idle(qtbot, screen)
    assert screen.thumbs.count() == 12
    note = screen.thumbs.item(3).text()
    assert "cannot render: travel_deg: test paint outside the model" in note
    assert all("cannot render" not in screen.thumbs.item(i).text() for i in range(12) if i != 3)
    assert "1 cannot be rendered" in screen.count.text()
    screen.close()


def test_painting_the_lab_cloud_costs_a_few_calls_not_one_per_point(qtbot):
    """The installed PySide6 drops a reference to None on every call that returns nothing (under
    Python 3.11 the process aborts once None's count reaches zero); the cloud of 1500 points is one
    image, so a repaint costs a handful of such calls, and the points are drawn in their colours."""
    import sys

    from station.formulate.snap import view_data
    from ui.widgets.library_screen import LabCloud

    lib = _library(1500)
    model = LibraryModel(lib)
    result = model.snap(DesignDocument().design)
    cloud = LabCloud()
    qtbot.addWidget(cloud)
    cloud.resize(400, 300)
    cloud.set_data(view_data(lib, result, max_cloud=1500))
    cloud.show()
    qtbot.waitExposed(cloud)
    before = sys.getrefcount(None)
    for _ in range(20):
        cloud.repaint()
    assert before - sys.getrefcount(None) < 20 * 40
    img = cloud.grab().toImage()
    x, y = np.trunc(cloud.project(cloud._cloud[7])).astype(int)
    want = cloud._cloud_rgb[7]
    got = img.pixelColor(int(x) + 1, int(y) + 1)  # inside the 2×2 point (later points may cover it)
    colours = {tuple(int(v) for v in c) for c in cloud._cloud_rgb}
    assert (got.red(), got.green(), got.blue()) in colours | {tuple(int(v) for v in want)}
    cloud.close()
