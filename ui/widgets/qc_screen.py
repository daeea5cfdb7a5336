"""QC screen: pick a job and a part, judge the samples against the part's standard, export the report.

The table shows each sample at each geometry (ΔL*, Δa*, Δb*, ΔE, pass / warn / fail, the 60° gloss of
the gloss reading paired with the sample, and the reason), coloured by verdict; the line above names the standard and the counts. Data and reports come from
:class:`ui.models.qc.QcModel` (the workstation's database or the service). Reports are written off the
GUI thread. "Metamerism of selected" gives the metamerism index (D65 → A, F11) of the selected sample
against the part's standard measurement. "Illuminant limits" (e.g. ``A=1.0,F11=1.5``) judges the samples
under those illuminants too: a geometry whose metamerism index is over its illuminant's limit fails, the
row named in its reason, and the PDF report gets the illuminant rows.

Judging as ``station qc summary`` does: "average each panel's repeats" judges a panel once on the mean
of its readings with the flagged outliers left out (the line under the table names each one and its
robust z), "keep outliers" averages them in and judges again; a tolerance file
(``station qc tolerance --json``) and texture limits (``ds=…,dg=…``: ΔS, ΔG within one vendor, the
texture table) are optional. The SPC tab draws the part's chart as ``station qc spc`` does (individuals,
or X̄/R with a subgroup size; baseline points; Western Electric and Nelson rule hits ringed and listed,
Cp/Cpk per geometry, a drift flagged and whether before the first fail); the report tab previews the
PDF report's first page once it is written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, cast

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QCheckBox,
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
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from db.models import PARTS
from station.errors import InputError, StationError
from ui.models.imports import FileImport, import_files, import_filter, import_summary, importable
from ui.models.measure_db import MeasurementSink
from ui.models.qc import FORMULAS, QcModel, verdict_rows
from ui.models.qc_views import Judging, texture_lines
from ui.widgets.common import cell_text
from ui.widgets.qc_panels import (
    VERDICT_COLOURS,
    SpcPage,
    fill_texture,
    picture,
    scrolled,
    show_png,
    texture_table,
)
from ui.widgets.tasks import TaskThread

COLUMNS = ("sample", "measured", "geometry", "ΔL*", "Δa*", "Δb*", "ΔE", "verdict", "60° GU", "reason")


def _signed(value: float) -> str:
    """A difference to 0.01 with its sign; a value that rounds to zero reads +0.00, never -0.00."""
    return f"{round(value, 2) + 0.0:+.2f}"


class QcScreen(QWidget):
    """Job, part and formula pickers; the standard picker; the verdict table per geometry; PDF and CSV
    export; vendor files imported by button or dropped on the screen."""

    def __init__(
        self, model: QcModel, parent: QWidget | None = None, sink: MeasurementSink | None = None
    ) -> None:
        super().__init__(parent)
        self.model = model
        self.sink = sink
        self.task: TaskThread | None = None
        self.last_report: Path | None = None
        self.imports: list[FileImport] = []
        self._build_pickers()
        self._build_buttons()
        self._build_import()
        self._build_judging()
        self._build_results()
        self._build_spc()
        self._lay_out()
        self._connect()
        self.setAcceptDrops(sink is not None)

    def _build_pickers(self) -> None:
        """Job, part, formula, illuminant limits and the standard picker."""
        self.job = QComboBox()
        self.part = QComboBox()
        self.formula = QComboBox()
        self.formula.addItems(list(FORMULAS))
        self.limits = QLineEdit()
        self.limits.setPlaceholderText("e.g. A=1.0,F11=1.5 — metamerism index limits (spectra needed)")
        self.standard_pick = QComboBox()
        self.standard_pick.setToolTip("a stored measurement of the part; selecting a table row picks it too")
        self.standard_pick.setPlaceholderText("choose a measurement to make the new standard")
        self.set_standard_btn = QPushButton("Set as standard")
        self.set_standard_btn.setEnabled(False)

    def _build_buttons(self) -> None:
        """Load, judge, export and metamerism buttons (all but Load wait for data)."""
        self.load_btn = QPushButton("Load jobs")
        self.judge_btn = QPushButton("Judge")
        self.pdf_btn = QPushButton("Export PDF…")
        self.csv_btn = QPushButton("Export CSV…")
        self.mi_btn = QPushButton("Metamerism of selected")
        for b in (self.judge_btn, self.pdf_btn, self.csv_btn, self.mi_btn):
            b.setEnabled(False)

    def _build_import(self) -> None:
        """The job and part imported files are stored on, the Import button and the result lines."""
        self.import_job = QLineEdit()
        self.import_job.setPlaceholderText("job the imported panels belong to, e.g. J-2026-0300")
        self.import_part = QComboBox()
        self.import_part.addItems(list(PARTS))
        self.import_part.setCurrentText("test_panel")
        self.import_btn = QPushButton("Import files…")
        self.import_btn.setEnabled(self.sink is not None)
        self.import_btn.setToolTip("CxF3, CGATS, MA-T12 workbook or CSV files; or drop them on this tab")
        self.import_result = QLabel(
            "Import vendor files with Import files… or drop them here." if self.sink is not None else ""
        )
        self.import_result.setWordWrap(True)
        self.import_result.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)

    def _build_judging(self) -> None:
        """Averaging with its keep-outliers switch, the tolerance file and the texture limits."""
        self.average = QCheckBox("average each panel's repeats")
        self.average.setToolTip(
            "judge a panel once on the mean of its readings (station qc --average-panels)"
        )
        self.keep_outliers = QCheckBox("keep outliers")
        self.keep_outliers.setToolTip("average flagged readings in too (station qc --keep-outliers)")
        self.keep_outliers.setEnabled(False)
        self.tolerance = QLineEdit()
        self.tolerance.setPlaceholderText("tolerance set JSON (station qc tolerance --json); blank: default")
        self.tolerance_btn = QPushButton("…")
        self.tolerance_btn.setMaximumWidth(32)
        self.tolerance_btn.setToolTip("choose the tolerance set file")
        self.texture_limits = QLineEdit()
        self.texture_limits.setPlaceholderText("e.g. ds=1,dg=0.5 — ΔS / ΔG limits within one vendor")

    def _build_spc(self) -> None:
        """The SPC page and the report preview."""
        self.spc = SpcPage()
        self.preview = picture()
        self.preview.setText("Export PDF… shows the report's first page here.")
        self.preview_png = b""

    def _build_results(self) -> None:
        """The standard line, the verdict table and the status line."""
        self.standard = QLabel("Load jobs to begin.")
        self.standard.setWordWrap(True)
        self.status = QLabel(f"source: {self.model.source.where}")
        self.status.setWordWrap(True)
        self.table = QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(list(COLUMNS))
        self.table.horizontalHeader().setSectionResizeMode(len(COLUMNS) - 1, QHeaderView.ResizeMode.Stretch)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.outliers = QLabel()
        self.outliers.setWordWrap(True)
        self.outliers.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.texture_table = texture_table()

    def _lay_out(self) -> None:
        """Pickers, buttons, the import row, then the standard line, table and status."""
        form = QFormLayout()
        form.addRow("job", self.job)
        form.addRow("part", self.part)
        form.addRow("formula", self.formula)
        form.addRow("illuminant limits", self.limits)
        judging = QHBoxLayout()
        judging.addWidget(self.average)
        judging.addWidget(self.keep_outliers)
        judging.addWidget(QLabel("tolerance"))
        judging.addWidget(self.tolerance, 2)
        judging.addWidget(self.tolerance_btn)
        judging.addWidget(QLabel("texture"))
        judging.addWidget(self.texture_limits, 1)
        form.addRow("judging", judging)
        std = QHBoxLayout()
        std.addWidget(self.standard_pick, 1)
        std.addWidget(self.set_standard_btn)
        form.addRow("standard", std)
        imp = QHBoxLayout()
        imp.addWidget(self.import_job, 2)
        imp.addWidget(self.import_part, 1)
        imp.addWidget(self.import_btn)
        form.addRow("import into", imp)
        buttons = QHBoxLayout()
        for b in (self.load_btn, self.judge_btn, self.pdf_btn, self.csv_btn, self.mi_btn):
            buttons.addWidget(b)
        layout = QVBoxLayout(self)
        layout.addLayout(form)
        layout.addWidget(self.import_result)
        layout.addLayout(buttons)
        layout.addWidget(self.standard)
        self.views = QTabWidget()
        self.views.addTab(self._verdicts_page(), "Verdicts")
        self.views.addTab(self.spc, "SPC")
        self.views.addTab(scrolled(self.preview), "Report preview")
        layout.addWidget(self.views, 1)
        layout.addWidget(self.status)

    def _verdicts_page(self) -> QWidget:
        page = QWidget()
        box = QVBoxLayout(page)
        box.setContentsMargins(0, 0, 0, 0)
        box.addWidget(self.table, 3)
        box.addWidget(self.outliers)
        box.addWidget(self.texture_table, 1)
        return page

    def _connect(self) -> None:
        """Wire the buttons and pickers."""
        self.load_btn.clicked.connect(self.load_jobs)
        self.judge_btn.clicked.connect(self.judge)
        self.job.currentTextChanged.connect(self._on_job)
        self.part.currentTextChanged.connect(self._show_part)
        self.pdf_btn.clicked.connect(lambda: self.export("pdf"))
        self.csv_btn.clicked.connect(lambda: self.export("csv"))
        self.mi_btn.clicked.connect(self.metamerism)
        self.set_standard_btn.clicked.connect(self.set_standard)
        self.import_btn.clicked.connect(self.ask_import)
        self.table.itemSelectionChanged.connect(self._on_row)
        self.average.toggled.connect(self._on_average)
        self.keep_outliers.toggled.connect(self._rejudge)
        self.tolerance_btn.clicked.connect(self.ask_tolerance)
        self.spc.draw_btn.clicked.connect(self.draw_spc)

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
            self.model.judge(
                self.job.currentText(), self.formula.currentText(), self.limits.text(), self.judging()
            )
        except StationError as exc:
            self.status.setText(f"error: {exc}")
            self._clear_results()
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
        self.spc.draw_btn.setEnabled(True)
        self._show_part(self.part.currentText())
        if self.spc.png:  # a chart was shown: draw it again as now judged
            self.draw_spc()

    def judging(self) -> Judging:
        """How the samples are judged, as the pickers say."""
        return Judging(
            self.average.isChecked(),
            self.average.isChecked() and self.keep_outliers.isChecked(),
            self.tolerance.text().strip(),
            self.texture_limits.text().strip(),
        )

    def _on_average(self, on: bool) -> None:
        self.keep_outliers.setEnabled(on)
        self._rejudge()

    def _rejudge(self) -> None:
        """Judge the shown job again (the averaging or keep-outliers switch changed)."""
        if self.model.summary_key is not None and self.judge_btn.isEnabled():
            self.judge()

    def _clear_results(self) -> None:
        """No stale answer after an error: the table, outliers, texture, SPC and preview emptied."""
        self.model.summary = None
        self.model.summary_key = None
        self.table.setRowCount(0)
        self.outliers.setText("")
        self.texture_table.setRowCount(0)
        self.texture_table.setVisible(False)
        self.spc.clear("")
        self.standard.setText("no verdict")
        for b in (self.pdf_btn, self.csv_btn, self.mi_btn, self.spc.draw_btn):
            b.setEnabled(False)

    def ask_tolerance(self) -> None:
        path, _ = QFileDialog.getOpenFileName(
            self,
            "Tolerance set",
            "",
            "Tolerance JSON (*.json)",
            options=QFileDialog.Option.DontUseNativeDialog,
        )
        if path:
            self.tolerance.setText(path)

    def draw_spc(self) -> None:
        """The SPC of the shown part (``station qc spc`` with the screen's judging): the table per
        geometry, the rule hits and drift in words, the chart with the hits ringed."""
        base, subgroup = self.spc.choice()
        try:
            spc = self.model.spc(self.part.currentText(), base, subgroup)
        except StationError as exc:
            self.spc.clear(f"error: {exc}")
            return
        self.spc.show_spc(spc)

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
        self.standard_pick.clear()
        for mid, label in self.model.standard_candidates(part):
            self.standard_pick.addItem(label, mid)
        self.standard_pick.setCurrentIndex(-1)  # the line above names the standard; nothing new is chosen yet
        self.set_standard_btn.setEnabled(self.standard_pick.count() > 0)
        self.table.blockSignals(True)
        self.table.clearSelection()
        self.table.setRowCount(len(rows))
        for i, r in enumerate(rows):
            cells = (
                str(r.measurement_id),
                r.measured_at[:16].replace("T", " "),
                r.geometry,
                _signed(r.dl),
                _signed(r.da),
                _signed(r.db),
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
        self.table.blockSignals(False)
        self.outliers.setText(self.model.outliers_text(part))
        self._show_texture(entry)

    def _show_texture(self, entry: dict[str, Any] | None) -> None:
        fill_texture(self.texture_table, [] if entry is None else texture_lines(entry))

    def _on_row(self) -> None:
        """A selected sample row becomes the standard picker's choice."""
        row = self.table.currentRow()
        if row < 0 or self.table.item(row, 0) is None:
            return
        i = self.standard_pick.findData(int(cell_text(self.table, row, COLUMNS.index("sample"))))
        if i >= 0:
            self.standard_pick.setCurrentIndex(i)

    def set_standard(self) -> None:
        """Make the picked measurement the standard of the shown part, then judge the job again."""
        part, mid = self.part.currentText(), self.standard_pick.currentData()
        if mid is None:
            self.status.setText("error: standard: pick a measurement of the part first")
            return
        try:
            self.model.set_standard(part, int(mid))
        except StationError as exc:
            self.status.setText(f"error: {exc}")
            return
        self.status.setText(f"measurement {mid} is now the standard of {part}; the job was judged again")
        self._show_part(part)

    def open_job(self, job: str, part: str, measurement_id: int | None = None) -> None:
        """Show *job*'s verdicts at *part* (a job-history row opened), the rows of *measurement_id* selected."""
        self.load_jobs()
        i = self.job.findText(job)
        if i < 0:
            self.status.setText(f"error: job: expected a stored job, got {job!r}")
            return
        self.job.setCurrentIndex(i)
        self.judge()
        if self.model.summary_key is None or self.model.summary_key[0] != job:
            return
        self.part.setCurrentText(part)
        if measurement_id is not None:
            hits = [
                r for r in range(self.table.rowCount()) if cell_text(self.table, r, 0) == str(measurement_id)
            ]
            if hits:
                self.table.selectRow(hits[0])
                self.table.scrollTo(self.table.model().index(hits[0], 0))
            if not hits:
                std = (self.model.part(part) or {}).get("standard") or {}
                what = (
                    "the standard" if std.get("measurement_id") == measurement_id else "not a judged sample"
                )
                self.status.setText(
                    f"{self.status.text()} — measurement {measurement_id} is {what} of {part}"
                )

    # -- import --------------------------------------------------------------------------------------
    def _import_panel(self) -> tuple[str, str]:
        """The job and part typed for the imported panels (:class:`InputError` naming the field)."""
        job = self.import_job.text().strip() or self.job.currentText()
        if not job:
            raise InputError("import job", "a job name (type it beside Import files…)", job)
        return job, self.import_part.currentText()

    def ask_import(self) -> None:
        paths, _ = QFileDialog.getOpenFileNames(
            self,
            "Import vendor measurement files",
            "",
            import_filter(),
            options=QFileDialog.Option.DontUseNativeDialog,
        )
        if paths:
            self.import_paths([Path(p) for p in paths])

    def import_paths(self, paths: list[Path], skipped: tuple[str, ...] = ()) -> None:
        """Import *paths* in a worker through the one ingest path, then show what each file gave
        (*skipped*: names of dropped files of no importable kind, said with the result)."""
        sink = self.sink
        if sink is None or (self.task is not None and self.task.isRunning()):
            return
        try:
            job, part = self._import_panel()
        except InputError as exc:
            self.import_result.setText(f"error: {exc}")
            return
        sink.prepare()  # first open + migration on the GUI thread, never in the worker
        ingestor = sink.ingestor
        self.import_btn.setEnabled(False)
        self.import_result.setText(f"importing {len(paths)} files into {job} {part}…")
        self.task = TaskThread(lambda _p: import_files(paths, ingestor, job, part), self)
        self.task.succeeded.connect(lambda results: self._on_imported(job, results, skipped))
        self.task.failed.connect(lambda msg: self.import_result.setText(f"error: {msg}"))
        self.task.finished.connect(lambda: self.import_btn.setEnabled(True))
        self.task.start()

    def _on_imported(self, job: str, results: list[FileImport], skipped: tuple[str, ...] = ()) -> None:
        self.imports = results
        lines = [import_summary(results), *(r.text() for r in results)]
        if skipped:
            lines.append(f"not measurement files (skipped): {', '.join(skipped)}")
        self.import_result.setText("\n".join(lines))
        if any(r.stored for r in results):
            self.load_jobs()
            i = self.job.findText(job)
            if i >= 0:
                self.job.setCurrentIndex(i)

    def dragEnterEvent(self, event) -> None:
        """Vendor files dragged over the tab are accepted (other things are not)."""
        if any(importable(u.toLocalFile()) for u in event.mimeData().urls() if u.isLocalFile()):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dropEvent(self, event) -> None:
        """Vendor files dropped on the tab are imported; other files are named as refused."""
        files = [Path(u.toLocalFile()) for u in event.mimeData().urls() if u.isLocalFile()]
        ok = [f for f in files if importable(f)]
        if not ok:
            event.ignore()
            return
        event.acceptProposedAction()
        self.import_paths(ok, tuple(f.name for f in files if f not in ok))

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

        def write(_progress: object) -> tuple[Path, bytes]:
            out = self.model.report(kind, target)
            return out, (self.model.report_preview() if kind == "pdf" else b"")

        self.task = TaskThread(write, self)
        self.task.succeeded.connect(self._on_written)
        self.task.failed.connect(lambda msg: self.status.setText(f"error: {msg}"))
        self.task.finished.connect(self._export_done)
        self.task.start()

    def _on_written(self, result: object) -> None:
        path, png = cast("tuple[Path, bytes]", result)
        self.last_report = Path(str(path))
        self.status.setText(f"report written: {self.last_report}")
        if png:
            self.preview_png = png
            show_png(self.preview, png)

    def _export_done(self) -> None:
        self.pdf_btn.setEnabled(True)
        self.csv_btn.setEnabled(True)

    def closeEvent(self, event) -> None:
        if self.task is not None:
            self.task.wait()
        super().closeEvent(event)
