"""Viewer test configuration: one Qt platform for the whole session, warnings fail, nothing leaks.

Qt reads ``QT_QPA_PLATFORM`` once, when the QApplication is created, so the platform is chosen here at
import time, before pytest-qt's ``qapp`` exists: an Xvfb server is started on a free display
(``-displayfd``) and every viewer test runs on ``xcb`` with Mesa's llvmpipe serving GL. If Xvfb is
missing or fails, the session stays on ``offscreen`` and the GL tests skip with the reason (under
``CI=true`` they fail: ``tests.services.service_missing``).

* Qt messages of level WARNING or above fail the test (``qt_log_level_fail`` marker on every item).
* Autouse fixture: after each test no top-level widget is left open and no QThread is still running.
* Autouse fixture: after each test its closed widgets' deferred deletes run, as the event loop would run them.
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator

import pytest

from tests.processes import KILL_WAIT_S, Stream
from tests.services import service_missing
from tests.waiting import WaitTimeout

XVFB_ERROR = ""
#: Seconds Xvfb gets to report its display number.
XVFB_START_S = 60.0


def _start_xvfb() -> subprocess.Popen | None:
    global XVFB_ERROR
    if shutil.which("Xvfb") is None:
        XVFB_ERROR = "Xvfb is not installed (scripts/setup.sh installs it)"
        return None
    r, w = os.pipe()
    try:
        proc = subprocess.Popen(
            [
                "Xvfb",
                "-displayfd",
                str(w),
                "-screen",
                "0",
                "1600x1200x24",
                "-nolisten",
                "tcp",
                "+extension",
                "GLX",
            ],
            pass_fds=(w,),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError as exc:
        XVFB_ERROR = f"Xvfb failed to start: {exc}"
        return None
    finally:
        os.close(w)
    with Stream(r, "Xvfb's display number") as reported:  # a line, or nothing once Xvfb has failed
        try:
            display = reported.wait_for("\n", XVFB_START_S).strip()
        except WaitTimeout:
            display = ""
    if not display:
        proc.kill()
        proc.wait(KILL_WAIT_S)
        XVFB_ERROR = f"Xvfb did not report a display number within {XVFB_START_S:g} s"
        return None
    os.environ["DISPLAY"] = f":{display}"
    atexit.register(_stop_xvfb, proc)
    return proc


def _stop_xvfb(proc: subprocess.Popen) -> None:
    """End the test run's Xvfb: asked first, killed when it does not go."""
    proc.terminate()
    try:
        proc.wait(KILL_WAIT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(KILL_WAIT_S)


XVFB = _start_xvfb()
os.environ["QT_QPA_PLATFORM"] = "xcb" if XVFB is not None else "offscreen"

from ui.widgets.render_view import configure_default_format  # noqa: E402  (after the platform is set)

configure_default_format()
GL = XVFB is not None


def pytest_collection_modifyitems(config, items) -> None:
    """Every viewer test fails on Qt warnings."""
    here = os.path.dirname(__file__)
    for item in items:
        if str(item.fspath).startswith(here):
            item.add_marker(pytest.mark.qt_log_level_fail("WARNING"))
            # the offscreen platform plugin's own limitation (QMainWindow docks), not a viewer fault
            item.add_marker(pytest.mark.qt_log_ignore("This plugin does not support propagateSizeHints"))


@pytest.fixture(autouse=True)
def _deferred_deletes_run() -> Iterator[None]:
    """After each test (its widgets closed and ``deleteLater``-ed by pytest-qt, whose teardown runs first)
    the deferred deletes run, as the application's event loop runs them: no test's widget outlives the
    test. A GL view left pending at interpreter exit was destroyed by the QApplication's destructor after
    PySide had deleted its GL surface (a Python-owned object), and the process crashed (SIGSEGV) before
    the exit handler above stopped Xvfb."""
    yield
    from PySide6.QtCore import QCoreApplication, QEvent

    if QCoreApplication.instance() is not None:
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)


@pytest.fixture(autouse=True)
def _gl_platform(request: pytest.FixtureRequest) -> None:
    """A test marked ``gl`` skips when there is no Xvfb (fails under ``CI=true``)."""
    if request.node.get_closest_marker("gl") is not None and not GL:
        service_missing(f"no GL-capable Qt platform: {XVFB_ERROR}")


@pytest.fixture(scope="package", autouse=True)
def _prefilter_cache_dir():
    """Prefiltered environments of the viewer tests go to a temporary cache shared by this package only."""
    old = os.environ.get("CACAD_CACHE_DIR")
    os.environ["CACAD_CACHE_DIR"] = os.path.join(tempfile.gettempdir(), "cacad-ui-test-cache")
    yield
    if old is None:
        os.environ.pop("CACAD_CACHE_DIR", None)
    else:
        os.environ["CACAD_CACHE_DIR"] = old


@pytest.fixture(autouse=True)
def _no_standalone_gl(request: pytest.FixtureRequest) -> Iterator[None]:
    """No viewer test makes a standalone (EGL) GL context: after one, Mesa crashes Qt's GLX contexts of
    later views in the same process (scripts/test.sh); draw the core on a view's own context instead."""
    had = "glcontext.egl" in sys.modules
    yield
    if not had and "glcontext.egl" in sys.modules:
        pytest.fail(f"{request.node.nodeid} made a standalone EGL context in the viewer's process")


@pytest.fixture(autouse=True)
def _data_dir(tmp_path, monkeypatch):
    """``$CACAD_DATA_DIR`` in the test's temporary folder: a default sink never writes to ./var."""
    monkeypatch.setenv("CACAD_DATA_DIR", str(tmp_path / "data"))


@pytest.fixture(autouse=True)
def _no_leftovers(request):
    """No top-level widget left visible and no QThread running after a test."""
    from PySide6.QtCore import QThread

    started: list[QThread] = []
    original = QThread.start

    def start(self, *args):
        started.append(self)
        return original(self, *args)

    QThread.start = start  # type: ignore[method-assign]
    try:
        yield
    finally:
        QThread.start = original  # type: ignore[method-assign]
    if "qapp" not in request.fixturenames and "qtbot" not in request.fixturenames:
        return
    from PySide6.QtWidgets import QApplication

    QApplication.processEvents()
    running = [t for t in started if t.isRunning()]
    visible = [w for w in QApplication.topLevelWidgets() if w.isVisible()]
    for w in visible:
        w.close()
    assert not running, f"QThreads still running: {running}"
    assert not visible, f"top-level widgets left open: {[type(w).__name__ for w in visible]}"


@pytest.fixture
def document():
    """A fresh design document with the default design."""
    from ui.models.document import DesignDocument

    return DesignDocument()


def close_widget(qtbot, widget) -> None:
    """Close a widget the way the user would and let its threads finish."""
    widget.close()
    qtbot.wait(1)
