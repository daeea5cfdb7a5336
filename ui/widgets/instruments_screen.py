"""Instruments screen: connect (simulators offered), pair a gloss meter, calibrate, scan a panel with
progress, see the reading (L*, a*, b* per angle with the fitted curve, the gloss meter's 20/60/85° GU,
haze and DOI, and a rendering), store it in the measurement database with the panel metadata (job,
part, substrate, notes).

Progress: steps done of a scan (gloss and colour measured, Lab and fit, stored, shown); a step of
unknown length (connecting, calibrating) shows a busy bar, never a jump to 100 % before it is done.

Every blocking call (the scan and its store included) runs in a :class:`~ui.widgets.tasks.TaskThread`; the
thread is joined and the instrument (and simulator) closed when the screen closes. Errors are shown in the
log as they are; a reading the database or service could not take stays in the on-disk outbox.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QComboBox,
    QFormLayout,
    QGridLayout,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMessageBox,
    QPlainTextEdit,
    QProgressBar,
    QPushButton,
    QSizePolicy,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from db.models import PARTS
from station.design.palette import booklet
from station.drivers import CalibrationStepResult
from station.errors import InputError
from station.scan import CalibrationSession, CalibrationStep
from ui.models.document import DesignDocument
from ui.models.instruments import SIM_DEVICES, STEPS, InstrumentSession, Measurement, MeasurementStore
from ui.models.measure_db import RECENT_MAX, PanelInfo
from ui.widgets.common import cell_text, lab_colour, pixmap_from_array
from ui.widgets.reading_plot import ReadingPlot
from ui.widgets.tasks import TaskProgress, TaskThread

PROMPT_BUTTONS = QMessageBox.StandardButton.Ok | QMessageBox.StandardButton.Cancel


class InstrumentsScreen(QWidget):
    """Device picker, actions, progress, the last reading and the stored list."""

    def __init__(
        self,
        store: MeasurementStore,
        document: DesignDocument | None = None,
        parent: QWidget | None = None,
        open_job: Callable[[str, str, int], None] | None = None,
    ) -> None:
        super().__init__(parent)
        self.store = store
        self.document = document
        self.open_job = open_job
        self.session = InstrumentSession()
        self.task: TaskThread | None = None
        self.last: Measurement | None = None
        self._task_done = True  # no task running and its result handled (see :attr:`idle`)
        self.prompt: QMessageBox | None = None  # the calibration prompt on screen (tests answer it)
        self.calibration: CalibrationSession | None = None  # the steps being asked for and run
        self._build_panel_form()
        self._build_actions()
        self._build_reading()
        self._lay_out()
        self._connect()
        self._sync_buttons()

    def _build_panel_form(self) -> None:
        """Device and gloss meter pickers and the panel metadata (job, part, substrate, notes)."""
        self.device = QComboBox()
        self.device.setEditable(True)
        self.device.addItems(list(SIM_DEVICES))
        self.gloss_device = QComboBox()
        self.gloss_device.setEditable(True)
        self.gloss_device.addItems(["sim:gloss"])
        self.gloss_device.setToolTip(
            "a gloss meter read with every scan; its 60° gloss is stored with the colour"
        )
        self.job = QLineEdit("J-0001")
        self.part = QComboBox()
        self.part.addItems(list(PARTS))
        self.part.setCurrentText("test_panel")
        self.substrate = QLineEdit()
        self.substrate.setPlaceholderText("e.g. PP/EPDM, steel")
        self.notes = QPlainTextEdit()
        self.notes.setPlaceholderText("notes stored with the panel")
        self.notes.setMaximumHeight(54)
        self.notes.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)

    def _build_actions(self) -> None:
        """The buttons, progress, state line, storage line and log."""
        self.pair_btn = QPushButton("Pair gloss meter")
        self.retry_btn = QPushButton("Retry queued")
        self.history_btn = QPushButton("Job history")
        self.history_btn.setToolTip("every stored measurement of the job typed above (database or service)")
        self.connect_btn = QPushButton("Connect")
        self.calibrate_btn = QPushButton("Calibrate")
        self.calibrate_btn.setToolTip("asks for the black trap and the white tile, then calibrates")
        self.scan_btn = QPushButton("Scan panel")
        self.use_btn = QPushButton("Use as design")
        self.progress = QProgressBar()
        self.progress.setRange(0, STEPS)
        self.state = QLabel("not connected")
        self.busy = TaskProgress()
        self.where = QLabel(self._where_text())
        self.where.setWordWrap(True)
        self.log = QPlainTextEdit()
        self.log.setReadOnly(True)
        self.log.setMaximumBlockCount(500)

    def _build_reading(self) -> None:
        """The last reading (table, swatch, gloss, plot), the session's scans and the job history."""
        self.gloss = QLabel("gloss: no gloss meter paired")
        self.gloss.setWordWrap(True)
        self.table = QTableWidget(0, 5)
        self.table.setHorizontalHeaderLabels(["geometry", "L*", "a*", "b*", "colour"])
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
        self.table.verticalHeader().setDefaultSectionSize(20)
        self.table.setMinimumHeight(150)
        self.swatch = QLabel()
        self.swatch.setMinimumSize(160, 160)
        self.plot = ReadingPlot()
        self.stored = QListWidget()
        self.history = QListWidget()
        self.history.setToolTip("double-click a measurement to open its job's verdicts in the QC tab")
        self.history_title = QLabel("job history (stored): click Job history")

    def _lay_out(self) -> None:
        """Form, buttons and log on the left; the reading and the lists on the right."""
        form = QFormLayout()
        form.addRow("device", self.device)
        pair = QHBoxLayout()
        pair.addWidget(self.gloss_device, 1)
        pair.addWidget(self.pair_btn)
        form.addRow("gloss meter", pair)
        form.addRow("job", self.job)
        form.addRow("part", self.part)
        form.addRow("substrate", self.substrate)
        form.addRow("notes", self.notes)
        buttons = QGridLayout()  # two rows of three: the screen fits beside the designer at 1280 px
        for i, btn in enumerate(
            (
                self.connect_btn,
                self.calibrate_btn,
                self.scan_btn,
                self.use_btn,
                self.retry_btn,
                self.history_btn,
            )
        ):
            buttons.addWidget(btn, i // 3, i % 3)
        left = QVBoxLayout()
        left.addLayout(form)
        left.addLayout(buttons)
        for w in (self.progress, self.busy, self.state, self.where, QLabel("log"), self.log):
            left.addWidget(w)
        right = QVBoxLayout()
        right.addWidget(QLabel("last reading"))
        row = QHBoxLayout()
        row.addWidget(self.table, 2)
        row.addWidget(self.swatch, 1)
        right.addLayout(row)
        right.addWidget(self.gloss)
        right.addWidget(self.plot, 3)
        right.addWidget(QLabel("scans since the viewer started"))
        right.addWidget(self.stored, 1)
        right.addWidget(self.history_title)
        right.addWidget(self.history, 1)
        lay = QHBoxLayout(self)
        lay.addLayout(left, 1)
        lay.addLayout(right, 2)

    def _connect(self) -> None:
        """Wire the buttons, the history list and the store's events."""
        self.connect_btn.clicked.connect(self.connect_device)
        self.pair_btn.clicked.connect(self.toggle_gloss)
        self.calibrate_btn.clicked.connect(self.calibrate)
        self.scan_btn.clicked.connect(self.scan)
        self.use_btn.clicked.connect(self.use_as_design)
        self.retry_btn.clicked.connect(self.retry)
        self.history_btn.clicked.connect(self.job_history)
        self.history.itemDoubleClicked.connect(self._on_history_opened)
        self.store.events.added.connect(self._on_added)

    @property
    def idle(self) -> bool:
        """Nothing under way: no task running (its result handled) and no calibration in progress.

        A calibration is busy from its first prompt to its outcome, prompts and the moments between a
        prompt closing and its step's worker starting included, so the screen never reads idle while
        a reference is still to be asked for or read."""
        return self._task_done and self.calibration is None and self.prompt is None

    # ------------------------------------------------------------------ actions
    def _run(self, fn, done, label: str, steps: int = 0, failed=None) -> None:
        """Run *fn* in a worker; *steps* > 0: a bar of that many steps, 0: a busy bar (unknown length);
        *failed* hears the error message (default: the log and the state line)."""
        if self.task is not None and self.task.isRunning():
            if not self.task.result_sent:
                self._say("busy: wait for the running task")
                return
            self.task.wait()  # it has sent its result and is returning: the next task may start
        if self.store.sink is not None:
            self.store.sink.prepare()  # first open + migration on the GUI thread, never in the worker
        self.progress.setRange(0, steps)
        self.progress.setValue(0)
        self.state.setText(label)
        self.task = task = TaskThread(fn)
        self.task.progress.connect(self._on_progress)
        self._task_done = False
        self.task.succeeded.connect(done)
        self.task.failed.connect(failed or self._on_failed)
        self.task.cancelled.connect(self._on_cancelled)
        self.busy.watch(self.task, label, steps, cancellable=steps > 0)  # a scan stops between steps
        self.task.finished.connect(self._sync_buttons)
        # Idle only once the thread has ended and the buttons are live again: the result signal comes
        # first (the result is shown), but until ``finished`` the buttons are still disabled and a new
        # task would be refused as busy.
        task.finished.connect(lambda: self._on_task_done(task))
        self._sync_buttons(busy=True)
        self.task.start()

    def connect_device(self) -> None:
        """Open the chosen device (a simulator is started for ``sim:*``)."""
        device = self.device.currentText()
        self._run(lambda _p: self.session.connect(device), self._on_connected, f"connecting {device}…")

    def toggle_gloss(self) -> None:
        """Pair the gloss meter typed beside "gloss meter" (a simulator for ``sim:gloss``), or unpair it."""
        if self.session.gloss_meter is not None:
            self.session.unpair_gloss()
            self._say("gloss meter unpaired")
            self.gloss.setText("gloss: no gloss meter paired")
            self._sync_buttons()
            return
        device = self.gloss_device.currentText()
        self._run(lambda _p: self.session.pair_gloss(device), self._on_paired, f"pairing {device}…")

    def calibration_prompts(self) -> list[tuple[str, str]]:
        """(title, text) of each reference the technician is asked for, in the instruments' order: the
        black trap (zero), the white tile, the verification tile, then the paired gloss meter's
        standard (``station.scan.CalibrationSession``)."""
        if not self.session.connected:
            return []
        return [(s.title, s.prompt) for s in self.session.calibration().steps]

    def calibrate(self) -> None:
        """Calibrate step by step: ask for each reference in turn, and on OK read it (that step alone,
        in a worker) before asking for the next. Cancel between steps stops the calibration: the
        instrument is then not calibrated (after the black trap it needs its white tile again). A
        failed step stops it too, its message naming the step."""
        if self.prompt is not None or self.calibration is not None or not self.session.connected:
            return
        self.calibration = self.session.calibration()
        self._sync_buttons(busy=True)
        self._next_prompt()

    def _next_prompt(self) -> None:
        cal = self.calibration
        step = None if cal is None else cal.next
        if cal is None or step is None:
            self.prompt, self.calibration = None, None
            if cal is not None:
                self._on_calibrated(cal.results())
            self._sync_buttons()
            return
        box = QMessageBox(QMessageBox.Icon.Information, step.title, step.prompt, PROMPT_BUTTONS, self)
        box.setDefaultButton(QMessageBox.StandardButton.Ok)
        box.setEscapeButton(QMessageBox.StandardButton.Cancel)
        box.setWindowModality(Qt.WindowModality.WindowModal)
        box.finished.connect(lambda _r, b=box, st=step: self._on_prompt(b, st))
        self.prompt = box
        self.state.setText(f"calibration: {step.title.lower()}")
        box.open()

    def _on_prompt(self, box: QMessageBox, step: CalibrationStep) -> None:
        """A prompt answered: on OK its step is read, then the next prompt; on Cancel the calibration
        stops, not calibrated."""
        ok = box.clickedButton() is box.button(QMessageBox.StandardButton.Ok)
        box.deleteLater()
        self.prompt = None
        cal = self.calibration
        if cal is None:
            return
        if ok:
            label = f"calibration: reading the {step.title.lower()} of {step.device}…"
            self._run(lambda _p: cal.run_next(), self._on_step_done, label, failed=self._on_step_failed)
            return
        cal.cancel()
        self.calibration = None
        self.state.setText("calibration cancelled")
        self._say(f"calibration cancelled at the {step.title.lower()}: {step.device} is {cal.state}")
        self._sync_buttons()

    def _on_step_done(self, result: CalibrationStepResult) -> None:
        de = "" if result.verification_de is None else f" (ΔE00 {result.verification_de:.3f})"
        self._say(f"calibration step {result.step} done{de}")
        self._next_prompt()

    def _on_step_failed(self, message: str) -> None:
        """A step failed: the message names it; the calibration is over, not calibrated."""
        self._on_failed(message)
        self.calibration = None
        self.state.setText(message.partition(": ")[2] or message)
        self._sync_buttons()

    def panel_info(self) -> PanelInfo:
        """The panel metadata as typed (validated: :class:`InputError` names the field)."""
        return PanelInfo(
            self.job.text(), self.part.currentText(), self.substrate.text(), self.notes.toPlainText()
        ).validated()

    def scan(self) -> None:
        """Measure the panel; the reading is stored (or queued on disk) in the worker, then shown."""
        try:
            panel = self.panel_info()
        except InputError as exc:
            self._on_failed(str(exc))
            return
        self._run(
            lambda p: self.session.scan(panel, p, self.store),
            self._on_scanned,
            f"scanning {panel.label}…",
            STEPS,
        )

    def retry(self) -> None:
        """Send the readings waiting in the outbox."""
        sink = self.store.sink
        if sink is None:
            return
        self._run(lambda _p: sink.flush(), self._on_retried, "sending queued readings…")

    def job_history(self) -> None:
        """List every stored measurement of the typed job, newest first (read in a worker)."""
        sink = self.store.sink
        job = self.job.text().strip()
        if sink is None or not job:
            return
        self._run(
            lambda _p: [r for r in sink.recent(RECENT_MAX) if r.label.startswith(job + " ")],
            lambda rows: self._on_history(job, rows),
            f"reading the history of job {job}…",
        )

    def _on_history(self, job: str, rows: list) -> None:
        self._done_bar()
        self.history.clear()
        for r in rows:
            item = QListWidgetItem(f"#{r.id}  {r.measured_at}  {r.label}  {len(r.geometries_deg)} geometries")
            item.setData(Qt.ItemDataRole.UserRole, (job, r.label[len(job) + 1 :], r.id))
            self.history.addItem(item)
        self.history_title.setText(f"job history (stored): {len(rows)} measurements of job {job}")
        self.state.setText(f"{len(rows)} stored measurements of job {job}")

    def _on_history_opened(self, item: QListWidgetItem) -> None:
        """A history row double-clicked: its job's verdicts (in the QC tab), that measurement selected."""
        job, part, measurement_id = item.data(Qt.ItemDataRole.UserRole)
        if self.open_job is None:
            self.state.setText("no QC tab to open the job in")
            return
        self.open_job(job, part, int(measurement_id))

    def _where_text(self) -> str:
        sink = self.store.sink
        if sink is None:
            return "storage: none (scans kept only until the viewer closes)"
        waiting = sink.pending()
        queued = f" ({waiting} readings waiting: Retry queued)" if waiting else ""
        return f"storage: {sink.where}; outbox {sink.outbox_path}{queued}"

    def use_as_design(self) -> None:
        """Make the last reading's fitted design the current design (undoable)."""
        if self.document is not None and self.last is not None and self.last.design is not None:
            self.document.set_design(self.last.design, f"measured {self.last.panel.label}")

    # ------------------------------------------------------------------ results
    def _on_task_done(self, task: TaskThread) -> None:
        """*task* ended: idle again unless a newer task has started since (its end comes later)."""
        if task is self.task:
            self._task_done = True

    def _say(self, text: str) -> None:
        self.log.appendPlainText(text)

    def _on_progress(self, step: int, text: str) -> None:
        self.progress.setValue(step)
        self.state.setText(text)

    def _done_bar(self) -> None:
        """The task is done and its result shown: a full bar."""
        self.progress.setRange(0, STEPS)
        self.progress.setValue(STEPS)

    def _on_cancelled(self) -> None:
        self.progress.setRange(0, STEPS)
        self.progress.setValue(0)
        self.state.setText("cancelled")
        self._say("cancelled: nothing was stored")

    def _on_failed(self, message: str) -> None:
        self.progress.setRange(0, STEPS)
        self.progress.setValue(0)
        self.state.setText("failed")
        self._say(f"ERROR {message}")

    def _on_connected(self, address: str) -> None:
        self._done_bar()
        self.state.setText(f"connected: {address}")
        self._say(f"connected {self.session.device} at {address}")

    def _on_paired(self, address: str) -> None:
        self._done_bar()
        self.pair_btn.setText("Unpair gloss meter")
        self.state.setText(f"gloss meter paired: {address}")
        self.gloss.setText(f"gloss: {self.session.gloss_device} paired, read with every scan")
        self._say(f"paired gloss meter {self.session.gloss_device} at {address}")

    def _on_calibrated(self, results) -> None:
        self._done_bar()
        passed = all(r.passed for _d, r in results)
        self.state.setText(f"calibration {'passed' if passed else 'FAILED'}")
        for device, r in results:
            verdict = "passed" if r.passed else "FAILED"
            de = "" if r.verification_de is None else f", verification ΔE00 {r.verification_de}"
            self._say(
                f"calibration of {device}: {r.calibration_id} {verdict}: steps {', '.join(r.steps)}{de}"
            )

    def _on_scanned(self, m: Measurement) -> None:
        self._done_bar()
        self.store.add(m)
        self.where.setText(self._where_text())
        r = m.receipt
        g = m.gloss_receipt
        if m.gloss_only and (g is None or g.gloss_reading_id is None):
            self.state.setText("gloss reading NOT STORED" if g is not None else "gloss reading shown")
            self._say(
                f"{'ERROR ' if g is not None else ''}gloss reading {m.panel.label}: {m.gloss_text()}; "
                f"{g.message if g is not None else 'not stored (no database)'}"
            )
        elif m.gloss_only and g is not None:
            self.state.setText(f"stored as gloss reading {g.gloss_reading_id}")
            self._say(f"{g.status} {m.panel.label} as gloss reading {g.gloss_reading_id}: {m.gloss_text()}")
        elif r is None:
            self._say(
                f"scanned {m.panel.label} ({len(m.geometries)} geometries) {m.note}; not stored (no database)"
            )
        elif r.status in ("stored", "duplicate"):
            self.state.setText(f"stored as measurement {r.measurement_id}")
            self._say(
                f"{r.status} {m.panel.label} as measurement {r.measurement_id} "
                f"({len(m.geometries)} geometries) {m.note}"
            )
        else:
            self.state.setText("NOT STORED — kept in the outbox" if r.status == "queued" else "REFUSED")
            self._say(f"ERROR {r.message}")

    def _on_retried(self, receipts: dict) -> None:
        self._done_bar()
        self.where.setText(self._where_text())
        done = [r for r in receipts.values() if r.status in ("stored", "duplicate")]
        left = self.store.sink.pending() if self.store.sink is not None else 0
        self.state.setText(f"{len(done)} sent, {left} still queued")
        self._say(f"retry: {len(done)} sent, {left} still queued")
        for r in receipts.values():
            if r.message:
                self._say(f"ERROR {r.message}")

    def _on_added(self, m: Measurement) -> None:
        self.last = m
        gloss_receipt = m.gloss_receipt
        status = (
            (
                f"gloss #{gloss_receipt.gloss_reading_id}"
                if gloss_receipt is not None and gloss_receipt.gloss_reading_id
                else "gloss only, not stored"
            )
            if m.gloss_only
            else "session only"
            if m.receipt is None
            else (
                f"#{m.receipt.measurement_id}"
                if m.receipt.measurement_id is not None
                else m.receipt.status.upper()
            )
        )
        self.stored.addItem(f"{m.time}  {m.panel.label}  {status}  {m.device}  {m.note}")
        self.table.setRowCount(len(m.geometries))
        for i, (g, lab) in enumerate(zip(m.geometries, m.lab, strict=True)):
            for j, text in enumerate((g, *(f"{v:.2f}" for v in lab))):
                self.table.setItem(i, j, QTableWidgetItem(text))
            sw = QTableWidgetItem("")
            sw.setBackground(lab_colour(lab))
            self.table.setItem(i, 4, sw)
        self.gloss.setText(
            f"gloss ({m.device if m.gloss_only else self.session.gloss_device}): {m.gloss_text()}"
            if m.gloss is not None
            else "gloss: not measured (no gloss meter paired)"
        )
        if m.design is not None:
            self.swatch.setPixmap(pixmap_from_array(booklet(m.design, 160)))
        else:
            self.swatch.clear()
        self.plot.set_reading(m.aspecular_deg, m.lab, m.design)
        self._sync_buttons()

    def _sync_buttons(self, busy: bool = False) -> None:
        busy = (
            busy
            or self.prompt is not None
            or self.calibration is not None
            or (self.task is not None and self.task.isRunning())
        )
        self.connect_btn.setEnabled(not busy)
        self.pair_btn.setEnabled(not busy)
        self.pair_btn.setText(
            "Unpair gloss meter" if self.session.gloss_meter is not None else "Pair gloss meter"
        )
        self.calibrate_btn.setEnabled(not busy and self.session.connected)
        self.scan_btn.setEnabled(not busy and self.session.connected)
        self.retry_btn.setEnabled(not busy and self.store.sink is not None)
        self.history_btn.setEnabled(not busy and self.store.sink is not None)
        self.use_btn.setEnabled(
            self.last is not None and self.last.design is not None and self.document is not None
        )

    def lab_table(self) -> np.ndarray:
        """The Lab values shown in the table (rows × 3)."""
        return np.array(
            [[float(cell_text(self.table, i, j)) for j in (1, 2, 3)] for i in range(self.table.rowCount())]
        )

    def closeEvent(self, event) -> None:
        if self.prompt is not None:
            self.prompt.reject()  # a calibration waiting at a prompt is cancelled
        if self.task is not None:
            self.task.wait()
        self.session.close()
        self.store.events.added.disconnect(self._on_added)
        super().closeEvent(event)
