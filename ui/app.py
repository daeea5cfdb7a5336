"""Main window of the CACAD Station viewer: the 3D view in the centre, the designer in a dock, and
tabs for the mood board, library, instruments and QA screens.

Start with ``station viewer`` (or ``python -m ui.app``). Edit → Undo/Redo (Ctrl+Z / Ctrl+Shift+Z) reverts
any design edit. File → New / Open / Save / Save As work on the design (Ctrl+N/O/S, Ctrl+Shift+S), the
palette and the mood board (:class:`ui.models.files.StylistFiles`); File → Export writes the design as
thesis XML or CxF3; File → Load environment reads an own HDR; File → Open model shows an own glTF/GLB,
OBJ or STL model in the 3D view. Closing with unsaved changes asks first; a file that cannot be read is
reported in a message box and changes nothing.
"""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QFileDialog,
    QFrame,
    QMainWindow,
    QMessageBox,
    QScrollArea,
    QTabWidget,
    QWidget,
)

from ui.models.designer import DesignerModel
from ui.models.document import DesignDocument
from ui.models.files import EXPORTS, KINDS, TITLES, FileInputError, Kind, StylistFiles
from ui.models.view import ViewModel
from ui.widgets.designer_panel import DesignerPanel
from ui.widgets.view_panel import ViewPanel

if TYPE_CHECKING:
    from ui.models.measure_db import MeasurementSink
    from ui.models.moodboard import MoodBoardModel
    from ui.models.service import ServiceClient
    from ui.widgets.formulation_screen import FormulationScreen
    from ui.widgets.library_screen import LibraryScreen
    from ui.widgets.qc_screen import QcScreen
    from ui.widgets.screens import LazyScreen

#: Width of the designer panel in its dock, pixels (the window's minimum fits 1280 × 800 with it).
DESIGNER_WIDTH = 370


