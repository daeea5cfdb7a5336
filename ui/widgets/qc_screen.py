"""QC screen: pick a job and a part, judge the samples against the part's standard, export the report.

The table shows each sample at each geometry (ΔL*, Δa*, Δb*, ΔE, pass / warn / fail, the 60° gloss of
the gloss reading paired with the sample, and the reason), coloured by verdict; the line above names the standard and the counts. Data and reports come from
:class:`ui.models.qc.QcModel` (the workstation's database or the service). Reports are written off the
GUI thread. "Metamerism of selected" gives the metamerism index (D65 → A, F11) of the selected sample
against the part's standard measurement. "Illuminant limits" (e.g. ``A=1.0,F11=1.5``) judges the samples
under those illuminants too: a geometry whose metamerism index is over its illuminant's limit fails, the
row named in its reason, and the PDF report gets the illuminant rows.
"""

from __future__ import annotations

from pathlib import Path

from PySide6.QtGui import QColor
from PySide6.QtWidgets import (
    QComboBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.errors import StationError
from ui.models.qc import FORMULAS, QcModel, verdict_rows
from ui.widgets.common import cell_text
from ui.widgets.tasks import TaskThread

COLUMNS = ("sample", "measured", "geometry", "ΔL*", "Δa*", "Δb*", "ΔE", "verdict", "60° GU", "reason")
VERDICT_COLOURS = {"pass": "#b7e1b0", "warn": "#ffe08a", "fail": "#f4a09a"}


class QcScreen(QWidget):
    """Job, part and formula pickers; the verdict table per geometry; PDF and CSV export."""

    def __init__(self, model: QcModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.task: TaskThread | None = None
        self.last_report: Path | None = None
        self.job = QComboBox()
        self.part = QComboBox()
        self.formula = QComboBox()
        self.formula.addItems(list(FORMULAS))
        self.limits = QLineEdit()
        self.limits.setPlaceholderText("e.g. A=1.0,F11=1.5 — metamerism index limits (spectra needed)")
        self.load_btn = QPushButton("Load jobs")
        self.judge_btn = QPushButton("Judge")
        self.pdf_btn = QPushButton("Export PDF…")
        self.csv_btn = QPushButton("Export CSV…")
        self.mi_btn = QPushButton("Metamerism of selected")
        for b in (self.judge_btn, self.pdf_btn, self.csv_btn, self.mi_btn):
            b.setEnabled(False)
        self.standard = QLabel("Load jobs to begin.")
        self.standard.setWordWrap(True)
        self.status = QLabel(f"source: {model.source.where}")
        self.status.setWordWrap(True)
        self.table = QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(list(COLUMNS))
        self.table.horizontalHeader().setSectionResizeMode(len(COLUMNS) - 1, QHeaderView.ResizeMode.Stretch)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)

        form = QFormLayout()
        form.addRow("job", self.job)
        form.addRow("part", self.part)
        form.addRow("formula", self.formula)
        form.addRow("illuminant limits", self.limits)
        buttons = QHBoxLayout()
        for b in (self.load_btn, self.judge_btn, self.pdf_btn, self.csv_btn, self.mi_btn):
            buttons.addWidget(b)
        layout = QVBoxLayout(self)
        layout.addLayout(form)
        layout.addLayout(buttons)
        layout.addWidget(self.standard)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.status)

        self.load_btn.clicked.connect(self.load_jobs)
        self.judge_btn.clicked.connect(self.judge)
        self.job.currentTextChanged.connect(self._on_job)
        self.part.currentTextChanged.connect(self._show_part)
        self.pdf_btn.clicked.connect(lambda: self.export("pdf"))
        self.csv_btn.clicked.connect(lambda: self.export("csv"))
        self.mi_btn.clicked.connect(self.metamerism)

    # -- actions -------------------------------------------------------------------------------------
    def load_jobs(self) -> None:
        """Read the jobs from the source and fill the job picker."""
        try:
            jobs = self.model.load_jobs()
        except StationError as exc:
            self.status.setText(f"error: {exc}")
            return
        self.job.blockSignals(True)
        self.job.clear()
        self.job.addItems([j.job for j in jobs])
        self.job.blockSignals(False)
        self._on_job(self.job.currentText())
        self.judge_btn.setEnabled(bool(jobs))
        self.status.setText(f"{len(jobs)} jobs from {self.model.source.where}")

    def _on_job(self, job: str) -> None:
        self.part.blockSignals(True)
        self.part.clear()
        self.part.addItems(list(self.model.parts_of(job)))
        self.part.blockSignals(False)
        if self.model.summary_key is not None and self.model.summary_key[0] == job:
            self._show_part(self.part.currentText())

    def judge(self) -> None:
        """Judge every sample of the chosen job against its part's standard and show the chosen part."""
        try:
            self.model.judge(self.job.currentText(), self.formula.currentText(), self.limits.text())
        except StationError as exc:
            self.status.setText(f"error: {exc}")
            return
        assert self.model.summary is not None  # noqa: S101 - judge() set it
        c = self.model.summary["counts"]
        self.status.setText(
            f"{self.model.summary['job']} ({self.model.summary['formula']}): "
            f"pass {c['pass']} · warn {c['warn']} · fail {c['fail']}"
        )
        self.pdf_btn.setEnabled(True)
        self.csv_btn.setEnabled(True)
        self.mi_btn.setEnabled(True)
        self._show_part(self.part.currentText())

    def metamerism(self) -> None:
        """The metamerism index (D65 → A, F11) of the selected row's sample against the part's standard."""
        row = self.table.currentRow()
        if row < 0:
            self.status.setText("error: select a sample row first")
            return
        sample_id = int(cell_text(self.table, row, COLUMNS.index("sample")))
        try:
            self.status.setText(self.model.metamerism_text(self.part.currentText(), sample_id))
        except StationError as exc:
            self.status.setText(f"error: {exc}")

    def _show_part(self, part: str) -> None:
        entry = self.model.part(part)
        rows = verdict_rows(entry) if entry is not None else []
        self.standard.setText(self.model.standard_text(part))
        self.table.setRowCount(len(rows))
        for i, r in enumerate(rows):
            cells = (
                str(r.measurement_id),
                r.measured_at[:16].replace("T", " "),
                r.geometry,
                f"{r.dl:+.2f}",
                f"{r.da:+.2f}",
                f"{r.db:+.2f}",
                f"{r.de:.2f}",
                r.verdict,
                "" if r.gloss_60_gu is None else f"{r.gloss_60_gu:.1f}",
                r.reason,
            )
            for j, text in enumerate(cells):
                item = QTableWidgetItem(text)
                if j == COLUMNS.index("verdict"):
                    item.setBackground(QColor(VERDICT_COLOURS.get(r.verdict, "#ffffff")))
                self.table.setItem(i, j, item)

    def export(self, kind: str, path: str | None = None) -> None:
        """Write the judged job's report (``pdf`` or ``csv``) to *path*, asked for when not given."""
        if path is None:
            job = self.model.summary_key[0] if self.model.summary_key else "job"
            path, _ = QFileDialog.getSaveFileName(
                self, f"Export QC report ({kind.upper()})", f"qc-{job}.{kind}", f"{kind.upper()} (*.{kind})"
            )
            if not path:
                return
        if self.task is not None and self.task.isRunning():
            return
        self.pdf_btn.setEnabled(False)
        self.csv_btn.setEnabled(False)
        self.status.setText(f"writing {path} …")
        target = path
        self.task = TaskThread(lambda _progress: self.model.report(kind, target), self)
        self.task.succeeded.connect(self._on_written)
        self.task.failed.connect(lambda msg: self.status.setText(f"error: {msg}"))
        self.task.finished.connect(self._export_done)
        self.task.start()

    def _on_written(self, path: object) -> None:
        self.last_report = Path(str(path))
        self.status.setText(f"report written: {self.last_report}")

    def _export_done(self) -> None:
        self.pdf_btn.setEnabled(True)
        self.csv_btn.setEnabled(True)

    def closeEvent(self, event) -> None:
        if self.task is not None:
            self.task.wait()
        super().closeEvent(event)
