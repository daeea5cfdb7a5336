"""Main window of the CACAD Station viewer: the 3D view in the centre, the designer in a dock, and
tabs for the mood board, library, instruments and QA screens.

Start with ``station viewer`` (or ``python -m ui.app``). Edit → Undo/Redo (Ctrl+Z / Ctrl+Shift+Z) reverts
any design edit.
"""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QApplication, QDockWidget, QMainWindow, QTabWidget, QWidget

from ui.models.designer import DesignerModel
from ui.models.document import DesignDocument
from ui.models.view import ViewModel
from ui.widgets.designer_panel import DesignerPanel
from ui.widgets.view_panel import ViewPanel

if TYPE_CHECKING:
    from ui.models.measure_db import MeasurementSink
    from ui.models.service import ServiceClient


class MainWindow(QMainWindow):
    """Docks and tabs around one design document and one view model."""

    def __init__(
        self,
        document: DesignDocument | None = None,
        service_url: str | None = None,
        sink: MeasurementSink | None = None,
        service: ServiceClient | None = None,
        parent: QWidget | None = None,
    ) -> None:
        """*service* (a client) or *service_url* puts the viewer in service mode; *sink* is where scans
        are stored (default: the service's measurements, or the workstation's database)."""
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

        self.designer_panel = DesignerPanel(self.designer)
        self.designer_panel.setMinimumWidth(440)
        dock = QDockWidget("Designer", self)
        dock.setObjectName("designer-dock")
        dock.setWidget(self.designer_panel)
        dock.setFeatures(
            QDockWidget.DockWidgetFeature.DockWidgetMovable
            | QDockWidget.DockWidgetFeature.DockWidgetFloatable
        )
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, dock)
        self._make_menu()
        self.statusBar().showMessage(self._status_text())

    def _add_screens(self) -> None:
        """Tabs of the other screens (each module is optional while its core lands)."""
        from ui.widgets import screens

        for title, widget in screens.build_screens(self):
            self.tabs.addTab(widget, title)
            self.screens[title] = widget

    def _make_menu(self) -> None:
        edit = self.menuBar().addMenu("&Edit")
        self.undo_action = QAction("Undo", self, shortcut=QKeySequence.StandardKey.Undo)
        self.redo_action = QAction("Redo", self, shortcut=QKeySequence.StandardKey.Redo)
        self.undo_action.triggered.connect(self.document.undo)
        self.redo_action.triggered.connect(self.document.redo)
        edit.addAction(self.undo_action)
        edit.addAction(self.redo_action)
        self.document.events.history.connect(self._on_history)
        self._on_history()
        if self.service is not None:
            svc = self.menuBar().addMenu("&Service")
            svc.addAction("Load designs into palette", self.load_from_service)
            svc.addAction("Save current design", self.save_to_service)

    def load_from_service(self) -> int:
        """Add every service design to the palette; returns how many (errors go to the status bar)."""
        from ui.models.service import ServiceError

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

    def _on_design(self, design) -> None:
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
        self.document.events.changed.disconnect(self._on_design)
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