class MainWindow(QMainWindow):
    """Docks and tabs around one design document and one view model."""

    # set by ui.widgets.screens.build_screens while the tabs are added
    moodboard: MoodBoardModel
    library_screen: LazyScreen[LibraryScreen]
    formulation_screen: LazyScreen[FormulationScreen]
    qc_screen: LazyScreen[QcScreen]

    def __init__(
        self,
        document: DesignDocument | None = None,
        service_url: str | None = None,
        sink: MeasurementSink | None = None,
        service: ServiceClient | None = None,
        parent: QWidget | None = None,
        ask_on_close: bool = True,
    ) -> None:
        """*service* (a client) or *service_url* puts the viewer in service mode; *sink* is where scans
        are stored (default: the service's measurements, or the workstation's database); with
        *ask_on_close* (the default) closing with unsaved changes asks whether to save them."""
        super().__init__(parent)
        from ui.models.instruments import MeasurementStore
        from ui.models.measure_db import LocalSink, ServiceSink

        self.setWindowTitle("CACAD Station")
        self.document = document or DesignDocument()
        self.designer = DesignerModel(self.document)
        self.view_model = ViewModel()
        self.service = service
        if service is None and service_url:
            from ui.models.service import ServiceClient

            self.service = ServiceClient(service_url)
        self.service_url = self.service.url if self.service is not None else None
        # every scan is queued on disk, then stored in the database (or on the service): nothing is lost
        if sink is None:
            sink = ServiceSink(self.service) if self.service is not None else LocalSink()
        self.store = MeasurementStore(sink)
        self.view_model.show(self.document.design)
        self.document.events.changed.connect(self._on_design)

        self.tabs = QTabWidget()
        self.view_panel = ViewPanel(self.view_model)
        self.tabs.addTab(self.view_panel, "Design")
        self.setCentralWidget(self.tabs)
        self.screens: dict[str, QWidget] = {"Design": self.view_panel}
        self._add_screens()

        self.designer_panel = DesignerPanel(self.designer, self.view_model, self._view_basis)
        self.designer_panel.setMinimumWidth(DESIGNER_WIDTH)
        # the designer scrolls inside its dock, and the dock can be closed (View menu) or floated
        designer_scroll = QScrollArea()
        designer_scroll.setObjectName("designer-scroll")
        designer_scroll.setWidgetResizable(True)
        designer_scroll.setFrameShape(QFrame.Shape.NoFrame)
        designer_scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        designer_scroll.setWidget(self.designer_panel)
        vbar = designer_scroll.verticalScrollBar().sizeHint().width()
        designer_scroll.setMinimumWidth(DESIGNER_WIDTH + vbar)
        dock = QDockWidget("Designer", self)
        dock.setObjectName("designer-dock")
        dock.setWidget(designer_scroll)
        dock.setFeatures(
            QDockWidget.DockWidgetFeature.DockWidgetMovable
            | QDockWidget.DockWidgetFeature.DockWidgetFloatable
            | QDockWidget.DockWidgetFeature.DockWidgetClosable
        )
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, dock)
        self.designer_dock = dock
        self.files = StylistFiles(self.document, self.designer, self.moodboard)
        self.ask_on_close = ask_on_close
        self.error_box: QMessageBox | None = None
        self.file_dialog: QFileDialog | None = None  # the open file dialog (tests drive it)
        self.unsaved_box: QMessageBox | None = None  # the open "unsaved changes" question
        self._make_file_menu()
        self._make_menu()
        self.designer.events.palette.connect(self._update_title)
        self.moodboard.events.board.connect(self._update_title)
        self._update_title()
        self.statusBar().showMessage(self._status_text())

    def _view_basis(self):
        """The main view's cached basis images (the core's) when they are final for the view, else None:
        the variations grid renders its swatches from them."""
        v = self.view_panel.view
        return v.basis.core if v.basis is not None and v.basis_current else None

    def _add_screens(self) -> None:
        """Tabs of the other screens (each module is optional while its core lands)."""
        from ui.widgets import screens

        for title, widget in screens.build_screens(self):
            self.tabs.addTab(widget, title)
            self.screens[title] = widget

    # ------------------------------------------------------------------ File menu
    def _make_file_menu(self) -> None:
        menu = self.menuBar().addMenu("&File")
        self.file_menu = menu
        self.file_actions: dict[str, QAction] = {}
        keys = {
            "design": (
                QKeySequence.StandardKey.New,
                QKeySequence.StandardKey.Open,
                QKeySequence.StandardKey.Save,
                QKeySequence.StandardKey.SaveAs,
            ),
        }
        for kind in KINDS:
            title = TITLES[kind]
            shortcuts = keys.get(kind)
            for i, (verb, slot) in enumerate(
                (
                    ("New", lambda _=False, k=kind: self.file_new(k)),
                    ("Open", lambda _=False, k=kind: self.file_open(k)),
                    ("Save", lambda _=False, k=kind: self.file_save(k)),
                    ("Save As", lambda _=False, k=kind: self.file_save_as(k)),
                )
            ):
                text = f"{verb} {title}" + ("…" if verb in ("Open", "Save As") else "")
                act = QAction(text, self)
                if shortcuts is not None:
                    act.setShortcut(QKeySequence(shortcuts[i]))
                act.triggered.connect(slot)
                menu.addAction(act)
                self.file_actions[f"{verb} {title}"] = act
            menu.addSeparator()
        for fmt, label in (("xml", "Export design as XML…"), ("cxf", "Export design as CxF…")):
            act = QAction(label, self)
            act.triggered.connect(lambda _=False, f=fmt: self.file_export(f))
            menu.addAction(act)
            self.file_actions[label.rstrip("…")] = act
        menu.addSeparator()
        env = QAction("Load environment (HDR)…", self)
        if callable(getattr(self.view_model, "load_environment", None)):
            env.triggered.connect(self.load_environment)
        else:
            env.setEnabled(False)
            env.setToolTip("Loading an own HDR needs the 3D view's environment loader (not in this build)")
        menu.addAction(env)
        self.file_actions["Load environment (HDR)"] = env
        model = QAction("Open model…", self)
        model.setToolTip("Your own car or part (glTF/GLB, OBJ, STL) in the 3D view, beside the shapes")
        model.triggered.connect(self.open_model)
        menu.addAction(model)
        self.file_actions["Open model"] = model
        imp = QAction("Import measurement files…", self)
        imp.setToolTip("CxF3, CGATS, MA-T12 workbook or CSV files into the measurement store (QC tab)")
        imp.triggered.connect(self.import_measurements)
        imp.setEnabled(self.store.sink is not None)
        menu.addAction(imp)
        self.file_actions["Import measurement files"] = imp
        self.setAcceptDrops(self.store.sink is not None)
        menu.addSeparator()
        quit_act = QAction("Quit", self, shortcut=QKeySequence(QKeySequence.StandardKey.Quit))
        quit_act.triggered.connect(self.close)
        menu.addAction(quit_act)

    def _ask_path(self, title: str, name_filter: str, save: bool, suffix: str) -> str | None:
        """A file dialog (Qt's own, the same on every desktop); None when cancelled."""
        dlg = QFileDialog(self, title, "", name_filter)
        dlg.setOption(QFileDialog.Option.DontUseNativeDialog, True)
        dlg.setObjectName("file-dialog")
        if save:
            dlg.setAcceptMode(QFileDialog.AcceptMode.AcceptSave)
            dlg.setFileMode(QFileDialog.FileMode.AnyFile)
            dlg.setDefaultSuffix(suffix.lstrip("."))
        else:
            dlg.setFileMode(QFileDialog.FileMode.ExistingFile)
        self.file_dialog = dlg
        try:
            if dlg.exec() != QFileDialog.DialogCode.Accepted or not dlg.selectedFiles():
                return None
            return dlg.selectedFiles()[0]
        finally:
            self.file_dialog = None
            dlg.deleteLater()

    def show_error(self, title: str, message: str) -> None:
        """A visible, non-blocking message box (and the status bar) for a refused file."""
        self.statusBar().showMessage(f"{title}: {message}")
        if self.error_box is not None:
            self.error_box.close()
        box = QMessageBox(QMessageBox.Icon.Warning, title, message, QMessageBox.StandardButton.Ok, self)
        box.setObjectName("error-box")
        box.open()
        self.error_box = box

    def _filter(self, kind: Kind) -> str:
        return f"{TITLES[kind].capitalize()} files (*.json);;All files (*)"

    def file_new(self, kind: Kind) -> None:
        """File → New design / palette / mood board (unsaved changes of that kind are asked about)."""
        if kind in self.files.unsaved() and not self._confirm_discard([kind]):
            return
        self.files.new(kind)
        self.statusBar().showMessage(f"new {TITLES[kind]}")
        self._update_title()

    def file_open(self, kind: Kind) -> bool:
        """File → Open…: choose a file and open it; a bad file shows an error and changes nothing."""
        if kind in self.files.unsaved() and not self._confirm_discard([kind]):
            return False
        path = self._ask_path(f"Open {TITLES[kind]}", self._filter(kind), save=False, suffix=".json")
        if path is None:
            return False
        try:
            self.files.open(kind, path)
        except FileInputError as exc:
            self.show_error(f"Cannot open {TITLES[kind]}", str(exc))
            return False
        self.statusBar().showMessage(f"opened {TITLES[kind]} {path}")
        self._update_title()
        return True

    def file_save(self, kind: Kind) -> bool:
        """File → Save (Save As when it has no file yet)."""
        if self.files.paths[kind] is None:
            return self.file_save_as(kind)
        return self._write(kind, None)

    def file_save_as(self, kind: Kind) -> bool:
        """File → Save As…"""
        path = self._ask_path(f"Save {TITLES[kind]} as", self._filter(kind), save=True, suffix=".json")
        return path is not None and self._write(kind, path)

    def _write(self, kind: Kind, path: str | None) -> bool:
        try:
            written = self.files.save(kind, path)
        except FileInputError as exc:
            self.show_error(f"Cannot save {TITLES[kind]}", str(exc))
            return False
        self.statusBar().showMessage(f"saved {TITLES[kind]} {written}")
        self._update_title()
        return True

    def file_export(self, fmt: str) -> bool:
        """File → Export design as XML / CxF…"""
        suffix = EXPORTS[fmt]
        label = "XML" if fmt == "xml" else "CxF3"
        path = self._ask_path(
            f"Export design as {label}", f"{label} files (*{suffix});;All files (*)", save=True, suffix=suffix
        )
        if path is None:
            return False
        try:
            written = self.files.export(fmt, path)
        except FileInputError as exc:
            self.show_error("Cannot export", str(exc))
            return False
        self.statusBar().showMessage(f"exported {label} {written}")
        return True

    def import_measurements(self) -> None:
        """File ▸ Import measurement files…: the QC tab, then its file dialog (the import runs there)."""
        self.tabs.setCurrentWidget(self.qc_screen)
        self.qc_screen.content().ask_import()

    def dragEnterEvent(self, event) -> None:
        """Vendor measurement files dragged over the window go to the QC tab's import."""
        self.qc_screen.content().dragEnterEvent(event)

    def dropEvent(self, event) -> None:
        """Vendor measurement files dropped on the window are imported in the QC tab, which is shown."""
        self.tabs.setCurrentWidget(self.qc_screen)
        self.qc_screen.content().dropEvent(event)

    def load_environment(self) -> bool:
        """File → Load environment (HDR)…: an own HDR lights the 3D view."""
        from station.errors import StationError

        path = self._ask_path("Load environment", "HDR images (*.hdr *.exr);;All files (*)", False, ".hdr")
        if path is None:
            return False
        try:
            self.view_model.load_environment(path)
        except (StationError, OSError, ValueError) as exc:
            self.show_error("Cannot load environment", str(exc))
            return False
        self.statusBar().showMessage(f"environment {path}")
        return True

    def open_model(self) -> bool:
        """File → Open model…: a glTF/GLB, OBJ or STL model joins the 3D view's shape picker and is shown;
        a file that cannot be used is named in a visible message."""
        from station.render.meshes import MESH_SUFFIXES

        patterns = " ".join(f"*{x}" for x in MESH_SUFFIXES)
        path = self._ask_path("Open model", f"Models ({patterns});;All files (*)", False, ".glb")
        if path is None:
            return False
        if not self.view_panel.open_model(path):
            self.show_error("Cannot open model", self.view_panel.env_status.text())
            return False
        self.statusBar().showMessage(f"model {path}")
        return True

    def _confirm_discard(self, kinds: list[Kind]) -> bool:
        """Ask about unsaved *kinds*: Save (each), Discard or Cancel; True when it is fine to go on."""
        names = ", ".join(TITLES[k] for k in kinds)
        box = QMessageBox(
            QMessageBox.Icon.Question,
            "Unsaved changes",
            f"The {names} {'has' if len(kinds) == 1 else 'have'} unsaved changes.",
            QMessageBox.StandardButton.Save
            | QMessageBox.StandardButton.Discard
            | QMessageBox.StandardButton.Cancel,
            self,
        )
        box.setObjectName("unsaved-box")
        box.setDefaultButton(QMessageBox.StandardButton.Save)
        self.unsaved_box = box
        try:
            answer = box.exec()
        finally:
            self.unsaved_box = None
            box.deleteLater()
        if answer == QMessageBox.StandardButton.Discard:
            return True
        if answer == QMessageBox.StandardButton.Save:
            return all(self.file_save(k) for k in kinds)
        return False

    def _make_menu(self) -> None:
        edit = self.menuBar().addMenu("&Edit")
        self.undo_action = QAction("Undo", self, shortcut=QKeySequence(QKeySequence.StandardKey.Undo))
        self.redo_action = QAction("Redo", self, shortcut=QKeySequence(QKeySequence.StandardKey.Redo))
        self.undo_action.triggered.connect(self.document.undo)
        self.redo_action.triggered.connect(self.document.redo)
        edit.addAction(self.undo_action)
        edit.addAction(self.redo_action)
        self.document.events.history.connect(self._on_history)
        self._on_history()
        view_menu = self.menuBar().addMenu("&View")
        self.designer_action = self.designer_dock.toggleViewAction()
        self.designer_action.setText("Designer panel")
        view_menu.addAction(self.designer_action)
        if self.service is not None:
            svc = self.menuBar().addMenu("&Service")
            svc.addAction("Load designs into palette", self.load_from_service)
            svc.addAction("Save current design", self.save_to_service)

    def load_from_service(self) -> int:
        """Add every service design to the palette; returns how many (errors go to the status bar)."""
        from ui.models.service import ServiceError

        if self.service is None:
            self.statusBar().showMessage("no service: the viewer runs on this workstation's database")
            return 0
        try:
            rows = self.service.list_designs()
        except ServiceError as exc:
            self.statusBar().showMessage(str(exc))
            return 0
        for _id, name, design in rows:
            self.designer.palette.append((name, design))
        self.designer.events.palette.emit()
        self.statusBar().showMessage(f"{len(rows)} designs loaded from {self.service_url}")
        return len(rows)

    def save_to_service(self) -> int | None:
        """Save the current design to the service as a new design."""
        from ui.models.service import ServiceError

        if self.service is None:
            self.statusBar().showMessage("no service: the viewer runs on this workstation's database")
            return None
        try:
            new_id = self.service.save_design(self.document.name, self.document.design)
        except ServiceError as exc:
            self.statusBar().showMessage(str(exc))
            return None
        self.statusBar().showMessage(f"saved as design {new_id} on {self.service_url}")
        return new_id

    def _on_history(self) -> None:
        self.undo_action.setEnabled(self.document.can_undo)
        self.redo_action.setEnabled(self.document.can_redo)
        self.undo_action.setText(f"Undo {self.document.undo_label or ''}".strip())

    def _update_title(self) -> None:
        """``name · CACAD Station``, with ``*`` while something is unsaved (Qt's modified marker)."""
        name = self.document.name
        self.setWindowTitle(f"{name}[*] · CACAD Station")
        self.setWindowModified(bool(self.files.unsaved()))

    def _on_design(self, design) -> None:
        self._update_title()
        self.view_model.show(design)
        self.statusBar().showMessage(self._status_text())

    def _status_text(self) -> str:
        d = self.document.design
        travel = "solid" if d.travel_deg is None else f"travel {d.travel_deg:.0f}°"
        face = ", ".join(f"{v:.1f}" for v in d.face)
        flop = ", ".join(f"{v:.1f}" for v in d.flop)
        src = f" · service {self.service_url}" if self.service_url else " · local core"
        return f"face ({face}) flop ({flop}) {travel} gloss {d.gloss_gu:.0f} GU{src}"

    def closeEvent(self, event) -> None:
        unsaved = self.files.unsaved()
        if self.ask_on_close and unsaved and not self._confirm_discard(unsaved):
            event.ignore()
            return
        if self.error_box is not None:
            self.error_box.close()
        self.document.events.changed.disconnect(self._on_design)
        self.designer.events.palette.disconnect(self._update_title)
        self.moodboard.events.board.disconnect(self._update_title)
        self.document.events.history.disconnect(self._on_history)
        self.designer_panel.close()
        for w in self.screens.values():
            w.close()
        if self.store.sink is not None:
            self.store.sink.close()
        if self.service is not None:
            self.service.close()
        super().closeEvent(event)


def main(argv: list[str] | None = None, service_url: str | None = None, token: str | None = None) -> int:
    """Run the viewer; prints the start-up-to-first-frame time on stderr."""
    from ui.widgets.render_view import configure_default_format

    t0 = time.perf_counter()
    configure_default_format()
    app = QApplication.instance() or QApplication(argv if argv is not None else sys.argv)
    service = None
    if service_url:
        from ui.models.service import ServiceClient

        service = ServiceClient(service_url, token)
    win = MainWindow(service=service)
    win.resize(1500, 950)
    view = win.view_panel.view
    view.frame_rendered.connect(
        lambda: (
            print(f"first frame after {time.perf_counter() - t0:.2f} s ({view.gl_renderer})", file=sys.stderr)
            if view.frames == 1
            else None
        )
    )
    win.show()
    return app.exec()


if __name__ == "__main__":
    raise SystemExit(main())
