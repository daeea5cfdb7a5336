"""Formulation screen (the chemist): open a design (the current one, one sent from QA, or a file),
ColorSnap it in the library restricted to solid / metallic / pearl paints (the five matches stay listed
after Formulate), formulate the recipe (mass fraction and grams per batch per colorant; the ranked
recipes side by side, ``ui.models.formulation_tables``), run the closed loop on the SYNTHETIC spray-out
panel (per step the measured ΔE00 and the tinting additions, or "remake" with the new recipe), and
export the design with its match and recipe as thesis XML or CxF3 (recipe in grams and predicted
spectra) — as ``station snap`` / ``formulate`` / ``export --recipe`` do. Every computation runs in a
worker with the progress indicator.

In service mode every step runs on the service against the service's library (every stored library, or
the one picked in "library"): ``ui.models.formulation.ServiceFormulation``. The closed loop stores the
design and the job on the service and runs to its end once started (no Cancel)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

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
from ui.models import formulation_tables as ft
from ui.models.document import DesignDocument
from ui.widgets.tasks import TaskProgress, TaskThread

if TYPE_CHECKING:
    from ui.models.service import ServiceClient

#: The "library" choice that searches every library the service stores.
EVERY_LIBRARY = "every stored library"

DIALOG = QFileDialog.Option.DontUseNativeDialog
#: Columns of the closed-loop table: one group of rows per step, one row per colorant line.
LOOP_COLUMNS = ("step", "action", "mean ΔE00", "colorant", "g for the batch")


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
        self.formulation: fm.Formulation | fm.ServiceFormulated | None = None
        self.job: Any = None
        self.snapped: fm.SnapView | None = None
        self.exported: Path | None = None
        self.task: TaskThread | None = None
        self.idle = True
        self._build_controls()
        self._build_tables()
        self._build_layout()
        self._init_source(library)
        self._connect()
        self.add_design("current design", document.design)
        self._sync()

    def _build_controls(self) -> None:
        """Design picker, library, type filter, batch, the four action buttons, progress and status."""
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
        for combo in (self.design, self.source):  # a long design or library name must not widen the screen
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(24)
        self.status = QLabel("")
        self.status.setWordWrap(True)

    def _build_tables(self) -> None:
        """Matches, the recipe weighed out for the batch, the recipes side by side and the closed loop."""
        self.matches = QTableWidget(0, 4)
        self.matches.setHorizontalHeaderLabels(["match", "type", "ΣΔE00 15/45/110", "library"])
        self.recipe = QTableWidget(0, 3)
        self.recipe.setHorizontalHeaderLabels(["component", "mass %", "grams per batch"])
        self.recipes = QTableWidget(0, 0)
        self.recipes.setObjectName("recipes-side-by-side")
        self.loop = QTableWidget(0, len(LOOP_COLUMNS))
        self.loop.setHorizontalHeaderLabels(list(LOOP_COLUMNS))
        for t in (self.matches, self.recipe, self.recipes, self.loop):
            t.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
            t.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        fit = QHeaderView.ResizeMode.ResizeToContents
        for t, columns in ((self.recipe, (1, 2)), (self.loop, (0, 1, 2, 4))):
            t.verticalHeader().hide()
            for j in columns:
                t.horizontalHeader().setSectionResizeMode(j, fit)

    def _build_layout(self) -> None:
        """The form and buttons over the matches and the side-by-side recipes (left); the recipe for the
        batch and the closed loop (right)."""
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
        left.addWidget(QLabel("recipes side by side (g per kg of batch)"))
        left.addWidget(self.recipes, 1)
        right = QVBoxLayout()
        right.addWidget(QLabel("recipe weighed out for the batch"))
        right.addWidget(self.recipe, 1)
        right.addWidget(QLabel("closed loop (simulated spray-out): ΔE00, additions per step"))
        right.addWidget(self.loop, 1)
        lay = QHBoxLayout(self)
        lay.addLayout(left, 1)
        lay.addLayout(right, 1)

    def _init_source(self, library: Library | None) -> None:
        """The library choice: the local library (fixed) or the service's stored libraries."""
        if self.remote is None and library is not None:
            self.source.addItem(library.name)
            self.source.setEnabled(False)
            self.status.setText(
                f"library: {library.name} ({len(library)} paints{', SYNTHETIC' if library.synthetic else ''})"
            )
        else:
            self.refresh_libraries()

    def _connect(self) -> None:
        self.open_btn.clicked.connect(self._on_open_clicked)
        self.snap_btn.clicked.connect(self.run_snap)
        self.formulate_btn.clicked.connect(self.run_formulate)
        self.loop_btn.clicked.connect(self.run_loop)
        self.export_btn.clicked.connect(self._on_export_clicked)
        self.batch.valueChanged.connect(self._show_recipe)
        self.batch.valueChanged.connect(self._show_loop)
        self.design.currentTextChanged.connect(self._on_design_changed)
        self.document.events.changed.connect(self._on_document)

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
        self.snapped = None
        for t in (self.matches, self.recipe, self.recipes, self.loop):
            t.setRowCount(0)
        self.recipes.setColumnCount(0)
        self.loop.clearSpans()
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
        if isinstance(f, fm.Formulation):
            local, batch = f, self.batch.value()
            self._run(
                lambda _p: fm.closed_loop(local, batch_g=batch),
                self._on_loop,
                f"closed loop for a {batch:g} g batch: spraying and measuring…",
            )

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
        """Write the design, its ColorSnap match (library of the ticked types) and its recipe — in CxF3
        with the grams for the batch and the predicted spectra, as ``station export --recipe`` — to
        *path*; in service mode the service's export with its library's match."""
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
        lib, batch = self._library(), self.batch.value()
        if lib is not None:
            done = self._formulated_for(design, lib)
            self._run(
                lambda _p: fm.export(design, lib, path, done, batch),
                self._on_exported,
                f"exporting to {path.name}…",
                False,
                False,
            )

    def _formulated_for(self, design: FaceFlopTravelGloss, lib: Library) -> Any:
        """The recipe already formulated for *design* in *lib* (None: the export formulates it)."""
        f = self.formulation
        if isinstance(f, fm.Formulation) and f.design is design and f.library.name == lib.name:
            return f.result
        return None

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
        if self.snapped is None or len(f.shown.rows) >= len(self.snapped.rows):
            self._show_matches(f.shown)  # the service lists its starts only: keep the longer ColorSnap list
        self._show_recipe()
        self._show_recipes(ft.recipe_columns(f.result, getattr(f, "metamerism", None)))
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

    def _show_recipes(self, columns: list[ft.RecipeColumn]) -> None:
        """One column per recipe, a row per colorant (g per kg) and per criterion."""
        labels, cells = ft.recipe_table(columns)
        self.recipes.setColumnCount(len(columns))
        self.recipes.setRowCount(len(labels))
        self.recipes.setHorizontalHeaderLabels([c.label for c in columns])
        self.recipes.setVerticalHeaderLabels(labels)
        for i, row in enumerate(cells):
            for j, text in enumerate(row):
                self.recipes.setItem(i, j, QTableWidgetItem(text))

    def _on_loop(self, job) -> None:
        self.job = job
        self._show_loop()
        stored = f" Stored on the service as job {job.recipe_id}." if hasattr(job, "recipe_id") else ""
        self.status.setText(ft.loop_summary(job) + stored)

    def _show_loop(self, *_args) -> None:
        """Each step's group of rows: number, action and ΔE00 spanning its colorant lines."""
        self.loop.clearSpans()
        if self.job is None:
            self.loop.setRowCount(0)
            return
        groups = ft.loop_groups(self.job.steps, self.batch.value())
        self.loop.setRowCount(sum(len(g.lines) for g in groups))
        row = 0
        for g in groups:
            for j, text in enumerate((str(g.number), g.action, f"{g.mean_de:.2f}")):
                item = QTableWidgetItem(text)
                item.setToolTip(g.note)
                self.loop.setItem(row, j, item)
                if len(g.lines) > 1:
                    self.loop.setSpan(row, j, len(g.lines), 1)
            for k, (name, grams) in enumerate(g.lines):
                self.loop.setItem(row + k, 3, QTableWidgetItem(name))
                self.loop.setItem(row + k, 4, QTableWidgetItem(grams))
            row += len(g.lines)

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
