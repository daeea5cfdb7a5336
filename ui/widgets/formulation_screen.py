"""Formulation screen (the chemist): open a design (the current one, one sent from QA, or a file),
ColorSnap it in the library restricted to solid / metallic / pearl paints, formulate the recipe (mass
fraction and grams per batch per colorant), run the closed loop on the SYNTHETIC spray-out panel, and
export the design with its match as thesis XML or CxF3 — as ``station snap`` / ``formulate`` /
``export`` do. Every computation runs in a worker with the progress indicator.

In service mode every step runs on the service against the service's library (every stored library, or
the one picked in "library"): ``ui.models.formulation.ServiceFormulation``. The closed loop stores the
design and the job on the service and runs to its end once started (no Cancel)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.errors import InputError
from station.formulate.library import PAINT_TYPES, Library
from station.model import FaceFlopTravelGloss
from station.model.design_io import load_design
from ui.models import formulation as fm
from ui.models.document import DesignDocument
from ui.widgets.tasks import TaskProgress, TaskThread

if TYPE_CHECKING:
    from ui.models.service import ServiceClient

#: The "library" choice that searches every library the service stores.
EVERY_LIBRARY = "every stored library"

DIALOG = QFileDialog.Option.DontUseNativeDialog


class FormulationScreen(QWidget):
    """Design picker, type filter, batch size; matches, recipe and closed-loop tables; export."""

    def __init__(
        self,
        library: Library | None,
        document: DesignDocument,
        parent: QWidget | None = None,
        service: ServiceClient | None = None,
    ) -> None:
        """*library*: the local library (the demo library); with *service* every step runs on the service
        and its library instead (*library* may then be None)."""
        super().__init__(parent)
        if library is None and service is None:
            raise InputError("library", "a library, or a service to formulate on", None)
        self.library = library
        self.remote = fm.ServiceFormulation(service) if service is not None else None
        self.document = document
        self.designs: dict[str, FaceFlopTravelGloss] = {}
        self.formulation: fm.Formulation | None = None
        self.job = None
        self.snapped: fm.SnapView | None = None
        self.exported: Path | None = None
        self.task: TaskThread | None = None
        self.idle = True

        self.design = QComboBox()
        self.open_btn = QPushButton("Open design…")
        self.types = {t: QCheckBox(t) for t in PAINT_TYPES}
        for box in self.types.values():
            box.setChecked(True)
        self.batch = QDoubleSpinBox()
        self.batch.setRange(*fm.BATCH_G_RANGE)
        self.batch.setValue(fm.BATCH_G_DEFAULT)
        self.batch.setSuffix(" g")
        self.batch.setDecimals(0)
        self.snap_btn = QPushButton("ColorSnap")
        self.formulate_btn = QPushButton("Formulate")
        self.loop_btn = QPushButton("Run closed loop")
        self.export_btn = QPushButton("Export XML / CxF…")
        self.busy = TaskProgress()
        self.source = QComboBox()
        self.source.setObjectName("service-library")
        self.status = QLabel("")
        self.status.setWordWrap(True)
        if self.remote is None and library is not None:
            self.source.addItem(library.name)
            self.source.setEnabled(False)
            self.status.setText(
                f"library: {library.name} ({len(library)} paints{', SYNTHETIC' if library.synthetic else ''})"
            )
        else:
            self.refresh_libraries()
        self.matches = QTableWidget(0, 4)
        self.matches.setHorizontalHeaderLabels(["match", "type", "ΣΔE00 15/45/110", "library"])
        self.recipe = QTableWidget(0, 3)
        self.recipe.setHorizontalHeaderLabels(["component", "mass %", "grams per batch"])
        self.loop = QTableWidget(0, 3)
        self.loop.setHorizontalHeaderLabels(["step", "kind", "measured mean ΔE00"])
        for t in (self.matches, self.recipe, self.loop):
            t.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
            t.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)

        form = QFormLayout()
        row = QHBoxLayout()
        row.addWidget(self.design, 1)
        row.addWidget(self.open_btn)
        form.addRow("design", row)
        form.addRow("library", self.source)
        types = QHBoxLayout()
        for box in self.types.values():
            types.addWidget(box)
        form.addRow("paint types", types)
        form.addRow("batch", self.batch)
        buttons = QHBoxLayout()
        for b in (self.snap_btn, self.formulate_btn, self.loop_btn, self.export_btn):
            buttons.addWidget(b)
        left = QVBoxLayout()
        left.addLayout(form)
        left.addLayout(buttons)
        left.addWidget(self.busy)
        left.addWidget(self.status)
        left.addWidget(QLabel("ColorSnap matches"))
        left.addWidget(self.matches, 1)
        right = QVBoxLayout()
        right.addWidget(QLabel("recipe"))
        right.addWidget(self.recipe, 1)
        right.addWidget(QLabel("closed loop (simulated spray-out panels)"))
        right.addWidget(self.loop, 1)
        lay = QHBoxLayout(self)
        lay.addLayout(left, 1)
        lay.addLayout(right, 1)

        self.open_btn.clicked.connect(self._on_open_clicked)
        self.snap_btn.clicked.connect(self.run_snap)
        self.formulate_btn.clicked.connect(self.run_formulate)
        self.loop_btn.clicked.connect(self.run_loop)
        self.export_btn.clicked.connect(self._on_export_clicked)
        self.batch.valueChanged.connect(self._show_recipe)
        self.design.currentTextChanged.connect(self._on_design_changed)
        document.events.changed.connect(self._on_document)
        self.add_design("current design", document.design)
        self._sync()

    # ------------------------------------------------------------------ designs
    def add_design(self, label: str, design: FaceFlopTravelGloss, select: bool = False) -> None:
        """Offer *design* under *label* (replacing one of that label); *select*: make it the current pick."""
        self.designs[label] = design
        if self.design.findText(label) < 0:
            self.design.addItem(label)
        if select:
            self.design.setCurrentText(label)
        self._on_design_changed()

    def receive(self, paint: FaceFlopTravelGloss) -> None:
        """A paint sent on for formulation (QA's corrected paint): picked, ready for ColorSnap; in service
        mode also stored there as a design, so the chemist finds it (``GET /designs``)."""
        self.add_design(f"sent: {paint.name or 'paint'}", paint, select=True)
        text = f"received {paint.name or 'a paint'} for formulation: ColorSnap it, then Formulate"
        if self.remote is not None:
            from ui.models.service import ServiceError

            try:
                design_id = self.remote.client.save_design(
                    paint.name or "corrected paint", paint, "QA correction, for formulation"
                )
            except ServiceError as exc:
                text += f"\nnot stored on the service for the chemist: {exc}"
            else:
                text += f"\nstored on the service as design #{design_id} for the chemist"
        self.status.setText(text)

    def picked(self) -> FaceFlopTravelGloss:
        """The design being formulated."""
        return self.designs[self.design.currentText()]

    def chosen_types(self) -> list[str]:
        """The paint types ticked."""
        return [t for t, box in self.types.items() if box.isChecked()]

    def _on_document(self, design) -> None:
        self.designs["current design"] = design
        if self.design.currentText() == "current design":
            self._on_design_changed()

    def _on_design_changed(self, *_args) -> None:
        self.formulation = None
        self.job = None
        for t in (self.matches, self.recipe, self.loop):
            t.setRowCount(0)
        self._sync()

    def _on_open_clicked(self) -> None:
        path, _f = QFileDialog.getOpenFileName(
            self, "Open design", str(Path.cwd()), "designs (*.json)", options=DIALOG
        )
        if path:
            self.open_design(Path(path))

    def open_design(self, path: Path) -> None:
        """Load a design file and pick it (a file that is not a design is shown, not raised)."""
        try:
            design = load_design(path)
        except (InputError, OSError, ValueError) as exc:
            self.status.setText(f"error: {exc}")
            return
        self.add_design(f"file: {Path(path).name}", design, select=True)

    # ------------------------------------------------------------------ work
    def _run(self, fn, done, label: str, pure: bool = True, cancellable: bool = True) -> None:
        if self.task is not None and self.task.isRunning():
            return
        self.idle = False
        self.status.setText(label)
        self.task = TaskThread(fn, pure=pure)
        self.task.succeeded.connect(done)
        self.task.failed.connect(self._on_failed)
        self.task.cancelled.connect(lambda: self.status.setText("cancelled"))
        self.task.finished.connect(self._on_finished)
        self.busy.watch(self.task, label, cancellable=cancellable)
        self._sync(busy=True)
        self.task.start()

    def refresh_libraries(self) -> None:
        """Service mode: offer the service's stored libraries (``GET /library/libraries``)."""
        if self.remote is None:
            return
        from ui.models.service import ServiceError

        self.source.clear()
        self.source.addItem(EVERY_LIBRARY)
        try:
            libs = self.remote.libraries()
        except ServiceError as exc:
            self.status.setText(f"error: the service's libraries: {exc}")
            return
        for lib in libs:
            self.source.addItem(str(lib["name"]))
        total = sum(int(lib["paints"]) for lib in libs)
        self.status.setText(
            f"library: service {self.remote.client.url}, {total} paints in {len(libs)} stored "
            f"librar{'y' if len(libs) == 1 else 'ies'} ({', '.join(str(lib['name']) for lib in libs)})"
        )

    def _remote(self) -> fm.ServiceFormulation | None:
        """The service formulation with the library picked, or None in local mode."""
        if self.remote is not None:
            text = self.source.currentText()
            self.remote.library = None if text in ("", EVERY_LIBRARY) else text
        return self.remote

    def _library(self) -> Library | None:
        try:
            if self.library is None:  # service mode: the service filters; the types are checked here
                fm.checked_types(self.chosen_types())
                return None
            return fm.filtered(self.library, self.chosen_types())
        except InputError as exc:
            self.status.setText(f"error: {exc}")
            return None

    def _types_ok(self) -> bool:
        try:
            fm.checked_types(self.chosen_types())
        except InputError as exc:
            self.status.setText(f"error: {exc}")
            return False
        return True

    def run_snap(self) -> None:
        """ColorSnap the design in the library of the ticked types (the service's in service mode)."""
        design, remote = self.picked(), self._remote()
        if remote is not None:
            if self._types_ok():
                types = self.chosen_types()
                self._run(
                    lambda _p: remote.snap(design, types), self._on_snapped, "ColorSnap on the service…"
                )
            return
        lib = self._library()
        if lib is not None:
            self._run(
                lambda _p: fm.snap_view(lib, fm.snap(design, lib)),
                self._on_snapped,
                f"ColorSnap in {len(lib)} paints…",
            )

    def run_formulate(self) -> None:
        """Formulate the recipe from the matches' recipes."""
        design, remote = self.picked(), self._remote()
        if remote is not None:
            if self._types_ok():
                types = self.chosen_types()
                self._run(
                    lambda _p: remote.formulate(design, types),
                    self._on_formulated,
                    "formulating on the service…",
                )
            return
        lib = self._library()
        if lib is not None:
            self._run(
                lambda _p: fm.formulate(design, lib),
                self._on_formulated,
                f"formulating in {len(lib)} paints…",
            )

    def run_loop(self) -> None:
        """Spray, measure, correct until within tolerance."""
        f, remote = self.formulation, self._remote()
        if f is None:
            return
        if remote is not None:
            design = f.design
            self._run(
                lambda _p: remote.closed_loop(design),
                self._on_loop,
                "closed loop on the service: spraying and measuring…",
                pure=False,
                cancellable=False,
            )
            return
        self._run(lambda _p: fm.closed_loop(f), self._on_loop, "closed loop: spraying and measuring…")

    def _on_export_clicked(self) -> None:
        name = (self.picked().name or "design").replace(" ", "-")
        path, _f = QFileDialog.getSaveFileName(
            self,
            "Export design and match",
            str(Path.cwd() / f"{name}.xml"),
            "thesis XML (*.xml);;CxF3 (*.cxf)",
            options=DIALOG,
        )
        if path:
            self.export(Path(path))

    def export(self, path: Path) -> None:
        """Write the design and its ColorSnap match (library of the ticked types; in service mode the
        service's export with its library's match) to *path*."""
        design, remote = self.picked(), self._remote()
        if remote is not None:
            self._run(
                lambda _p: remote.export(design, path),
                self._on_exported,
                f"exporting to {path.name} on the service…",
                False,
                False,
            )
            return
        lib = self._library()
        if lib is not None:
            self._run(
                lambda _p: fm.export(design, lib, path),
                self._on_exported,
                f"exporting to {path.name}…",
                False,
                False,
            )

    # ------------------------------------------------------------------ results
    def _on_finished(self) -> None:
        self.idle = True
        self._sync()

    def _on_failed(self, message: str) -> None:
        self.status.setText(f"error: {message}")

    def _show_matches(self, view: fm.SnapView) -> None:
        self.matches.setRowCount(len(view.rows))
        for i, (code, kind, sum_de, library) in enumerate(view.rows):
            for j, text in enumerate((code, kind, f"{sum_de:.2f}", library)):
                self.matches.setItem(i, j, QTableWidgetItem(text))

    def _on_snapped(self, view: fm.SnapView) -> None:
        self.snapped = view
        self._show_matches(view)
        warn = "; ".join(view.warnings)
        self.status.setText(f"{len(view.rows)} matches in {view.searched}" + (f" — {warn}" if warn else ""))

    def _on_formulated(self, f) -> None:
        self.formulation = f
        self._show_matches(f.shown)
        self._show_recipe()
        r = f.result
        self.status.setText(
            f"recipe from {r.start}: predicted ΔE00 mean {r.mean_de:.2f}, max {r.max_de:.2f} "
            f"({'formulable' if r.formulable else 'NOT formulable'} at {r.tolerance:g}); {r.message}"
            + (" (SYNTHETIC colorants)" if r.synthetic else "")
        )

    def _show_recipe(self, *_args) -> None:
        if self.formulation is None:
            return
        rows = fm.batch_rows(self.formulation.result.recipe, self.batch.value())
        self.recipe.setRowCount(len(rows))
        for i, (name, frac, grams) in enumerate(rows):
            for j, text in enumerate((name, f"{100 * frac:.2f}", f"{grams:.1f}")):
                self.recipe.setItem(i, j, QTableWidgetItem(text))

    def _on_loop(self, job) -> None:
        self.job = job
        self.loop.setRowCount(len(job.steps))
        for i, s in enumerate(job.steps):
            for j, text in enumerate((str(s.number), s.kind, f"{s.mean_de:.2f}")):
                self.loop.setItem(i, j, QTableWidgetItem(text))
        stored = f"; stored on the service as job {job.recipe_id}" if hasattr(job, "recipe_id") else ""
        self.status.setText(
            f"closed loop {job.status}: {job.message} ({job.corrections} corrections){stored}"
        )

    def _on_exported(self, got) -> None:
        path, code = got
        self.exported = path
        self.status.setText(f"exported {path} (match {code})")

    def _sync(self, busy: bool = False) -> None:
        busy = busy or (self.task is not None and self.task.isRunning())
        for b in (self.snap_btn, self.formulate_btn, self.export_btn, self.open_btn):
            b.setEnabled(not busy)
        self.loop_btn.setEnabled(not busy and self.formulation is not None)

    def closeEvent(self, event) -> None:
        if self.task is not None:
            self.task.wait()
        self.document.events.changed.disconnect(self._on_document)
        super().closeEvent(event)
