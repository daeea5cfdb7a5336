"""The instruments screen calibrates step by step against the simulator subprocesses (real ptys, real
drivers), answered by QTest clicks: each prompt is followed by its own reading, a cancel at the white
tile leaves the instrument not calibrated by its own status, a failing white tile says so naming the step."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.ui.dialogs import answer_calibration
from ui.models.instruments import MeasurementStore
from ui.widgets.instruments_screen import InstrumentsScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]


@pytest.fixture
def screen(qtbot) -> Iterator[InstrumentsScreen]:
    s = InstrumentsScreen(MeasurementStore())
    qtbot.addWidget(s)
    s.show()
    yield s
    s.session.close()


def _connect(screen: InstrumentsScreen, device: str, faults: tuple[str, ...] = ()) -> None:
    screen.session.connect(device, faults=faults)
    screen._sync_buttons()
    assert screen.calibrate_btn.isEnabled()


def _settled(qtbot, screen: InstrumentsScreen) -> None:
    qtbot.waitUntil(lambda: screen.idle and screen.calibration is None, timeout=30000)


def test_each_prompt_then_its_step_and_cancel_at_the_white_tile(qtbot, screen):
    _connect(screen, "sim:ma6")
    inst = screen.session.instrument
    assert inst is not None
    assert answer_calibration(qtbot, screen, ["ok", "cancel"]) == ["Black trap", "White tile"]
    _settled(qtbot, screen)
    log = screen.log.toPlainText()
    assert "calibration step zero done" in log and "step white" not in log
    assert screen.state.text() == "calibration cancelled" and "sim:ma6 is not calibrated" in log
    assert inst.status().needed == "white"  # the zero ran, the white tile did not: the instrument says so
    assert screen.calibrate_btn.isEnabled()

    titles = answer_calibration(qtbot, screen, ["ok"] * 3)
    assert titles == ["Black trap", "White tile", "Verification tile"]
    _settled(qtbot, screen)
    assert screen.state.text() == "calibration passed", screen.log.toPlainText()
    status = inst.status()
    assert status.needed is None and status.calibration_id in screen.log.toPlainText()


def test_failing_white_tile_names_the_step(qtbot, screen):
    _connect(screen, "sim:ma3", ("cal-failure@WC",))
    assert answer_calibration(qtbot, screen, ["ok", "ok"]) == ["Black trap", "White tile"]
    _settled(qtbot, screen)
    assert screen.prompt is None  # no verification tile asked for after a failed white tile
    text = screen.state.text()
    assert "step 2 of 3 (white tile)" in text and "not calibrated" in text, text
    assert screen.state.isVisible()
    assert "ERROR" in screen.log.toPlainText()
    inst = screen.session.instrument
    assert inst is not None and inst.status().needed == "white"


def test_busy_from_a_prompt_closing_to_its_step_starting(qtbot, screen):
    """The white tile's prompt is answered the moment it opens, while the black trap's worker is still
    ending (its ``finished`` not yet delivered): the state line reads the white tile's reading at once,
    and the screen never reads idle until the calibration's outcome, however the two workers' ends
    interleave."""
    from PySide6.QtCore import QObject, Qt, Slot
    from PySide6.QtTest import QTest
    from PySide6.QtWidgets import QMessageBox

    ok = QMessageBox.StandardButton.Ok
    _connect(screen, "sim:ma6")
    QTest.mouseClick(screen.calibrate_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.prompt is not None and screen.prompt.isVisible(), timeout=10000)
    QTest.mouseClick(screen.prompt.button(ok), Qt.MouseButton.LeftButton)  # the black trap: its step runs
    zero = screen.task
    assert zero is not None and not screen.idle
    seen: dict[str, object] = {}
    idle_while_calibrating: list[str] = []

    class Answer(QObject):
        """Answers the white tile's prompt as soon as the screen has opened it (a slot after the screen's)."""

        @Slot(object)
        def on_zero_done(self, _result: object) -> None:
            box = screen.prompt
            assert box is not None and box.windowTitle() == "White tile"
            QTest.mouseClick(box.button(ok), Qt.MouseButton.LeftButton)
            seen["state"], seen["idle"] = screen.state.text(), screen.idle  # right after the prompt closed
            seen["task"] = screen.task

    answer = Answer()
    zero.succeeded.connect(answer.on_zero_done)

    def sample() -> bool:
        if screen.calibration is not None and screen.idle:
            idle_while_calibrating.append(screen.state.text())
        if (
            screen.prompt is not None
            and screen.prompt.isVisible()
            and screen.prompt.windowTitle() != "White tile"
        ):
            QTest.mouseClick(screen.prompt.button(ok), Qt.MouseButton.LeftButton)  # the verification tile
        return screen.calibration is None and screen.idle

    qtbot.waitUntil(sample, timeout=30000)
    assert seen["state"] == "calibration: reading the white tile of sim:ma6…", screen.log.toPlainText()
    assert seen["idle"] is False and seen["task"] is not zero
    assert idle_while_calibrating == []
    assert "busy: wait for the running task" not in screen.log.toPlainText()
    assert screen.state.text() == "calibration passed", screen.log.toPlainText()
    inst = screen.session.instrument
    assert inst is not None and inst.status().needed is None
