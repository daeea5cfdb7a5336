"""Designer panel: L/a/b plots, the a–b arrow plot, HSB, gloss and travel sliders (each with its value in
an editable box), face and flop Lab typed in, the variations grid (each variation rendered on the object
of the main view, in its environment) and the palette."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import QSize, Qt, QTimer
from PySide6.QtGui import QIcon
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QSlider,
    QSpinBox,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from station.design.designer import CHANNELS
from station.design.palette import swatch
from station.design.variations import CATEGORIES
from station.model import FaceFlopTravelGloss
from station.render.basis_images import BasisImages
from ui.models.designer import DesignerModel, VariationSwatches
from ui.models.view import ViewModel, ViewSettings
from ui.widgets.common import pixmap_from_array
from ui.widgets.plots import ABPlot, CurvePlot

HUE_RANGE, SAT_RANGE, BRIGHT_RANGE = 180, (0, 200), 50
#: Size of a variation's rendered object (pixels).
VARIATION_PX = 44
#: How often (ms) the grid looks for the main view's basis images while it renders from its own.
SOURCE_POLL_MS = 250
#: Where the swatches come from: the main view's cached basis images when they are current, else None.
BasisSource = Callable[[], BasisImages | None]


def _slider(lo: int, hi: int, value: int) -> QSlider:
    s = QSlider(Qt.Orientation.Horizontal)
    s.setRange(lo, hi)
    s.setValue(value)
    return s


class VariationsGrid(QWidget):
    """3 × 3 grid: the current design in the centre, its ring of variations around (click to accept).

    Each cell shows its design rendered on the object of the main view (shape, camera, environment,
    stage, coat and exposure of *view_model*): the main view's cached basis images (*basis_source*)
    re-weighted for the cell's design and box-filtered to VARIATION_PX² (:class:`VariationSwatches`).
    While the main view has no current basis (a view change in progress) the grid renders the view
    itself at a small size and switches to the main view's images when they arrive. ``source`` says which
    (``"main view"`` or ``"own"``).
    """

    def __init__(
        self,
        model: DesignerModel,
        view_model: ViewModel | None = None,
        basis_source: BasisSource | None = None,
        parent: QWidget | None = None,
    ) -> None:
        super().__init__(parent)
        self.model = model
        self.view_model = view_model
        self.basis_source = basis_source
        self.swatches = VariationSwatches(VARIATION_PX)
        self.source = ""
        self.images: list = [None] * 9  # the (px, px, 3) uint8 swatch of each cell, None when disabled
        self._poll = QTimer(self)
        self._poll.setInterval(SOURCE_POLL_MS)
        self._poll.timeout.connect(self._on_poll)
        self.category = QComboBox()
        self.category.addItems(list(CATEGORIES))
        self.degree = QDoubleSpinBox()
        self.degree.setRange(0.5, 50.0)
        self.degree.setValue(5.0)
        top = QHBoxLayout()
        top.addWidget(self.category)
        top.addWidget(QLabel("step"))
        top.addWidget(self.degree)
        grid = QGridLayout()
        self.buttons: list[QToolButton] = []
        longest = max(("more chroma", "less travel", "current", "more gloss"), key=len)
        for i in range(9):
            b = QToolButton()
            b.setIconSize(QSize(VARIATION_PX, VARIATION_PX))
            width = max(VARIATION_PX + 12, b.fontMetrics().horizontalAdvance(longest) + 16)
            b.setFixedSize(width, VARIATION_PX + b.fontMetrics().height() + 12)
            b.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextUnderIcon)
            b.clicked.connect(lambda _=False, k=i: self._on_click(k))
            grid.addWidget(b, i // 3, i % 3)
            self.buttons.append(b)
        lay = QVBoxLayout(self)
        lay.addLayout(top)
        lay.addLayout(grid)
        self.cells: list[FaceFlopTravelGloss | None] = [None] * 9
        self.category.currentTextChanged.connect(lambda _t: self.refresh())
        self.degree.valueChanged.connect(lambda _v: self.refresh())
        model.document.events.changed.connect(self._on_changed)
        if view_model is not None:
            view_model.events.settings.connect(self._on_view)
        self.refresh()

    def _settings(self) -> ViewSettings:
        return self.view_model.settings if self.view_model is not None else ViewSettings()

    def _choose_source(self) -> bool:
        """Use the main view's basis when it is current, else an own render; True if the source changed."""
        main = self.basis_source() if self.basis_source is not None else None
        if main is not None:
            self._poll.stop()
            changed = self.swatches.use(main)
            self.source = "main view"
            return changed
        changed = self.swatches.use_settings(self._settings())
        self.source = "own"
        if self.basis_source is not None and not self._poll.isActive():
            self._poll.start()
        return changed

    def _on_poll(self) -> None:
        if self.basis_source is not None and self.basis_source() is not None:
            self.refresh()

    def _on_view(self, _settings: ViewSettings) -> None:
        self.refresh()

    def _on_changed(self, design: FaceFlopTravelGloss) -> None:
        self.refresh()

    def refresh(self) -> None:
        """Recompute the ring around the current design and render each cell on the object."""
        self._choose_source()
        exposure = self._settings().exposure_ev
        ring = self.model.variations(CATEGORIES[self.category.currentIndex()], self.degree.value())
        order = [0, 1, 2, 3, None, 4, 5, 6, 7]  # ring of 8 around the centre cell
        for cell, idx in enumerate(order):
            b = self.buttons[cell]
            if idx is None or idx >= len(ring.variations):
                design, label, reason = (ring.centre, "current", "") if idx is None else (None, "", "")
            else:
                v = ring.variations[idx]
                design, label, reason = v.design, v.label, v.reason
            self.cells[cell] = design
            b.setText(label)
            b.setEnabled(design is not None)
            b.setToolTip(reason or label)
            image = None if design is None else self.swatches.render(design, exposure)
            self.images[cell] = image
            b.setIcon(QIcon(pixmap_from_array(image)) if image is not None else QIcon())

    def _on_click(self, cell: int) -> None:
        d = self.cells[cell]
        if d is not None and cell != 4:
            self.model.accept(d, f"variation {self.buttons[cell].text()}")

    def closeEvent(self, event) -> None:
        self._poll.stop()
        self.model.document.events.changed.disconnect(self._on_changed)
        if self.view_model is not None:
            self.view_model.events.settings.disconnect(self._on_view)
        super().closeEvent(event)


