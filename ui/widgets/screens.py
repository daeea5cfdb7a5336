"""The tabs beside the design view. Each screen is built (and its core modules imported) the first
time its tab is shown, so start-up reaches the first frame of the 3D view sooner. Every tab page scrolls
when the window is smaller than the screen's minimum size, so the viewer fits a 1280 × 800 display."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Generic, TypeVar

from PySide6.QtWidgets import QFrame, QScrollArea, QVBoxLayout, QWidget

from ui.models.instruments import MeasurementStore
from ui.models.moodboard import MoodBoardModel

if TYPE_CHECKING:
    from ui.widgets.formulation_screen import FormulationScreen
    from ui.widgets.library_screen import LibraryScreen
    from ui.widgets.qc_screen import QcScreen

#: The screen class a :class:`LazyScreen` builds.
Screen = TypeVar("Screen", bound=QWidget)


class LazyScreen(QScrollArea, Generic[Screen]):
    """A tab page that builds its content with *factory* when first shown (or on :meth:`content`).

    The content fills the page and scrolls when the page is smaller than the content's minimum size.
    """

    def __init__(self, factory: Callable[[], Screen], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._factory = factory
        self._content: Screen | None = None
        self.setWidgetResizable(True)
        self.setFrameShape(QFrame.Shape.NoFrame)
        holder = QWidget()
        self._box = QVBoxLayout(holder)
        self._box.setContentsMargins(0, 0, 0, 0)
        self.setWidget(holder)

    def content(self) -> Screen:
        """The real screen (built now if needed)."""
        if self._content is None:
            self._content = self._factory()
            self._box.addWidget(self._content)
        return self._content

    def showEvent(self, event) -> None:
        self.content()
        super().showEvent(event)

    def closeEvent(self, event) -> None:
        if self._content is not None:
            self._content.close()
        super().closeEvent(event)


def _library_screen(window) -> LibraryScreen:
    """The service's library in service mode (the demo library, said so, when the service cannot give one)."""
    from station.formulate.demo import demo_library
    from ui.models.library import LibraryModel
    from ui.widgets.library_screen import LibraryScreen

    library = None
    if window.service is not None:
        from ui.models.service import ServiceError

        try:
            library = window.service.library()
            window.statusBar().showMessage(f"library: {len(library)} paints from {window.service_url}")
        except ServiceError as exc:
            window.statusBar().showMessage(
                f"library from the service failed ({exc}); showing the demo library"
            )
    return LibraryScreen(LibraryModel(library if library is not None else demo_library()), window.document)


def _qc_screen(window) -> QcScreen:
    """The QC screen on the service, or on the database the window's scans go to; vendor files it imports
    are stored where the scans go (the window's sink)."""
    from ui.models.measure_db import LocalSink
    from ui.models.qc import LocalQc, QcModel, ServiceQc
    from ui.widgets.qc_screen import QcScreen

    sink = window.store.sink
    if window.service is not None:
        return QcScreen(QcModel(ServiceQc(window.service)), sink=sink)
    url = sink.url if isinstance(sink, LocalSink) else None
    return QcScreen(QcModel(LocalQc(url)), sink=sink)


def _booth_screen(window) -> QWidget:
    """The light booth on the service, or on the database the window's scans go to."""
    from ui.models.booth import BoothModel, LocalBoothSource, ServiceBoothSource
    from ui.models.measure_db import LocalSink
    from ui.widgets.booth_screen import BoothScreen

    if window.service is not None:
        return BoothScreen(BoothModel(ServiceBoothSource(window.service)))
    sink = window.store.sink
    url = sink.url if isinstance(sink, LocalSink) else None  # the database the scans go to
    return BoothScreen(BoothModel(LocalBoothSource(url)))


def build_screens(window) -> list[tuple[str, QWidget]]:
    """(title, widget) of every secondary screen; sets ``window.store`` and ``window.moodboard``."""
    window.store = getattr(window, "store", None) or MeasurementStore()
    window.moodboard = MoodBoardModel(window.document)
    library = LazyScreen(lambda: _library_screen(window))
    window.library_screen = library

    def formulation_screen() -> FormulationScreen:
        from station.formulate.demo import demo_library
        from ui.widgets.formulation_screen import FormulationScreen

        if window.service is not None:  # every step on the service, against its library
            return FormulationScreen(None, window.document, service=window.service)
        return FormulationScreen(demo_library(), window.document)

    formulation = LazyScreen(formulation_screen)
    window.formulation_screen = formulation

    def send_to_formulation(paint) -> None:
        """QA's corrected paint goes to the chemist's screen, picked and ready for ColorSnap."""
        window.tabs.setCurrentWidget(formulation)
        formulation.content().receive(paint)

    def moodboard() -> QWidget:
        from ui.widgets.moodboard_screen import MoodBoardScreen

        return MoodBoardScreen(window.moodboard)

    def instruments() -> QWidget:
        from ui.widgets.instruments_screen import InstrumentsScreen

        return InstrumentsScreen(window.store, window.document, open_job=open_job)

    def qa() -> QWidget:
        from ui.widgets.qa_screen import QAScreen

        return QAScreen(window.designer, window.store, send_to_formulation)

    qc_page: LazyScreen[QcScreen] = LazyScreen(lambda: _qc_screen(window))
    window.qc_screen = qc_page

    def open_job(job: str, part: str, measurement_id: int) -> None:
        """A job-history row opened in the Instruments tab: its job's verdicts in the QC tab."""
        window.tabs.setCurrentWidget(qc_page)
        qc_page.content().open_job(job, part, measurement_id)

    def tweaker() -> QWidget:
        from ui.widgets.tweaker_screen import TweakerScreen

        return TweakerScreen(window.document, window.view_model)

    return [
        ("Tweaker", LazyScreen(tweaker)),
        ("Mood board", LazyScreen(moodboard)),
        ("Library", library),
        ("Instruments", LazyScreen(instruments)),
        ("QA", LazyScreen(qa)),
        ("QC", qc_page),
        ("Booth", LazyScreen(lambda: _booth_screen(window))),
        ("Formulation", formulation),
    ]
