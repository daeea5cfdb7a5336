"""Stylist's day, driven through the real main window with mouse clicks and key presses only.

File → New design, pick a metallic from the full 6000-paint demo library, edit it (whole-arrow drag on the
a*b* plot, the hue value typed, the face Lab typed, a variation clicked), undo/redo with Ctrl+Z /
Ctrl+Shift+Z, mood-board eyedroppers with the automatic face/flop swap (and without it), screen sampling
outside the board and the gloss blend over a drag, then Save / reopen / Export XML and CxF. Every number
is checked against an independent expectation: the sRGB → CIELAB closed form for grey patches, the
pixel geometry of the plot, the rotation of (a*, b*), the face = Lab at 15° and flop = Lab beyond
θ_clamp definitions of the model, and the file contents parsed here.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt, QTimer
from PySide6.QtGui import QColor, QPalette
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QLineEdit, QMenu, QMessageBox, QWidget

from tests.ui.dialogs import enter_file_name
from ui.app import MainWindow
from ui.demo import patch_image
from ui.models.document import DEFAULT_DESIGN
from ui.models.measure_db import LocalSink
from ui.widgets.library_screen import LibraryScreen
from ui.widgets.moodboard_screen import MoodBoardScreen

pytestmark = [pytest.mark.qt]
LEFT = Qt.MouseButton.LeftButton
CTRL = Qt.KeyboardModifier.ControlModifier
DARK, LIGHT, SCREEN = 0.2, 0.6, 0.8  # sRGB-encoded greys of the two board patches and the screen patch


def grey_L(v: float) -> float:
    """CIE L* of an sRGB-encoded grey *v* (closed form: IEC 61966-2-1 decoding, then CIE 1976 L*)."""
    v = round(v * 255) / 255  # the PNG / screen stores 8 bits
    y = v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4
    return 116.0 * y ** (1 / 3) - 16.0 if y > (6 / 29) ** 3 else y * (29 / 3) ** 3


def click_center(qtbot, widget: QWidget) -> None:
    qtbot.mouseClick(widget, LEFT, pos=widget.rect().center())


def click_box(qtbot, box: QWidget) -> None:
    """Click a check box on its indicator (the box may be wider than its text)."""
    qtbot.mouseClick(box, LEFT, pos=QPoint(8, box.height() // 2))


def type_into(qtbot, edit: QLineEdit, text: str) -> None:
    """Select what is there, type *text*, press Enter."""
    click_center(qtbot, edit)
    qtbot.keyClick(edit, Qt.Key.Key_A, CTRL)
    qtbot.keyClicks(edit, text)
    qtbot.keyClick(edit, Qt.Key.Key_Return)


def when_shown(get, act) -> None:
    """Run *act(widget)* as soon as ``get()`` returns a visible widget (a modal dialog about to open)."""

    def poll() -> None:
        w = get()
        if w is None or not w.isVisible():
            QTimer.singleShot(20, poll)
            return
        QTimer.singleShot(150, lambda: act(w))  # let the dialog settle (a file dialog lists its folder)

    QTimer.singleShot(20, poll)


def answer_file_dialog(holder, path, tries: int = 20) -> None:
    """Type *path* into the next file dialog of *holder* and press Enter (again, a little later, while
    the dialog is still busy listing its folder and clears what was typed)."""

    def act(dlg) -> None:
        enter_file_name(dlg.findChild(QLineEdit, "fileNameEdit"), path)
        left[0] -= 1
        if dlg.isVisible() and left[0] > 0:
            QTimer.singleShot(200, lambda: act(dlg) if dlg.isVisible() else None)

    left = [tries]
    when_shown(lambda: holder.file_dialog, act)


def file_menu(qtbot, win: MainWindow, name: str, path=None) -> None:
    """Click File, then the item *name*; a file dialog it opens gets *path* typed in."""
    if path is not None:
        answer_file_dialog(win, path)
    bar, menu = win.menuBar(), win.file_menu
    qtbot.mouseClick(bar, LEFT, pos=bar.actionGeometry(menu.menuAction()).center())
    qtbot.waitUntil(menu.isVisible)
    action = win.file_actions[name]
    qtbot.mouseClick(menu, LEFT, pos=menu.actionGeometry(action).center())
    qtbot.waitUntil(lambda: not menu.isVisible())


def show_tab(qtbot, win: MainWindow, title: str) -> QWidget:
    bar = win.tabs.tabBar()
    i = [win.tabs.tabText(k) for k in range(win.tabs.count())].index(title)
    qtbot.mouseClick(bar, LEFT, pos=bar.tabRect(i).center())
    assert win.tabs.currentIndex() == i
    screen = win.screens[title]
    content = screen.content() if hasattr(screen, "content") else screen
    qtbot.waitUntil(content.isVisible)
    return content


@pytest.fixture
def window(qtbot, tmp_path):
    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    win = MainWindow(sink=sink)  # closed below, not by qtbot: its close would ask about unsaved changes
    win.resize(1500, 950)
    win.move(0, 0)
    win.show()
    qtbot.waitExposed(win)
    win.activateWindow()
    qtbot.waitUntil(win.isActiveWindow)
    yield win
    if win.isVisible():
        win.ask_on_close = False
        win.view_panel.view.wait_idle()
        win.close()


def test_stylist_journey(qtbot, window, tmp_path):
    win, doc = window, window.document
    pick_design_from_library(qtbot, win)
    edit_with_plots_and_values(qtbot, win)
    moodboard_eyedroppers(qtbot, win, tmp_path)
    own_environment(qtbot, win, tmp_path)
    save_reopen_export(qtbot, win, tmp_path)
    assert doc.design is not DEFAULT_DESIGN
    win.view_panel.view.wait_idle()


def pick_design_from_library(qtbot, win: MainWindow) -> None:
    doc = win.document
    win.designer_panel.values["gloss"].setFocus()
    file_menu(qtbot, win, "New design")
    assert doc.design == DEFAULT_DESIGN and doc.name == "untitled"
    lib_screen = show_tab(qtbot, win, "Library")
    assert isinstance(lib_screen, LibraryScreen)
    lib = lib_screen.model.library
    assert len(lib) == 6000  # the full demo library
    # narrow the list: metallics+pearls → neutral → light in the hierarchy, pearls unticked
    tree = lib_screen.tree
    node = tree.topLevelItem(0)
    for name in ("metallics+pearls", "neutral", "light"):
        assert node is not None
        kids = map(node.child, range(node.childCount()))
        node = next(k for k in kids if k is not None and k.text(0) == name)
    assert node is not None
    tree.scrollToItem(node)  # opens its parents, as clicking their arrows would
    qtbot.mouseClick(tree.viewport(), LEFT, pos=tree.visualItemRect(node).center())
    click_box(qtbot, lib_screen.type_boxes["pearl"])
    expected = np.flatnonzero(lib_screen.model.filter.mask(lib))
    assert expected.size and all(lib.types[r] == "metallic" for r in expected)
    # the thumbnails are made in the background; every listed paint renders
    qtbot.waitUntil(lambda: lib_screen.idle, timeout=120_000)
    thumbs = lib_screen.thumbs
    assert thumbs.count() == expected.size and lib_screen.count.text() == f"{expected.size} paints match"
    assert all(not thumbs.item(i).icon().isNull() for i in range(thumbs.count()))
    # double-click a thumbnail: that paint becomes the design
    item = thumbs.item(thumbs.count() // 2)
    row = lib_screen.row_of(item)
    thumbs.scrollToItem(item)
    pos = thumbs.visualItemRect(item).center()
    qtbot.mouseClick(thumbs.viewport(), LEFT, pos=pos)
    qtbot.mouseDClick(thumbs.viewport(), LEFT, pos=pos)
    d = doc.design
    assert doc.undo_label == f"library {lib.codes[row]}"
    assert d.gloss_gu == pytest.approx(float(lib.gloss_gu[row]), abs=1e-9)
    # the fit passes near the measured colour at every library angle (a few ΔE at most)
    fitted = d.lab_at(np.asarray(lib.angles_deg))
    assert float(np.max(np.linalg.norm(fitted - lib.lab[row], axis=-1))) < 12.0
    assert d.travel_deg is not None  # a metallic: the journey goes on with its flop
    show_tab(qtbot, win, "Design")


def edit_with_plots_and_values(qtbot, win: MainWindow) -> None:
    doc, panel = win.document, win.designer_panel
    ab = panel.ab
    r = ab.plot_rect()
    per_px = 160.0 / r.width()  # the plot spans a*, b* = -80 … 80 across its square
    # --- drag the arrowhead (face) to a point: a*, b* follow the pixel, L* kept
    face_px = ab.handles()["face"]
    to = QPoint(round(r.center().x() + 0.25 * r.width()), round(r.center().y() - 0.2 * r.height()))
    L_before = doc.design.face[0]
    qtbot.mousePress(ab, LEFT, pos=QPoint(round(face_px.x()), round(face_px.y())))
    qtbot.mouseMove(ab, to)
    qtbot.mouseRelease(ab, LEFT, pos=to)
    assert doc.design.face[1] == pytest.approx((to.x() - r.center().x()) * per_px, abs=1e-6)
    assert doc.design.face[2] == pytest.approx((r.center().y() - to.y()) * per_px, abs=1e-6)
    assert doc.design.face[0] == L_before and doc.undo_label == "move face"
    # --- whole-arrow drag on the shaft: both ends move by the drag, L* kept
    d0 = doc.design
    h = ab.handles()
    mid = (h["face"] + h["flop"]) / 2
    start = QPoint(round(mid.x()), round(mid.y()))
    assert ab.on_shaft(start.toPointF())
    dx, dy = 12, -8
    qtbot.mousePress(ab, LEFT, pos=start)
    qtbot.mouseMove(ab, start + QPoint(dx // 2, dy // 2))
    qtbot.mouseMove(ab, start + QPoint(dx, dy))
    qtbot.mouseRelease(ab, LEFT, pos=start + QPoint(dx, dy))
    d1 = doc.design
    for before, after in ((d0.face, d1.face), (d0.flop, d1.flop)):
        assert after[0] == pytest.approx(before[0], abs=1e-9)
        assert after[1] - before[1] == pytest.approx(dx * per_px, abs=1e-6)
        assert after[2] - before[2] == pytest.approx(-dy * per_px, abs=1e-6)
    assert doc.undo_label == "move arrow"
    # --- hue typed into the slider's value box: (a*, b*) of face and flop rotate by 30°
    type_into(qtbot, panel.values["hue"].lineEdit(), "30")
    d2 = doc.design
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    for before, after in ((d1.face, d2.face), (d1.flop, d2.flop)):
        assert after[1] == pytest.approx(c * before[1] - s * before[2], abs=1e-6)
        assert after[2] == pytest.approx(s * before[1] + c * before[2], abs=1e-6)
        assert after[0] == pytest.approx(before[0], abs=1e-6)
    assert panel.hue.value() == 0 and panel.values["hue"].value() == 0  # relative edit, applied
    # --- the face Lab typed in; gloss typed into its value box
    type_into(qtbot, panel.lab_edits["face"], "64, 22.5, -31")
    assert doc.design.face == (64.0, 22.5, -31.0)
    assert doc.design.flop == d2.flop
    type_into(qtbot, panel.values["gloss"].lineEdit(), "40")
    assert doc.design.gloss_gu == 40.0 and panel.gloss.value() == 40
    type_into(qtbot, panel.lab_edits["flop"], "oops")
    assert "Refused: flop" in panel.status.text() and doc.design.gloss_gu == 40.0
    # --- a variation: rendered on the object (a shaded panel, many colours), click to accept
    grid = panel.variations
    lighter = grid.buttons[0]
    assert lighter.text() == "lighter"
    icon = lighter.icon().pixmap(lighter.iconSize()).toImage()
    colours = {icon.pixel(x, y) for x in range(icon.width()) for y in range(icon.height())}
    assert len(colours) > 40  # shaded, not a flat swatch
    assert lighter.fontMetrics().horizontalAdvance("more chroma") <= lighter.width()
    prior = doc.design
    click_center(qtbot, lighter)
    step = grid.degree.value()
    assert doc.design.face == pytest.approx((prior.face[0] + step, *prior.face[1:]), abs=1e-9)
    # --- undo / redo from the keyboard
    qtbot.keyClick(win, Qt.Key.Key_Z, CTRL)
    assert doc.design == prior
    qtbot.keyClick(win, Qt.Key.Key_Z, CTRL | Qt.KeyboardModifier.ShiftModifier)
    assert doc.design.face[0] == pytest.approx(prior.face[0] + step, abs=1e-9)


def moodboard_eyedroppers(qtbot, win: MainWindow, tmp_path) -> None:
    doc = win.document
    screen = show_tab(qtbot, win, "Mood board")
    assert isinstance(screen, MoodBoardScreen)
    path = patch_image(tmp_path / "greys.png", ((DARK,) * 3, (LIGHT,) * 3), size=40)
    answer_file_dialog(screen, path)
    click_center(qtbot, screen.add_button)
    model = win.moodboard
    assert len(model.board.images) == 1
    canvas = screen.canvas
    x0, y0, _w, _h = model.image_rect(0)  # 80 × 40 board pixels at zoom 1
    dark_at = QPoint(int(x0) + 20, int(y0) + 20)
    light_at = QPoint(int(x0) + 60, int(y0) + 20)
    tools = {b.text().split()[0]: b for b in screen.tools.buttons()}

    def drop(tool: str, *points: QPoint) -> None:
        click_center(qtbot, tools[tool])
        qtbot.mousePress(canvas, LEFT, pos=points[0])
        for p in points[1:]:
            qtbot.mouseMove(canvas, p)
        qtbot.mouseRelease(canvas, LEFT, pos=points[-1])

    # flop on the light grey, then face on the dark grey: the face is darker → swapped (thesis §3.5.2)
    assert screen.auto_swap.isChecked()
    drop("flop", light_at)
    drop("face", dark_at)
    assert model.swapped and "swapped" in screen.readout.text()
    assert doc.design.face == pytest.approx((grey_L(LIGHT), 0.0, 0.0), abs=1e-6)
    assert doc.design.flop == pytest.approx((grey_L(DARK), 0.0, 0.0), abs=1e-6)
    # without auto swap a retroreflective (darker face) design is kept as sampled
    click_box(qtbot, screen.auto_swap)
    assert not model.auto_swap
    drop("face", dark_at)
    assert doc.design.face == pytest.approx((grey_L(DARK), 0.0, 0.0), abs=1e-6)
    assert doc.design.flop == pytest.approx((grey_L(LIGHT), 0.0, 0.0), abs=1e-6)
    assert not model.swapped
    # screen sampling: drag the face eyedropper off the board onto another window's colour
    patch = QWidget()
    qtbot.addWidget(patch)
    patch.setWindowFlag(Qt.WindowType.FramelessWindowHint)
    patch.setAttribute(Qt.WidgetAttribute.WA_ShowWithoutActivating)
    pal = patch.palette()
    v = round(SCREEN * 255)
    pal.setColor(QPalette.ColorRole.Window, QColor(v, v, v))
    patch.setPalette(pal)
    patch.setAutoFillBackground(True)
    patch.setGeometry(1520, 40, 60, 60)
    patch.show()
    qtbot.waitExposed(patch)
    qtbot.wait(50)
    target = canvas.mapFromGlobal(patch.mapToGlobal(QPoint(30, 30)))
    assert not canvas.rect().contains(target)
    drop("face", dark_at, target)
    assert doc.design.face == pytest.approx((grey_L(SCREEN), 0.0, 0.0), abs=1e-6)
    patch.close()
    win.activateWindow()  # what the window manager does when the user clicks back into the viewer
    qtbot.waitUntil(win.isActiveWindow)
    # gloss blended over the frames of one drag: uniform (contrast 0) then the dark/light edge
    screen.gloss_weight.setFocus()
    qtbot.keyClick(screen.gloss_weight, Qt.Key.Key_A, CTRL)
    qtbot.keyClicks(screen.gloss_weight, "0.6")
    qtbot.keyClick(screen.gloss_weight, Qt.Key.Key_Return)
    assert model.gloss_weight == 0.6
    qtbot.keyClick(screen.radius, Qt.Key.Key_A, CTRL)
    qtbot.keyClicks(screen.radius, "4")
    qtbot.keyClick(screen.radius, Qt.Key.Key_Return)
    assert model.radius == 4
    edge = QPoint(int(x0) + 40, int(y0) + 20)
    drop("gloss", dark_at, edge)
    # contrast at the edge = luma(light) − luma(dark) of the 8-bit greys; 0.5 contrast = 100 GU; the
    # blend is (1 − w)·0 + w·sample with w = 0.6
    contrast = (round(LIGHT * 255) - round(DARK * 255)) / 255
    assert doc.design.gloss_gu == pytest.approx(0.6 * min(100.0, contrast / 0.5 * 100.0), abs=1e-6)
    # one drag = one undo step
    g = doc.design.gloss_gu
    qtbot.keyClick(win, Qt.Key.Key_Z, CTRL)
    assert doc.design.gloss_gu != g
    qtbot.keyClick(win, Qt.Key.Key_Z, CTRL | Qt.KeyboardModifier.ShiftModifier)
    assert doc.design.gloss_gu == g


def own_environment(qtbot, win: MainWindow, tmp_path) -> None:
    """File → Load environment: with the 3D view's loader a file that is no HDR image is refused in a
    message box and the view keeps its environment; without it the item is disabled and says why."""
    action = win.file_actions["Load environment (HDR)"]
    if not callable(getattr(win.view_model, "load_environment", None)):
        assert not action.isEnabled() and "not in this build" in action.toolTip()
        return
    assert action.isEnabled()
    bad = tmp_path / "not-an-image.hdr"
    bad.write_bytes(b"#?RADIANCE\nthis is no picture\n")
    before = win.view_model.settings
    file_menu(qtbot, win, "Load environment (HDR)", bad)
    assert win.error_box is not None and win.error_box.isVisible()
    assert "not-an-image.hdr" in win.error_box.text()
    assert win.view_model.settings == before
    click_center(qtbot, win.error_box.button(QMessageBox.StandardButton.Ok))
    # an own HDR: a dim sky with one bright sun, 64 × 32 equirectangular
    from station.render.hdr_io import write_hdr

    sky = np.full((32, 64, 3), 0.2, np.float32)
    sky[6:9, 20:23] = 40.0
    own = tmp_path / "own-sky.hdr"
    write_hdr(own, sky)
    file_menu(qtbot, win, "Load environment (HDR)", own)
    assert win.view_model.settings.environment == str(own)
    assert f"environment {own}" in win.statusBar().currentMessage()


def save_reopen_export(qtbot, win: MainWindow, tmp_path) -> None:
    doc, files = win.document, win.files
    click_center(qtbot, win.designer_panel.palette_keep)
    assert set(files.unsaved()) == {"design", "palette", "moodboard"}
    assert win.isWindowModified()  # the title's [*] marker
    saved = doc.design
    design_path, palette_path, board_path = (
        tmp_path / "silver-grey.json",
        tmp_path / "palette.json",
        tmp_path / "board.json",
    )
    file_menu(qtbot, win, "Save design", design_path)  # no file yet: Save asks where
    file_menu(qtbot, win, "Save As palette", palette_path)
    file_menu(qtbot, win, "Save As mood board", board_path)
    assert files.unsaved() == []
    assert not win.isWindowModified() and win.windowTitle().startswith("silver-grey")
    data = json.loads(design_path.read_text())
    assert data["schema"] == "cacad.design/1" and data["name"] == "silver-grey"
    assert data["face"] == list(saved.face) and data["flop"] == list(saved.flop)
    assert data["travel_deg"] == saved.travel_deg and data["gloss_gu"] == saved.gloss_gu
    pal = json.loads(palette_path.read_text())
    assert [e["design"]["face"] for e in pal["entries"]] == [list(saved.face)]
    board = json.loads(board_path.read_text())
    assert [i["path"] for i in board["boards"][0]["images"]] == [str(tmp_path / "greys.png")]

    # New everything, then reopen: the same design, palette and board come back
    for kind in ("design", "palette", "mood board"):
        file_menu(qtbot, win, f"New {kind}")
    assert doc.design == DEFAULT_DESIGN and win.designer.palette == [] and not win.moodboard.board.images
    file_menu(qtbot, win, "Open design", design_path)
    assert doc.design.face == saved.face and doc.design.flop == saved.flop
    assert doc.design.gloss_gu == saved.gloss_gu and doc.name == "silver-grey"
    file_menu(qtbot, win, "Open palette", palette_path)
    assert [d.face for _n, d in win.designer.palette] == [saved.face]
    file_menu(qtbot, win, "Open mood board", board_path)
    assert len(win.moodboard.board.images) == 1 and win.moodboard.pixels

    # a bad file: a visible message, nothing lost
    bad = tmp_path / "broken.json"
    bad.write_text('{"schema": "cacad.design/1", "face": [50, 0]')
    current = doc.design
    file_menu(qtbot, win, "Open design", bad)
    assert win.error_box is not None and win.error_box.isVisible()
    assert "broken.json" in win.error_box.text()
    assert doc.design == current and files.paths["design"] == design_path
    click_center(qtbot, win.error_box.button(QMessageBox.StandardButton.Ok))

    # export: XML and CxF hold the face at 15° and the flop beyond θ_clamp
    xml_path, cxf_path = tmp_path / "silver-grey.xml", tmp_path / "silver-grey.cxf"
    file_menu(qtbot, win, "Export design as XML", xml_path)
    file_menu(qtbot, win, "Export design as CxF", cxf_path)
    check_export_xml(xml_path.read_bytes(), saved)
    check_export_cxf(cxf_path.read_bytes(), saved)

    # unsaved changes: closing asks; Cancel keeps the window, Discard closes it
    type_into(qtbot, win.designer_panel.values["gloss"].lineEdit(), "12")
    assert files.unsaved() == ["design"]
    when_shown(
        lambda: win.unsaved_box,
        lambda box: QTest.mouseClick(box.button(QMessageBox.StandardButton.Cancel), LEFT),
    )
    win.close()
    assert win.isVisible()
    when_shown(
        lambda: win.unsaved_box,
        lambda box: QTest.mouseClick(box.button(QMessageBox.StandardButton.Discard), LEFT),
    )
    win.view_panel.view.wait_idle()
    win.close()
    assert not win.isVisible()
    assert json.loads(design_path.read_text())["gloss_gu"] == saved.gloss_gu  # the file kept


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def xml_number(text: str | None) -> float:
    """A number written as an XML attribute or element text (present)."""
    assert text is not None
    return float(text)


def check_export_xml(data: bytes, design) -> None:
    """Every Lab at 15° is the face; at 110° (beyond θ_clamp) the flop, when travel <= 110°."""
    root = ET.fromstring(data)
    assert _local(root.tag) == "colors"
    (colour,) = [el for el in root if _local(el.tag) == "color"]
    assert colour.get("name") == "silver-grey" and colour.get("role") == "design"
    gloss = [el for el in colour if _local(el.tag) == "gloss"]
    assert xml_number(gloss[0].text) == pytest.approx(design.gloss_gu, abs=1e-4)
    labs = [el for el in colour.iter() if _local(el.tag) == "lab"]
    assert {xml_number(el.get("aspecularDeg")) for el in labs} == {15.0, 25.0, 45.0, 75.0, 110.0}
    for el in labs:
        lab = (xml_number(el.get("L")), xml_number(el.get("a")), xml_number(el.get("b")))
        angle = xml_number(el.get("aspecularDeg"))
        if angle == 15.0:
            assert lab == pytest.approx(design.face, abs=1e-4)
        if design.travel_deg is not None and angle >= design.travel_deg:
            assert lab == pytest.approx(design.flop, abs=1e-4)


def check_export_cxf(data: bytes, design) -> None:
    """CxF3: the object named after the file, CIELab at 45as15 = face and at 45as110 = flop."""
    root = ET.fromstring(data)
    assert _local(root.tag) == "CxF"
    objects = [el for el in root.iter() if _local(el.tag) == "Object"]
    assert [o.get("Name") for o in objects] == ["silver-grey"]
    values = {}
    for el in objects[0].iter():
        if _local(el.tag) == "ColorCIELab":
            kids = {_local(k.tag): xml_number(k.text) for k in el}
            values[el.get("ColorSpecification")] = (kids["L"], kids["A"], kids["B"])
    assert values["CS45as15"] == pytest.approx(design.face, abs=1e-4)
    if design.travel_deg is not None and design.travel_deg <= 110.0:
        assert values["CS45as110"] == pytest.approx(design.flop, abs=1e-4)


def click_menu_item(qtbot, win: MainWindow, menu_title: str, item: str) -> None:
    """Click a menu of the menu bar by its title, then its item by text."""
    bar = win.menuBar()
    (action,) = [a for a in bar.actions() if a.text() == menu_title]
    menu = action.menu()
    assert isinstance(menu, QMenu)
    qtbot.mouseClick(bar, LEFT, pos=bar.actionGeometry(action).center())
    qtbot.waitUntil(menu.isVisible)
    (target,) = [a for a in menu.actions() if a.text() == item]
    qtbot.mouseClick(menu, LEFT, pos=menu.actionGeometry(target).center())


def test_stylist_in_service_mode_opens_a_file_and_stores_it_on_the_service(qtbot, tmp_path):
    """Service mode: File → Open design reads the stylist's own file, Service → Save current design
    stores it (GET /api/v1/designs returns the same face, flop, travel and gloss)."""
    from station.model.design_io import save_design
    from tests.api.conftest import make_api
    from ui.models.measure_db import ServiceSink
    from ui.models.service import ServiceClient

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    win = None
    try:
        token = api.tokens[next(r for r in api.tokens if r.value == "stylist")]
        service = ServiceClient("http://testserver", token, client=api.http)
        win = MainWindow(service=service, sink=ServiceSink(service, tmp_path / "outbox.sqlite3"))
        win.resize(1200, 800)
        win.show()
        qtbot.waitExposed(win)
        mine = DEFAULT_DESIGN.replace(face=(61.5, -12.0, 33.0), flop=(30.0, -6.0, 20.0), gloss_gu=64.0)
        path = save_design(mine.replace(name="lime"), tmp_path / "lime.json")
        file_menu(qtbot, win, "Open design", path)
        assert win.document.name == "lime" and win.files.unsaved() == []
        click_menu_item(qtbot, win, "&Service", "Save current design")
        assert "saved as design" in win.statusBar().currentMessage()
        rows = api.client.get("/api/v1/designs", headers={"Authorization": f"Bearer {token}"}).json()
        (stored,) = [r for r in rows["data"] if r["name"] == "lime"]
        d = stored["design"]
        assert (d["face"], d["flop"], d["travel_deg"], d["gloss_gu"]) == (
            list(mine.face),
            list(mine.flop),
            mine.travel_deg,
            mine.gloss_gu,
        )
        win.view_panel.view.wait_idle()
        win.close()  # nothing unsaved: no question
        assert not win.isVisible()
    finally:
        if win is not None and win.isVisible():
            win.ask_on_close = False
            win.view_panel.view.wait_idle()
            win.close()
        gen.close()