class PaletteList(QListWidget):
    """Kept designs as gradient swatches with gloss borders (thesis §3.4.6); click to use one."""

    def __init__(self, model: DesignerModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.designer = model
        self.setIconSize(QSize(160, 32))
        self.setMaximumHeight(130)
        model.events.palette.connect(self._on_palette)
        self.itemClicked.connect(self._on_item)

    def _on_palette(self) -> None:
        self.clear()
        for name, design in self.designer.palette:
            item = QListWidgetItem(QIcon(pixmap_from_array(swatch(design).pixels)), name)
            self.addItem(item)

    def _on_item(self, item: QListWidgetItem) -> None:
        name, design = self.designer.palette[self.row(item)]
        self.designer.accept(design, f"palette {name}")

    def closeEvent(self, event) -> None:
        self.designer.events.palette.disconnect(self._on_palette)
        super().closeEvent(event)


class DesignerPanel(QWidget):
    """Everything that edits the design; every edit is one undoable step of the document."""

    def __init__(
        self,
        model: DesignerModel,
        view_model: ViewModel | None = None,
        basis_source: BasisSource | None = None,
        parent: QWidget | None = None,
    ) -> None:
        """*view_model* and *basis_source* (the main view's settings and its current cached basis images)
        let the variations render on the object shown; without them they render on a sphere in the
        booth."""
        super().__init__(parent)
        self.model = model
        self.plots = {c: CurvePlot(model, c) for c in CHANNELS}
        self.ab = ABPlot(model)
        plots = QGridLayout()
        plots.addWidget(self.plots["L"], 0, 0)
        plots.addWidget(self.ab, 0, 1)
        plots.addWidget(self.plots["a"], 1, 0)
        plots.addWidget(self.plots["b"], 1, 1)

        self.hue = _slider(-HUE_RANGE, HUE_RANGE, 0)
        self.sat = _slider(*SAT_RANGE, 100)
        self.bright = _slider(-BRIGHT_RANGE, BRIGHT_RANGE, 0)
        self.gloss = _slider(0, 100, round(model.design.gloss_gu))
        self.travel = _slider(16, 180, round(model.design.travel_deg or 75))
        self.values: dict[str, QSpinBox] = {}
        form = QFormLayout()
        for key, label, slider in (
            ("hue", "hue (°)", self.hue),
            ("sat", "saturation (%)", self.sat),
            ("bright", "brightness (ΔL*)", self.bright),
            ("gloss", "gloss (GU)", self.gloss),
            ("travel", "travel θ_clamp (°)", self.travel),
        ):
            form.addRow(label, self._with_value(key, slider))
        self.lab_edits: dict[str, QLineEdit] = {}
        for which in ("face", "flop"):
            e = QLineEdit()
            e.setObjectName(f"{which}-lab")
            e.setToolTip(f"{which} L*, a*, b* (D65/10°): type three numbers and press Enter")
            e.returnPressed.connect(lambda w=which: self._on_lab_typed(w))
            self.lab_edits[which] = e
            form.addRow(f"{which} L*, a*, b*", e)
        self._show_lab(model.design)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        hsb_box = QGroupBox("Colour")
        hsb_box.setLayout(form)

        for s in (self.hue, self.sat, self.bright):
            s.valueChanged.connect(self._on_hsb)
            s.sliderReleased.connect(self._on_hsb_released)
        self.gloss.valueChanged.connect(lambda v: self.model.set_gloss(float(v)))
        self.gloss.sliderReleased.connect(self.model.end_drag)
        self.travel.valueChanged.connect(self._on_travel)
        self.travel.sliderReleased.connect(self.model.end_drag)

        self.variations = VariationsGrid(model, view_model, basis_source)
        var_box = QGroupBox("Variations (click to accept)")
        QVBoxLayout(var_box).addWidget(self.variations)
        self.palette_list = PaletteList(model)
        keep = QPushButton("Keep in palette")
        self.palette_keep = keep
        keep.clicked.connect(lambda: self.model.keep())
        pal_box = QGroupBox("Palette")
        pl = QVBoxLayout(pal_box)
        pl.addWidget(keep)
        pl.addWidget(self.palette_list)

        lay = QVBoxLayout(self)
        lay.addLayout(plots, 3)
        lay.addWidget(hsb_box)
        lay.addWidget(self.status)
        lay.addWidget(var_box)
        lay.addWidget(pal_box)
        model.document.events.changed.connect(self._on_changed)
        model.document.events.error.connect(self._on_error)

    def _with_value(self, key: str, slider: QSlider) -> QWidget:
        """The slider and an editable box with its value (typed value + Enter = one undo step)."""
        box = QSpinBox()
        box.setObjectName(f"{key}-value")
        box.setRange(slider.minimum(), slider.maximum())
        box.setValue(slider.value())
        box.setKeyboardTracking(False)
        self.values[key] = box

        def from_slider(v: int) -> None:
            box.blockSignals(True)
            box.setValue(v)
            box.blockSignals(False)

        def from_box() -> None:
            if box.value() != slider.value():
                slider.setValue(box.value())
                if key in ("hue", "sat", "bright"):
                    self._on_hsb_released()
                else:
                    self.model.end_drag()

        slider.valueChanged.connect(from_slider)
        box.editingFinished.connect(from_box)
        row = QWidget()
        lay = QHBoxLayout(row)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(slider, 1)
        lay.addWidget(box)
        return row

    def _show_lab(self, design: FaceFlopTravelGloss) -> None:
        for which, lab in (("face", design.face), ("flop", design.flop)):
            e = self.lab_edits[which]
            if not e.hasFocus() or not e.isModified():
                e.setText(", ".join(f"{v:.1f}" for v in lab))
                e.setModified(False)

    def _on_lab_typed(self, which: str) -> None:
        e = self.lab_edits[which]
        try:
            parts = [float(t) for t in e.text().replace(";", ",").split(",")]
        except ValueError:
            parts = []
        if len(parts) != 3:
            self.status.setText(f"Refused: {which}: expected three numbers L*, a*, b*, got {e.text()!r}")
            return
        e.setModified(False)
        if self.model.set_lab(which, (parts[0], parts[1], parts[2])):
            self._show_lab(self.model.design)

    def _on_hsb(self, _v: int) -> None:
        self.model.set_hsb(float(self.hue.value()), self.sat.value() / 100.0, float(self.bright.value()))

    def _on_hsb_released(self) -> None:
        self.model.end_drag()
        for s, v in ((self.hue, 0), (self.sat, 100), (self.bright, 0)):
            s.blockSignals(True)
            s.setValue(v)
            s.blockSignals(False)
        for k, v in (("hue", 0), ("sat", 100), ("bright", 0)):
            self.values[k].blockSignals(True)
            self.values[k].setValue(v)
            self.values[k].blockSignals(False)

    def _on_travel(self, v: int) -> None:
        if not self.model.design.is_solid:
            self.model.set_travel(float(v))

    def _on_changed(self, design: FaceFlopTravelGloss) -> None:
        self.status.setText("")
        for key, s, v in (
            ("gloss", self.gloss, round(design.gloss_gu)),
            ("travel", self.travel, round(design.travel_deg or 75)),
        ):
            if s.value() != v and not s.isSliderDown():
                s.blockSignals(True)
                s.setValue(v)
                s.blockSignals(False)
                self.values[key].blockSignals(True)
                self.values[key].setValue(v)
                self.values[key].blockSignals(False)
        self._show_lab(design)

    def _on_error(self, message: str) -> None:
        self.status.setText(f"Refused: {message}")

    def closeEvent(self, event) -> None:
        self.model.document.events.changed.disconnect(self._on_changed)
        self.model.document.events.error.disconnect(self._on_error)
        children: tuple[QWidget, ...] = (*self.plots.values(), self.ab, self.variations, self.palette_list)
        for w in children:
            w.close()
        super().closeEvent(event)
