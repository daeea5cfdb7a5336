"""Mood board tab: boards as tabs, images dragged and zoomed, face/flop/gloss eyedroppers with a live
preview of the design they make (thesis §3.5, Figs. 3.9–3.10).

Options beside the tools: automatic face/flop swap (§3.5.2), the eyedropper radius, and the blend of
gloss samples over the frames of a drag (§3.5.3). An eyedropper dragged off the board samples the
screen under the cursor (another window, a web page, a photo viewer).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QGuiApplication, QImage, QMouseEvent, QPainter, QPen, QWheelEvent
from PySide6.QtWidgets import (
    QButtonGroup,
    QCheckBox,
    QDoubleSpinBox,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QTabBar,
    QVBoxLayout,
    QWidget,
)

from station.design.moodboard import RADIUS_MAX
from station.design.palette import booklet, swatch
from station.errors import InputError
from ui.models.moodboard import EYEDROPPERS, MoodBoardModel
from ui.widgets.common import pixmap_from_array

TOOLS = ("move", *EYEDROPPERS)


def grab_screen(global_x: int, global_y: int, radius: int) -> tuple[np.ndarray, tuple[int, int]] | None:
    """sRGB pixels ``(h, w, 3)`` uint8 of the screen around a global position, and the position inside
    them; None when no screen is there."""
    from PySide6.QtCore import QPoint

    screen = QGuiApplication.screenAt(QPoint(global_x, global_y))
    if screen is None:
        return None
    geo = screen.geometry()
    x, y = global_x - geo.x(), global_y - geo.y()
    x0, y0 = max(0, x - radius), max(0, y - radius)
    img = screen.grabWindow(0, x0, y0, 2 * radius + 1, 2 * radius + 1).toImage()
    img = img.convertToFormat(QImage.Format.Format_RGB888)
    w, h = img.width(), img.height()
    if w == 0 or h == 0:
        return None
    buf = np.frombuffer(img.constBits(), np.uint8, count=img.bytesPerLine() * h)
    px = buf.reshape(h, img.bytesPerLine())[:, : 3 * w].reshape(h, w, 3).copy()
    return px, (min(x - x0, w - 1), min(y - y0, h - 1))


MARKER = {"face": QColor(255, 220, 0), "flop": QColor(0, 200, 255), "gloss": QColor(255, 255, 255)}


class BoardCanvas(QWidget):
    """Draws the current board; the active tool decides what a drag does."""

    def __init__(self, model: MoodBoardModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.tool = "move"
        self._drag: tuple[int, QPointF, float, float] | None = None
        self._dropping = False
        self._qimages: dict[str, tuple[object, QImage]] = {}
        self.setMinimumSize(320, 240)
        self.setMouseTracking(False)
        # a click on the board takes the keyboard from the option boxes: Ctrl+Z then undoes the drop
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        model.events.board.connect(self.update)
        model.events.eyedropper.connect(self._on_eyedropper)

    def _on_eyedropper(self, name: str, xy) -> None:
        self.update()

    def _qimage(self, path: str) -> QImage:
        px = self.model.pixels[path]
        if path not in self._qimages:
            import numpy as np

            buf = np.ascontiguousarray(np.round(px * 255).astype(np.uint8))
            h, w = buf.shape[:2]
            self._qimages[path] = (buf, QImage(buf.data, w, h, 3 * w, QImage.Format.Format_RGB888))
        return self._qimages[path][1]

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.fillRect(self.rect(), QColor(60, 60, 64))
        for i, im in enumerate(self.model.board.images):
            if im.path in self.model.pixels:
                p.drawImage(QRectF(*self.model.image_rect(i)), self._qimage(im.path))
        for name, (x, y) in self.model.eyedroppers.items():
            p.setPen(QPen(MARKER[name], 2))
            p.drawEllipse(QPointF(x, y), 7, 7)
            p.drawLine(QPointF(x - 11, y), QPointF(x + 11, y))
            p.drawLine(QPointF(x, y - 11), QPointF(x, y + 11))
            p.drawText(QPointF(x + 9, y - 9), name)
        p.end()

    def mousePressEvent(self, event: QMouseEvent) -> None:
        pos = event.position()
        if self.tool == "move":
            hit = self.model.hit(pos.x(), pos.y())
            if hit is not None:
                im = self.model.board.images[hit.index]
                self._drag = (hit.index, pos, im.x, im.y)
        else:
            self._dropping = True
            self.model.drop(self.tool, pos.x(), pos.y())

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        pos = event.position()
        if self._drag is not None:
            i, start, x0, y0 = self._drag
            self.model.move_image(i, x0 + pos.x() - start.x(), y0 + pos.y() - start.y())
        elif self._dropping:
            if self.rect().contains(pos.toPoint()):
                self.model.drop(self.tool, pos.x(), pos.y())
            else:  # off the board: the screen under the cursor
                g = event.globalPosition().toPoint()
                grabbed = grab_screen(g.x(), g.y(), self.model.radius)
                if grabbed is not None:
                    self.model.drop_pixels(self.tool, *grabbed)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if self._dropping:
            self.model.end_drop()
        self._drag = None
        self._dropping = False

    def wheelEvent(self, event: QWheelEvent) -> None:
        pos = event.position()
        hit = self.model.hit(pos.x(), pos.y())
        if hit is not None:
            im = self.model.board.images[hit.index]
            z = min(100.0, max(0.01, im.zoom * 1.1 ** (event.angleDelta().y() / 120.0)))
            self.model.zoom_image(hit.index, z)

    def closeEvent(self, event) -> None:
        self.model.events.board.disconnect(self.update)
        self.model.events.eyedropper.disconnect(self._on_eyedropper)
        super().closeEvent(event)


class MoodBoardScreen(QWidget):
    """Board tabs, tools, the canvas and the live preview of the current design."""

    def __init__(self, model: MoodBoardModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.tabs = QTabBar()
        self.canvas = BoardCanvas(model)
        self.tools = QButtonGroup(self)
        bar = QHBoxLayout()
        for t in TOOLS:
            b = QPushButton(t if t == "move" else f"{t} eyedropper")
            b.setCheckable(True)
            b.setChecked(t == "move")
            self.tools.addButton(b)
            b.clicked.connect(lambda _=False, name=t: self.set_tool(name))
            bar.addWidget(b)
        self.file_dialog: QFileDialog | None = None  # the open "Add image" dialog (tests drive it)
        add = QPushButton("Add image…")
        self.add_button = add
        add.clicked.connect(self._add_dialog)
        new_board = QPushButton("New board")
        new_board.clicked.connect(
            lambda: self.model.add_board(f"board {len(self.model.moodboard.boards) + 1}")
        )
        bar.addWidget(add)
        bar.addWidget(new_board)
        bar.addStretch(1)
        self.auto_swap = QCheckBox("auto swap face/flop")
        self.auto_swap.setToolTip(
            "Swap face and flop when the sampled face is darker than the flop (untick for a retroreflective colour)"
        )
        self.auto_swap.setChecked(model.auto_swap)
        self.auto_swap.toggled.connect(lambda on: setattr(self.model, "auto_swap", bool(on)))
        self.radius = QSpinBox()
        self.radius.setRange(0, RADIUS_MAX)
        self.radius.setValue(model.radius)
        self.radius.setSuffix(" px")
        self.radius.setToolTip("Eyedropper radius: the median colour of this disc is sampled")
        self.radius.valueChanged.connect(lambda v: setattr(self.model, "radius", int(v)))
        self.gloss_weight = QDoubleSpinBox()
        self.gloss_weight.setRange(0.05, 1.0)
        self.gloss_weight.setSingleStep(0.05)
        self.gloss_weight.setValue(model.gloss_weight)
        self.gloss_weight.setToolTip(
            "Gloss blend over frames: weight of each new gloss sample while dragging (1 = no blending)"
        )
        self.gloss_weight.valueChanged.connect(lambda v: setattr(self.model, "gloss_weight", float(v)))
        opts = QHBoxLayout()
        opts.addWidget(self.auto_swap)
        opts.addWidget(QLabel("radius"))
        opts.addWidget(self.radius)
        opts.addWidget(QLabel("gloss blend"))
        opts.addWidget(self.gloss_weight)
        opts.addWidget(QLabel("drag an eyedropper off the board to sample the screen"))
        opts.addStretch(1)
        self.preview = QLabel()
        self.preview_swatch = QLabel()
        self.readout = QLabel()
        self.readout.setWordWrap(True)
        side = QVBoxLayout()
        side.addWidget(QLabel("live preview"))
        side.addWidget(self.preview)
        side.addWidget(self.preview_swatch)
        side.addWidget(self.readout)
        side.addStretch(1)
        body = QHBoxLayout()
        body.addWidget(self.canvas, 1)
        body.addLayout(side)
        lay = QVBoxLayout(self)
        lay.addWidget(self.tabs)
        lay.addLayout(bar)
        lay.addLayout(opts)
        lay.addLayout(body, 1)
        self.tabs.currentChanged.connect(self._on_tab)
        model.events.board.connect(self._on_board)
        model.document.events.changed.connect(self._on_design)
        self._on_board()
        self._on_design(model.document.design)

    def set_tool(self, name: str) -> None:
        """Choose the canvas tool: move or one of the eyedroppers."""
        self.canvas.tool = name
        for b in self.tools.buttons():
            b.setChecked(b.text().split()[0] == name)

    def _add_dialog(self) -> None:
        dlg = QFileDialog(self, "Add image", "", "Images (*.png *.jpg *.jpeg)")
        dlg.setOption(QFileDialog.Option.DontUseNativeDialog, True)  # the same dialog on every desktop
        dlg.setFileMode(QFileDialog.FileMode.ExistingFile)
        self.file_dialog = dlg
        try:
            ok = dlg.exec() == QFileDialog.DialogCode.Accepted and bool(dlg.selectedFiles())
            path = dlg.selectedFiles()[0] if ok else ""
        finally:
            self.file_dialog = None
            dlg.deleteLater()
        if path:
            try:
                self.model.add_image(path, 10.0, 10.0)
            except InputError as exc:
                self.readout.setText(f"Refused: {exc}")

    def _on_tab(self, i: int) -> None:
        if 0 <= i < len(self.model.moodboard.boards):
            name = self.tabs.tabText(i)
            if name != self.model.current:
                self.model.select(name)

    def _on_board(self) -> None:
        names = [b.name for b in self.model.moodboard.boards]
        if [self.tabs.tabText(i) for i in range(self.tabs.count())] != names:
            self.tabs.blockSignals(True)
            while self.tabs.count():
                self.tabs.removeTab(0)
            for n in names:
                self.tabs.addTab(n)
            self.tabs.blockSignals(False)
        self.tabs.setCurrentIndex(names.index(self.model.current))

    def _on_design(self, design) -> None:
        self.preview.setPixmap(pixmap_from_array(booklet(design, 160)))
        self.preview_swatch.setPixmap(pixmap_from_array(swatch(design).pixels))
        self.readout.setText(
            "face L*a*b* "
            + ", ".join(f"{v:.1f}" for v in design.face)
            + "\nflop L*a*b* "
            + ", ".join(f"{v:.1f}" for v in design.flop)
            + f"\ngloss {design.gloss_gu:.0f} GU"
            + (
                "\nface and flop swapped (the face sample was darker)"
                if self.model.swapped and (self.model.document.undo_label or "").endswith("eyedropper")
                else ""
            )
        )

    def closeEvent(self, event) -> None:
        self.model.events.board.disconnect(self._on_board)
        self.model.document.events.changed.disconnect(self._on_design)
        self.canvas.close()
        super().closeEvent(event)
