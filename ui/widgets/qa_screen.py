"""QA screen: two panels (designs, palette entries, scans made since the viewer started or measurements
stored in the database or on the service — "Load stored measurements"), a misalignment and the
geometry range → seam ΔE per geometry, the goniogeometric index, pass/fail, advice, and the seam rendered
as is and with the corrected paint for panel B (``station.analysis.qa.seam_qa``). The corrected paint
can be sent to formulation (ColorSnap in the library tab)."""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QSlider,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.analysis.qa import DEFAULT_ASPECULAR_DEG, DEFAULT_LIGHTS_DEG, SeamReport, seam_qa
from station.errors import InputError, StationError
from station.model import FaceFlopTravelGloss
from ui.models.designer import DesignerModel
from ui.models.instruments import MeasurementStore
from ui.models.measure_db import RECENT_DEFAULT, recent_limit
from ui.models.view import ViewModel, ViewSettings
from ui.widgets.render_view import make_render_view
from ui.widgets.tasks import TaskThread

METHODS = ("cie76", "cie2000", "din6175")


def _floats(text: str, field: str) -> tuple[float, ...]:
    """Comma-separated angles in degrees; InputError naming *field* otherwise (the core checks ranges)."""
    try:
        vals = tuple(float(t) for t in text.replace(";", ",").split(",") if t.strip())
    except ValueError as exc:
        raise InputError(field, "comma-separated angles in degrees", text) from exc
    if not vals:
        raise InputError(field, "at least one angle in degrees", text)
    return vals


