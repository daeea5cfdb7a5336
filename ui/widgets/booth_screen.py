"""Light booth screen: standard and trial side by side on a part, under a booth illuminant.

Standard and trial are picked from the job history (the measurement database, newest first) or from a
file; the trial may also be a recipe ("From recipe…": a ``station formulate --json`` file, or a stored
formulation job from the jobs picker), predicted by the colorant model at the standard's geometries; the illuminant from a row of buttons (D65 … LED-B4) or a user SPD file; the observer (10°, 2°) and
the part (panels, seam, car) from pickers. The picture is redrawn on every change and the table beside
it gives, per geometry under that illuminant, both Lab (the illuminant's own white), ΔE00 and the
metamerism index from D65. State and numbers live in :class:`ui.models.booth.BoothModel`; errors are
shown in the message line, never raised.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QGuiApplication
from PySide6.QtWidgets import (
    QButtonGroup,
    QComboBox,
    QFileDialog,
    QFormLayout,
    QGridLayout,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.errors import StationError
from station.model.booth import BOOTH_SHAPES
from station.model.illuminants import BOOTH_ILLUMINANTS
from ui.models.booth import OBSERVER_CHOICES, ROLES, BoothModel, BoothView
from ui.widgets.common import pixmap_from_array

COLUMNS = ("geometry", "standard L*a*b*", "trial L*a*b*", "ΔE00", "MI")
#: ΔE00 above which a row is marked (a visible difference in a booth).
MARK_DE00 = 1.0
ERROR_STYLE = "color: #b00020;"


class BoothScreen(QWidget):
    """Pickers (standard, trial, illuminant, observer, part), the booth picture and the ΔE / MI table."""

    def __init__(self, booth: BoothModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.booth = booth
        self.last_view: BoothView | None = None
        self._make_widgets()
        self._lay_out()
        self._connect()
        self.reload_history()

    # -- construction ----------------------------------------------------------------------------------
    def _make_widgets(self) -> None:
        self.pickers = {role: QComboBox() for role in ROLES}
        self.file_btns = {role: QPushButton("From file…") for role in ROLES}
        self.recipe_btn = QPushButton("From recipe…")
        self.recipe_jobs = QComboBox()
        self.recipe_jobs.setVisible(self.booth.has_recipe_jobs)
        self.reload_btn = QPushButton("Reload history")
        self.observer = QComboBox()
        self.observer.addItems([f"{o}°" for o in OBSERVER_CHOICES])
        self.shape = QComboBox()
        self.shape.addItems(list(BOOTH_SHAPES))
        self.illuminant_btns = {name: QPushButton(name) for name in BOOTH_ILLUMINANTS}
        self.spd_btn = QPushButton("SPD file…")
        self.illuminant_group = QButtonGroup(self)
        self.picture = QLabel("Choose a standard and a trial.")
        self.picture.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.picture.setMinimumSize(320, 320)
        self.table = self._make_table()
        self.message = QLabel("")
        self.message.setWordWrap(True)

    def _make_table(self) -> QTableWidget:
        table = QTableWidget(0, len(COLUMNS))
        table.setHorizontalHeaderLabels(list(COLUMNS))
        table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        return table

    def _illuminant_row(self) -> QGridLayout:
        grid = QGridLayout()
        for k, (name, btn) in enumerate(self.illuminant_btns.items()):
            btn.setCheckable(True)
            btn.setChecked(name == self.booth.illuminant_name)
            self.illuminant_group.addButton(btn)
            grid.addWidget(btn, k // 5, k % 5)
        self.spd_btn.setCheckable(True)
        self.illuminant_group.addButton(self.spd_btn)
        grid.addWidget(self.spd_btn, len(self.illuminant_btns) // 5, len(self.illuminant_btns) % 5)
        return grid

    def _lay_out(self) -> None:
        form = QFormLayout()
        for role in ROLES:
            row = QHBoxLayout()
            row.addWidget(self.pickers[role], 1)
            row.addWidget(self.file_btns[role])
            if role == "trial":
                row.addWidget(self.recipe_btn)
            form.addRow(role, row)
        form.addRow("", self.recipe_jobs)
        form.addRow("", self.reload_btn)
        form.addRow("illuminant", self._illuminant_row())
        form.addRow("observer", self.observer)
        form.addRow("part", self.shape)
        side = QVBoxLayout()
        side.addLayout(form)
        side.addWidget(self.table, 1)
        body = QHBoxLayout()
        body.addWidget(self.picture, 3)
        body.addLayout(side, 2)
        layout = QVBoxLayout(self)
        layout.addLayout(body, 1)
        layout.addWidget(self.message)

    def _connect(self) -> None:
        for role in ROLES:
            self.pickers[role].activated.connect(lambda _i, r=role: self.pick_history(r))
            self.file_btns[role].clicked.connect(lambda _c=False, r=role: self.pick_file(r))
        self.recipe_btn.clicked.connect(lambda _c=False: self.pick_recipe_file("trial"))
        self.recipe_jobs.activated.connect(lambda _i: self.pick_recipe_job("trial"))
        self.reload_btn.clicked.connect(self.reload_history)
        for name, btn in self.illuminant_btns.items():
            btn.clicked.connect(lambda _c=False, n=name: self.choose_illuminant(n))
        self.spd_btn.clicked.connect(self.choose_spd)
        self.observer.currentIndexChanged.connect(self._observer_changed)
        self.shape.currentTextChanged.connect(self._shape_changed)

    # -- actions ---------------------------------------------------------------------------------------
    def _fail(self, exc: StationError) -> None:
        self.message.setStyleSheet(ERROR_STYLE)
        self.message.setText(f"error: {exc}")

    def _say(self, text: str) -> None:
        self.message.setStyleSheet("")
        self.message.setText(text)

    def reload_history(self) -> None:
        """Fill both pickers with the job history (newest first); the first entry is a prompt."""
        try:
            entries = self.booth.history()
        except StationError as exc:
            self._fail(exc)
            return
        for picker in self.pickers.values():
            picker.clear()
            picker.addItem("— job history —", None)
            for e in entries:
                picker.addItem(e.text, e.id)
        self._say(f"{len(entries)} measurements in the job history")
        self.reload_recipe_jobs()

    def reload_recipe_jobs(self) -> None:
        """Fill the formulation jobs picker (service or database mode); the first entry is a prompt."""
        if not self.booth.has_recipe_jobs:
            return
        try:
            jobs = self.booth.recipe_jobs()
        except StationError as exc:
            self._fail(exc)
            return
        self.recipe_jobs.clear()
        self.recipe_jobs.addItem("— trial from a formulation job —", None)
        for j in jobs:
            self.recipe_jobs.addItem(j.text, j.id)

    def pick_recipe_job(self, role: str) -> None:
        """Use the recipe of the formulation job chosen in the jobs picker as *role*."""
        rid = self.recipe_jobs.currentData()
        if rid is None:
            return
        try:
            label = self.booth.pick_recipe_job(role, int(rid))
        except StationError as exc:
            self._fail(exc)
            return
        self.pickers[role].setCurrentIndex(0)
        self.pickers[role].setToolTip(label)
        self.refresh()

    def pick_recipe_file(self, role: str) -> None:
        """Use a recipe file (``station formulate --json`` output) as *role* (a file dialog)."""
        path, _f = QFileDialog.getOpenFileName(
            self, f"Open the {role}'s recipe", "", "Recipes (*.json);;All files (*)"
        )
        if not path:
            return
        try:
            label = self.booth.pick_recipe_file(role, path)
        except StationError as exc:
            self._fail(exc)
            return
        self.pickers[role].setCurrentIndex(0)
        self.pickers[role].setToolTip(label)
        self.refresh()

    def pick_history(self, role: str) -> None:
        """Use the measurement chosen in *role*'s picker."""
        mid = self.pickers[role].currentData()
        if mid is None:
            return
        try:
            self.booth.pick_history(role, int(mid))
        except StationError as exc:
            self._fail(exc)
            return
        self.refresh()

    def pick_file(self, role: str) -> None:
        """Use the one reading of a file as *role* (a file dialog)."""
        path, _f = QFileDialog.getOpenFileName(
            self,
            f"Open the {role}",
            "",
            "Readings or recipes (*.json *.cxf *.cgats *.txt *.csv);;All files (*)",
        )
        if not path:
            return
        try:
            label = self.booth.pick_file(role, path)
        except StationError as exc:
            self._fail(exc)
            return
        self.pickers[role].setCurrentIndex(0)
        self.pickers[role].setToolTip(label)
        self.refresh()

    def choose_illuminant(self, name: str) -> None:
        """Switch to the booth illuminant *name*."""
        try:
            self.booth.set_illuminant(name)
        except StationError as exc:
            self._fail(exc)
            return
        self.refresh()

    def choose_spd(self) -> None:
        """Switch to a user SPD file's illuminant (a file dialog)."""
        path, _f = QFileDialog.getOpenFileName(self, "Open an SPD file", "", "SPD (*.csv);;All files (*)")
        if not path:
            self._check_current_illuminant()
            return
        try:
            self.booth.load_spd(path)
        except StationError as exc:
            self._check_current_illuminant()
            self._fail(exc)
            return
        self.spd_btn.setText(f"SPD: {self.booth.illuminant_name}")
        self.refresh()

    def _check_current_illuminant(self) -> None:
        btn = self.illuminant_btns.get(self.booth.illuminant_name, self.spd_btn)
        btn.setChecked(True)

    def _observer_changed(self, index: int) -> None:
        self.booth.set_observer(OBSERVER_CHOICES[index])
        self.refresh()

    def _shape_changed(self, shape: str) -> None:
        self.booth.set_shape(shape)
        self.refresh()

    def refresh(self) -> None:
        """Redraw the picture and the table (once standard and trial are both chosen)."""
        if not self.booth.ready:
            missing = [r for r in ROLES if self.booth.readings[r] is None]
            self._say(f"choose the {' and the '.join(missing)}")
            return
        cold = not self.booth.renderer.cached(self.booth.shape)
        if cold:  # the part's basis images are drawn once (about a second; the car in a process of its own)
            self._say(f"drawing the {self.booth.shape} in the booth once…")
            QGuiApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        try:
            view = self.booth.compute()
        except StationError as exc:
            self._fail(exc)
            return
        finally:
            if cold:
                QGuiApplication.restoreOverrideCursor()
        self.last_view = view
        self.picture.setPixmap(pixmap_from_array(view.image))
        self._fill_table(view)
        self._say(
            f"{self.booth.labels['standard']} | {self.booth.labels['trial']} under {view.illuminant}, "
            f"{self.booth.observer}° observer: mean ΔE00 {view.mean_de:.2f} ({view.seconds * 1000:.0f} ms)"
        )

    def _fill_table(self, view: BoothView) -> None:
        self.table.setRowCount(len(view.rows))
        for i, row in enumerate(view.rows):
            cells = (
                row.geometry,
                ", ".join(f"{v:.2f}" for v in row.standard_lab),
                ", ".join(f"{v:.2f}" for v in row.sample_lab),
                f"{row.de00:.2f}",
                f"{row.metamerism_index:.2f}",
            )
            for j, text in enumerate(cells):
                item = QTableWidgetItem(text)
                if row.de00 > MARK_DE00:
                    item.setBackground(QColor("#ffe08a"))
                self.table.setItem(i, j, item)
