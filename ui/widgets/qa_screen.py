"""QA screen: two panels (designs, palette entries, scans made since the viewer started or measurements
stored in the database or on the service — "Load stored measurements"), a misalignment and the
geometry range → seam ΔE per geometry, the goniogeometric index, pass/fail, advice
(``station.analysis.qa.seam_qa``), and the seam pictured as is and with the corrected paint for panel B
at one analysed geometry — the worst by default, any other by clicking its row — under the point light
the verdict is computed for (``station.analysis.picture.seam_pair_lab``: the columns beside the seam
show the model's colours, so the picture agrees with the ΔE); the caption says which geometry. The
report exports as JSON with its PNG (``plot_seam_report``); the corrected paint can be sent to
formulation."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QPushButton,
    QSizePolicy,
    QSlider,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.analysis.picture import display_exposure, geometry_caption, lab_picture, seam_pair_lab
from station.analysis.qa import DEFAULT_ASPECULAR_DEG, DEFAULT_LIGHTS_DEG, SeamReport, seam_qa
from station.errors import InputError, StationError
from station.model import FaceFlopTravelGloss
from station.model.domain import ANGLE_MAX_DEG, ANGLE_MIN_DEG, DELTA_E_COMPUTED
from ui.models.designer import DesignerModel
from ui.models.instruments import MeasurementStore
from ui.models.measure_db import RECENT_DEFAULT, gloss_warning, recent_limit
from ui.widgets.common import pixmap_from_array
from ui.widgets.tasks import TaskProgress, TaskThread

#: The ΔE formulas the seam analysis takes, in the order the selector lists them.
METHODS = DELTA_E_COMPUTED
PICTURE_SIZE = (120, 240)
"""Seam pictures, pixels (height, width): panel A left, panel B right."""
VERDICT_STYLE = "font-size: 18pt; font-weight: bold"
ERROR_STYLE = VERDICT_STYLE + "; color: #b00020"
PICTURES_HINT = "run QA to picture the seam at the analysed geometries"
AS_IS_TITLE = "seam as is (A | B)"
FIXED_TITLE = "corrected (A | B′)"
#: Accepted light polar angles (signed, degrees from the normal): a light at or below the horizon lights nothing.
LIGHT_LIMIT_DEG = 90.0
LIGHTS_RANGE = f"comma-separated angles, {-LIGHT_LIMIT_DEG:g} < angle < {LIGHT_LIMIT_DEG:g}"
ASPECULAR_RANGE = f"comma-separated angles, {ANGLE_MIN_DEG:g} <= angle <= {ANGLE_MAX_DEG:g}"


def export_report(report: SeamReport, path: Path) -> tuple[Path, Path]:
    """Write *report* as JSON to *path* and its picture PNG beside it (``plot_seam_report``); both paths."""
    import json

    from station.analysis.picture import plot_seam_report

    path = Path(path)
    if path.suffix.lower() != ".json":
        path = path.with_suffix(".json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report.to_dict(), indent=2) + "\n", encoding="utf-8")
    return path, plot_seam_report(report, path.with_suffix(".png"))


def _floats(
    text: str, field: str, accepted: str, lo: float, hi: float, open_range: bool
) -> tuple[float, ...]:
    """Comma-separated angles in degrees within *lo* … *hi* (exclusive when *open_range*);
    :class:`InputError` naming *field* and *accepted* otherwise."""
    try:
        vals = tuple(float(t) for t in text.replace(";", ",").split(",") if t.strip())
    except ValueError as exc:
        raise InputError(field, accepted, text) from exc
    if not vals:
        raise InputError(field, accepted, text)
    for v in vals:
        inside = lo < v < hi if open_range else lo <= v <= hi
        if not (math.isfinite(v) and inside):
            raise InputError(field, accepted, v)
    return vals


def parse_lights(text: str) -> tuple[float, ...]:
    """The light polar angles typed, degrees (:data:`LIGHTS_RANGE`)."""
    return _floats(text, "lights", LIGHTS_RANGE, -LIGHT_LIMIT_DEG, LIGHT_LIMIT_DEG, True)


def parse_aspecular(text: str) -> tuple[float, ...]:
    """The aspecular angles typed, degrees (:data:`ASPECULAR_RANGE`, the model's angle range)."""
    return _floats(text, "aspecular range", ASPECULAR_RANGE, ANGLE_MIN_DEG, ANGLE_MAX_DEG, False)


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
        self.stored: list[tuple[str, FaceFlopTravelGloss]] = []
        self.exported: tuple[Path, Path] | None = None
        self.shown_geometry: int | None = None
        self.pictures: tuple | None = None  # (Lab as is, Lab corrected, display exposure)
        self._build_inputs()
        self._build_results()
        self._build_pictures()
        self._lay_out()
        self._connect()

    def _build_inputs(self) -> None:
        """Panel pickers, misalignment, tolerance, formula, geometries and the action buttons."""
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
        self.lights.setToolTip(f"light polar angles, degrees: {LIGHTS_RANGE}")
        self.aspecular = QLineEdit(", ".join(f"{v:g}" for v in DEFAULT_ASPECULAR_DEG))
        self.aspecular.setToolTip(f"aspecular angles, degrees: {ASPECULAR_RANGE}")
        self.run_btn = QPushButton("Run QA")
        self.load_btn = QPushButton("Load stored measurements")
        self.load_btn.setEnabled(self.store.sink is not None)
        self.load_btn.setToolTip("the newest measurements of the database (or the service in service mode)")
        self.send_btn = QPushButton("Send corrected paint to formulation")
        self.send_btn.setEnabled(False)
        self.export_btn = QPushButton("Export report…")
        self.export_btn.setEnabled(False)
        self.busy = TaskProgress()

    def _build_results(self) -> None:
        """The verdict, its details and the per-geometry table."""
        self.verdict = QLabel("—")
        self.verdict.setStyleSheet(VERDICT_STYLE)
        self.details = QLabel()
        self.details.setWordWrap(True)
        self.details.setAlignment(Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop)
        self.details.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.table = QTableWidget(0, 6)
        self.table.setHorizontalHeaderLabels(
            ["light °", "view °", "aspecular °", "seam ΔE", "geometric ΔE", "formulation ΔE"]
        )
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setToolTip("click a geometry to picture the seam there")

    def _build_pictures(self) -> None:
        """The two seam pictures (as is, corrected), their titles and the caption."""
        self.as_is = QLabel(PICTURES_HINT)
        self.fixed = QLabel()
        for pic in (self.as_is, self.fixed):
            pic.setMinimumSize(PICTURE_SIZE[1], PICTURE_SIZE[0])
            pic.setAlignment(Qt.AlignmentFlag.AlignCenter)
            # a picture wider than its column is cropped at the sides, not made to widen the screen
            pic.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Ignored)
        self.as_is_title = QLabel(AS_IS_TITLE)
        self.fixed_title = QLabel(FIXED_TITLE)
        for title in (self.as_is_title, self.fixed_title):
            title.setWordWrap(True)
        self.caption = QLabel()
        self.caption.setWordWrap(True)

    def _lay_out(self) -> None:
        """Inputs and verdict on the left, pictures and table on the right."""
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
        for w in (self.load_btn, self.run_btn, self.busy, self.verdict):
            left.addWidget(w)
        left.addWidget(self.details, 1)
        left.addWidget(self.export_btn)
        left.addWidget(self.send_btn)
        renders = QHBoxLayout()
        for title, view in ((self.as_is_title, self.as_is), (self.fixed_title, self.fixed)):
            col = QVBoxLayout()
            col.addWidget(title)
            col.addWidget(view, 1)
            renders.addLayout(col)
        right = QVBoxLayout()
        right.addLayout(renders, 3)
        right.addWidget(self.caption)
        right.addWidget(self.table, 2)
        lay = QHBoxLayout(self)
        lay.addLayout(left, 1)
        lay.addLayout(right, 2)

    def _connect(self) -> None:
        """Wire the widgets and the models' events."""
        self.beta.valueChanged.connect(self._on_beta)
        self.run_btn.clicked.connect(self.run)
        # clicked(bool) must not reach load_stored: its checked flag would become the row limit
        self.load_btn.clicked.connect(self._on_load_clicked)
        self.send_btn.clicked.connect(self._send)
        self.export_btn.clicked.connect(self._on_export_clicked)
        self.table.itemSelectionChanged.connect(self._on_row)
        self.designer.events.palette.connect(self.refresh_sources)
        self.designer.document.events.changed.connect(self._on_design)
        self.store.events.added.connect(self._on_measurement)
        self.refresh_sources()
        self._on_beta(self.beta.value())
        self.panel_a.currentTextChanged.connect(self._on_pick)
        self.panel_b.currentTextChanged.connect(self._on_pick)

    def _on_pick(self, *_args) -> None:
        """Another panel or misalignment: the last run's answer no longer applies and leaves the screen."""
        if self.report is None:
            return
        self.clear_result()
        self.caption.setText("the panels or β changed: run QA again")
        self.verdict.setText("—")
        self.verdict.setStyleSheet(VERDICT_STYLE)
        self.details.setText("")

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
        sink = self.store.sink
        if sink is None:
            self._show_error("stored measurements: no measurement store is open")
            return 0
        try:
            rows = sink.recent(limit)
        except StationError as exc:
            self._show_error(f"stored measurements: {exc}")
            return 0
        fits = [(r, f) for r in rows if (f := r.fit()) is not None]
        self.stored = [(f"stored #{r.id}: {r.label} {r.measured_at}", f.design) for r, f in fits]
        self.refresh_sources()
        self.details.setText(
            f"{len(self.stored)} stored measurements offered as panels "
            f"({len(rows) - len(self.stored)} without a design fit) from {sink.where}"
            + gloss_warning([f"#{r.id}" for r, f in fits if not f.design.gloss_measured])
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
        self._on_pick()

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
            lights = parse_lights(self.lights.text())
            asp = parse_aspecular(self.aspecular.text())
        except InputError as exc:
            self._on_failed(str(exc))
            return
        self.verdict.setText("running…")
        self.run_btn.setEnabled(False)
        self.task = TaskThread(
            lambda _p: seam_qa(
                a, b, beta, lights_deg=lights, aspecular_deg=asp, tolerance=tol, method=method
            ),
            pure=True,
        )
        self.task.succeeded.connect(self._on_report)
        self.task.failed.connect(self._on_failed)
        self.task.cancelled.connect(self._on_cancelled)
        self.task.finished.connect(lambda: self.run_btn.setEnabled(True))
        self.busy.watch(
            self.task, f"seam analysis at β = {beta:+g}° over {len(lights) * len(asp)} geometries"
        )
        self.task.start()

    def _on_cancelled(self) -> None:
        self.verdict.setText("cancelled")
        self.verdict.setStyleSheet(VERDICT_STYLE)
        self.details.setText("the seam analysis was cancelled; nothing changed")

    def _on_failed(self, message: str) -> None:
        """The analysis could not run: nothing of the last report stays on screen, the error is shown."""
        self.clear_result()
        self._show_error(message)

    def _show_error(self, message: str) -> None:
        """An error in the verdict's place (red), the message (field and accepted range) below it."""
        self.verdict.setText("error")
        self.verdict.setStyleSheet(ERROR_STYLE)
        self.details.setText(message)

    def clear_result(self) -> None:
        """Forget the last report: pictures, titles, caption, table, export and send, all cleared."""
        self.report = None
        self.pictures = None
        self.shown_geometry = None
        self.exported = None
        self.as_is.clear()
        self.as_is.setText(PICTURES_HINT)
        self.fixed.clear()
        self.as_is_title.setText(AS_IS_TITLE)
        self.fixed_title.setText(FIXED_TITLE)
        self.caption.clear()
        self.table.blockSignals(True)
        self.table.setRowCount(0)
        self.table.blockSignals(False)
        self.export_btn.setEnabled(False)
        self.send_btn.setEnabled(False)

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
            f"({'meets' if r.correction.meets_epsilon else 'does not meet'} tolerance)"
            + gloss_warning(["B′"] if not r.correction.paint.gloss_measured else [])
            + "\n\n"
            + "\n".join(r.advice)
        )
        self.table.blockSignals(True)
        self.table.setRowCount(len(r.geometries))
        for i, g in enumerate(r.geometries):
            vals = (
                g.light_deg,
                g.view_deg,
                g.aspecular_deg,
                r.seam_de[i],
                r.geometric_de[i],
                r.formulation_de[i],
            )
            for j, v in enumerate(vals):
                self.table.setItem(i, j, QTableWidgetItem(f"{float(v):.2f}"))
        self.table.selectRow(r.worst)
        self.table.blockSignals(False)
        self.show_geometry(r.worst)
        self.send_btn.setEnabled(self.send_to_formulation is not None)
        self.export_btn.setEnabled(True)

    def _on_row(self) -> None:
        rows = {i.row() for i in self.table.selectedItems()}
        if self.report is not None and len(rows) == 1:
            self.show_geometry(rows.pop())

    def show_geometry(self, g: int) -> None:
        """Picture the seam of the last report at its geometry *g*: as is and with the corrected paint,
        one display exposure for both; the caption says which geometry and the ΔE there."""
        r = self.report
        if r is None:
            return
        geo = r.geometries[g]
        labs = [
            seam_pair_lab(r.paint_a, pb, r.beta_deg, geo.light_deg, geo.view_deg, r.hinge, PICTURE_SIZE)
            for pb in (r.paint_b, r.correction.paint)
        ]
        scale = display_exposure(*labs)
        self.pictures = (labs[0], labs[1], scale)
        self.shown_geometry = g
        for label, lab in ((self.as_is, labs[0]), (self.fixed, labs[1])):
            label.setPixmap(pixmap_from_array(np.round(lab_picture(lab, scale) * 255.0).astype(np.uint8)))
        verdict = "PASS" if r.seam_de[g] <= r.tolerance else "FAIL"
        self.as_is_title.setText(f"seam as is (A | B): ΔE {r.seam_de[g]:.2f} {verdict} here")
        after = r.correction.seam_de_after
        fixed_de = float(after[g]) if len(after) == len(r.geometries) else None
        self.fixed_title.setText("corrected (A | B′)" + ("" if fixed_de is None else f": ΔE {fixed_de:.2f}"))
        shown = "" if scale == 1.0 else f"; shown {1 / scale:.1f}× darker (a paint brighter than white)"
        which = "worst geometry" if g == r.worst else f"geometry {g + 1} of {len(r.geometries)}"
        self.caption.setText(
            f"pictured at the {which}: {geometry_caption(r, g)} — point light, panel B turned by β "
            f"about the seam{shown}"
        )

    def _on_export_clicked(self) -> None:
        """Ask where to write the report (JSON, with its PNG beside it), then write both in a worker."""
        path, _filter = QFileDialog.getSaveFileName(
            self,
            "Export QA report",
            str(Path.cwd() / "qa-report.json"),
            "QA report (*.json)",
            options=QFileDialog.Option.DontUseNativeDialog,
        )
        if path:
            self.export(Path(path))

    def export(self, path: Path) -> None:
        """Write the last report to *path* (JSON) and its PNG, in a worker thread."""
        report = self.report
        if report is None or (self.task is not None and self.task.isRunning()):
            return
        self.export_btn.setEnabled(False)
        self.details.setText(f"exporting the report to {path}…")
        self.task = TaskThread(lambda _p: export_report(report, path))
        self.task.succeeded.connect(self._on_exported)
        self.task.failed.connect(lambda msg: self.details.setText(f"export failed: {msg}"))
        self.busy.watch(self.task, f"writing the report to {path.name} and its picture", cancellable=False)
        self.task.finished.connect(lambda: self.export_btn.setEnabled(self.report is not None))
        self.task.start()

    def _on_exported(self, paths: tuple[Path, Path]) -> None:
        self.exported = paths
        self.details.setText(f"report exported: {paths[0]} and {paths[1]}")

    def _send(self) -> None:
        if self.report is not None and self.send_to_formulation is not None:
            self.send_to_formulation(self.report.correction.paint)

    def closeEvent(self, event) -> None:
        if self.task is not None:
            self.task.wait()
        self.designer.events.palette.disconnect(self.refresh_sources)
        self.designer.document.events.changed.disconnect(self._on_design)
        self.store.events.added.disconnect(self._on_measurement)
        super().closeEvent(event)