class QAScreen(QWidget):
    """Panel pickers, misalignment, tolerance; results table, verdict and the two seam renderings."""

    def __init__(
        self,
        designer: DesignerModel,
        store: MeasurementStore,
        send_to_formulation: Callable[[FaceFlopTravelGloss], None] | None = None,
        parent: QWidget | None = None,
    ) -> None:
        super().__init__(parent)
        self.designer = designer
        self.store = store
        self.send_to_formulation = send_to_formulation
        self.report: SeamReport | None = None
        self.task: TaskThread | None = None
        self.panel_a, self.panel_b = QComboBox(), QComboBox()
        self.beta = QSlider(Qt.Orientation.Horizontal)
        self.beta.setRange(-45, 45)
        self.beta.setValue(5)
        self.beta_label = QLabel("+5°")
        self.tolerance = QDoubleSpinBox()
        self.tolerance.setRange(0.1, 20.0)
        self.tolerance.setValue(2.3)
        self.method = QComboBox()
        self.method.addItems(list(METHODS))
        self.lights = QLineEdit(", ".join(f"{v:g}" for v in DEFAULT_LIGHTS_DEG))
        self.aspecular = QLineEdit(", ".join(f"{v:g}" for v in DEFAULT_ASPECULAR_DEG))
        self.run_btn = QPushButton("Run QA")
        self.load_btn = QPushButton("Load stored measurements")
        self.load_btn.setEnabled(store.sink is not None)
        self.load_btn.setToolTip("the newest measurements of the database (or the service in service mode)")
        self.stored: list[tuple[str, FaceFlopTravelGloss]] = []
        self.send_btn = QPushButton("Send corrected paint to formulation")
        self.send_btn.setEnabled(False)
        self.verdict = QLabel("—")
        self.verdict.setStyleSheet("font-size: 18pt; font-weight: bold")
        self.details = QLabel()
        self.details.setWordWrap(True)
        self.details.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.table = QTableWidget(0, 5)
        self.table.setHorizontalHeaderLabels(
            ["light °", "aspecular °", "seam ΔE", "geometric ΔE", "formulation ΔE"]
        )
        self.as_is_model = ViewModel(ViewSettings(shape="panels", misalignment_deg=5.0))
        self.fixed_model = ViewModel(ViewSettings(shape="panels", misalignment_deg=5.0))
        self.as_is = make_render_view(self.as_is_model)
        self.fixed = make_render_view(self.fixed_model)

        form = QFormLayout()
        form.addRow("panel A", self.panel_a)
        form.addRow("panel B", self.panel_b)
        row = QHBoxLayout()
        row.addWidget(self.beta)
        row.addWidget(self.beta_label)
        form.addRow("misalignment β", row)
        form.addRow("tolerance ΔE", self.tolerance)
        form.addRow("ΔE formula", self.method)
        form.addRow("lights (°)", self.lights)
        form.addRow("aspecular range (°)", self.aspecular)
        left = QVBoxLayout()
        left.addLayout(form)
        left.addWidget(self.load_btn)
        left.addWidget(self.run_btn)
        left.addWidget(self.verdict)
        left.addWidget(self.details, 1)
        left.addWidget(self.send_btn)
        renders = QHBoxLayout()
        for title, view in (("seam as is (A | B)", self.as_is), ("corrected (A | B′)", self.fixed)):
            col = QVBoxLayout()
            col.addWidget(QLabel(title))
            col.addWidget(view, 1)
            renders.addLayout(col)
        right = QVBoxLayout()
        right.addLayout(renders, 3)
        right.addWidget(self.table, 2)
        lay = QHBoxLayout(self)
        lay.addLayout(left, 1)
        lay.addLayout(right, 2)

        self.beta.valueChanged.connect(self._on_beta)
        self.run_btn.clicked.connect(self.run)
        # clicked(bool) must not reach load_stored: its checked flag would become the row limit
        self.load_btn.clicked.connect(self._on_load_clicked)
        self.send_btn.clicked.connect(self._send)
        designer.events.palette.connect(self.refresh_sources)
        designer.document.events.changed.connect(self._on_design)
        store.events.added.connect(self._on_measurement)
        self.refresh_sources()
        self._on_beta(self.beta.value())
        self.panel_a.currentTextChanged.connect(self._on_pick)
        self.panel_b.currentTextChanged.connect(self._on_pick)
        self._on_pick()

    def _on_pick(self, *_args) -> None:
        a, b = self.picked()
        self.as_is_model.show(a, b)
        self.fixed_model.show(a, b)

    def sources(self) -> list[tuple[str, FaceFlopTravelGloss]]:
        """(label, design) of every panel that can be picked."""
        out = [("current design", self.designer.design)]
        out += [(f"palette: {n}", d) for n, d in self.designer.palette]
        out += [
            (f"measured: {m.panel.label} {m.time}", m.design)
            for m in self.store.items
            if m.design is not None
        ]
        return out + self.stored

    def _on_load_clicked(self) -> None:
        """The "Load stored measurements" click: the newest :data:`RECENT_DEFAULT` of the store."""
        self.load_stored(RECENT_DEFAULT)

    def load_stored(self, limit: int = RECENT_DEFAULT) -> int:
        """Offer the newest *limit* stored measurements (their FFTG fits) as panels; returns how many.

        *limit* is a row count, ``1 ≤ limit ≤ RECENT_MAX``; anything else (a ``bool`` included) raises
        :class:`InputError` naming ``limit``. A store that cannot be read is shown, not raised.
        """
        limit = recent_limit(limit)
        try:
            rows = self.store.sink.recent(limit)
        except StationError as exc:
            self._on_failed(f"stored measurements: {exc}")
            return 0
        self.stored = [
            (f"stored #{r.id}: {r.label} {r.measured_at}", d) for r in rows if (d := r.design()) is not None
        ]
        self.refresh_sources()
        self.details.setText(
            f"{len(self.stored)} stored measurements offered as panels "
            f"({len(rows) - len(self.stored)} without a design fit) from {self.store.sink.where}"
        )
        return len(self.stored)

    def refresh_sources(self) -> None:
        """Rebuild both pickers, keeping the selections where possible."""
        for combo in (self.panel_a, self.panel_b):
            keep = combo.currentText()
            combo.blockSignals(True)
            combo.clear()
            combo.addItems([label for label, _ in self.sources()])
            i = combo.findText(keep)
            combo.setCurrentIndex(max(i, 0))
            combo.blockSignals(False)

    def _on_design(self, _design) -> None:
        self.refresh_sources()

    def _on_measurement(self, _m) -> None:
        self.refresh_sources()

    def _on_beta(self, v: int) -> None:
        self.beta_label.setText(f"{v:+d}°")
        for m in (self.as_is_model, self.fixed_model):
            m.update(misalignment_deg=float(v))

    def picked(self) -> tuple[FaceFlopTravelGloss, FaceFlopTravelGloss]:
        """Designs of panel A and panel B."""
        src = dict(self.sources())
        return src[self.panel_a.currentText()], src[self.panel_b.currentText()]

    def run(self) -> None:
        """Run the seam QA in a worker thread."""
        if self.task is not None and self.task.isRunning():
            return
        a, b = self.picked()
        beta, tol, method = float(self.beta.value()), self.tolerance.value(), self.method.currentText()
        try:
            lights = _floats(self.lights.text(), "lights")
            asp = _floats(self.aspecular.text(), "aspecular range")
        except InputError as exc:
            self._on_failed(str(exc))
            return
        self.as_is_model.show(a, b)
        self.verdict.setText("running…")
        self.run_btn.setEnabled(False)
        self.task = TaskThread(
            lambda _p: seam_qa(a, b, beta, lights_deg=lights, aspecular_deg=asp, tolerance=tol, method=method)
        )
        self.task.succeeded.connect(self._on_report)
        self.task.failed.connect(self._on_failed)
        self.task.finished.connect(lambda: self.run_btn.setEnabled(True))
        self.task.start()

    def _on_failed(self, message: str) -> None:
        self.verdict.setText("error")
        self.details.setText(message)

    def _on_report(self, r: SeamReport) -> None:
        self.report = r
        self.verdict.setText("PASS" if r.passed else "FAIL")
        self.verdict.setStyleSheet(
            f"font-size: 18pt; font-weight: bold; color: {'#1a7f1a' if r.passed else '#b00020'}"
        )
        idx = r.index.to_dict()
        self.details.setText(
            f"seam ΔE max {max(r.seam_de):.2f} ({r.method}, tolerance {r.tolerance:g})\n{r.diagnosis}\n"
            f"goniogeometric index: {idx.get('message', '')}\n"
            f"corrected B′: seam ΔE max {r.correction.max_after:.2f} "
            f"({'meets' if r.correction.meets_epsilon else 'does not meet'} tolerance)\n\n"
            + "\n".join(r.advice)
        )
        self.table.setRowCount(len(r.geometries))
        for i, g in enumerate(r.geometries):
            d = g.to_dict()
            vals = (
                d.get("light_deg"),
                d.get("aspecular_deg"),
                r.seam_de[i],
                r.geometric_de[i],
                r.formulation_de[i],
            )
            for j, v in enumerate(vals):
                self.table.setItem(i, j, QTableWidgetItem(f"{float(v):.2f}"))
        self.fixed_model.show(r.paint_a, r.correction.paint)
        self.send_btn.setEnabled(self.send_to_formulation is not None)

    def _send(self) -> None:
        if self.report is not None and self.send_to_formulation is not None:
            self.send_to_formulation(self.report.correction.paint)

    def closeEvent(self, event) -> None:
        if self.task is not None:
            self.task.wait()
        self.designer.events.palette.disconnect(self.refresh_sources)
        self.designer.document.events.changed.disconnect(self._on_design)
        self.store.events.added.disconnect(self._on_measurement)
        self.as_is.close()
        self.fixed.close()
        super().closeEvent(event)
