"""Step-by-step calibration through ``station.scan.CalibrationSession`` against the simulator subprocesses
(real ptys, real drivers): each step is its own instrument command, a cancel between steps and a failed
step leave the instrument needing calibration by its own status, a failed step names itself. The CLI's
prompts (``station calibrate`` / ``station measure --calibrate``) are driven through stdin."""

from __future__ import annotations

import io
import json
from collections.abc import Iterator

import pytest

from station import scan
from station.cli import main
from station.drivers import HardwareFailure

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def pair() -> Iterator[tuple[scan.Device, scan.Device]]:
    with scan.open_device("sim:ma6") as spectro, scan.open_gloss_meter("sim:gloss") as meter:
        yield spectro, meter


def test_steps_in_order_with_prompts_and_each_its_own_command(pair):
    spectro, meter = pair
    session = scan.CalibrationSession(spectro, meter)
    assert [(s.device, s.step) for s in session.steps] == [
        ("sim:ma6", "zero"),
        ("sim:ma6", "white"),
        ("sim:ma6", "verify"),
        ("sim:gloss", "gloss"),
    ]
    assert "black trap" in session.steps[0].prompt and "Step 1 of 4" in session.steps[0].prompt
    assert "white calibration tile" in session.steps[1].prompt
    assert "black glass" in session.steps[3].prompt
    session.run_next()  # the zero alone: the instrument itself now asks for the white tile
    assert spectro.instrument.status().needed == "white"
    assert session.state == "not calibrated"
    white = session.run_next()
    assert white.calibration_id == spectro.instrument.status().calibration_id
    assert spectro.instrument.status().needed == "verify"  # a verification is owed before measuring
    session.run_next()
    session.run_next()
    assert session.next is None and session.state == "calibrated"
    (n1, r1), (n2, r2) = session.results()
    assert (n1, r1.steps, r1.calibration_id) == ("sim:ma6", ("zero", "white", "verify"), white.calibration_id)
    assert r1.verification_de is not None and r1.passed
    assert (n2, r2.steps, r2.calibration_id) == (
        "sim:gloss",
        ("gloss",),
        meter.instrument.status().calibration_id,
    )
    assert meter.instrument.status().needed is None


def test_cancel_at_the_white_tile_leaves_it_not_calibrated(pair):
    spectro, _ = pair
    session = scan.CalibrationSession(spectro)
    session.run_next()
    assert session.next is not None and session.next.step == "white"
    session.cancel()
    assert (
        session.next is None
        and session.state == "not calibrated"
        and session.results()[0][1].steps == ("zero",)
    )
    assert spectro.instrument.status().needed == "white"
    with pytest.raises(scan.ScanError, match="no step left"):
        session.run_next()
    with pytest.raises(Exception, match="calibration needed: white"):
        spectro.instrument.measure()
    scan.calibrate(spectro)  # the whole sequence at once, as the service runs it
    assert spectro.instrument.status().needed is None


def test_failed_white_tile_names_the_step_and_stops():
    with scan.open_device("sim:ma3", faults=["cal-failure@WC"]) as spectro:
        session = scan.CalibrationSession(spectro)
        session.run_next()
        with pytest.raises(scan.CalibrationStepError) as info:
            session.run_next()
        err = info.value
        assert err.step.step == "white" and isinstance(err.__cause__, HardwareFailure)
        assert "step 2 of 3 (white tile)" in str(err) and "not calibrated" in str(err)
        assert session.next is None and session.state == "not calibrated"
        assert spectro.instrument.status().needed == "white"


def _cli(capsys, monkeypatch, stdin: str, *argv: str) -> tuple[int, str, str]:
    monkeypatch.setattr("sys.stdin", io.StringIO(stdin))
    rc = main(list(argv))
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_cli_prompts_before_each_step(capsys, monkeypatch):
    rc, out, err = _cli(capsys, monkeypatch, "\n\n\n", "calibrate", "sim:ma6", "--json")
    assert rc == 0, err
    data = json.loads(out)
    assert data["state"] == "calibrated" and data["steps"] == ["zero", "white", "verify"]
    for head in ("Step 1 of 3 — black trap", "Step 2 of 3 — white tile", "Step 3 of 3 — verification tile"):
        assert head in err
    rc, out, err = _cli(capsys, monkeypatch, "\nq\n", "calibrate", "sim:ma6")
    assert rc == 1 and out == ""
    assert err.strip().splitlines()[-1] == (
        "error: calibration of sim:ma6 cancelled before step 2 of 3 (white tile): not calibrated"
    )


def test_cli_measure_calibrates_first(capsys, monkeypatch):
    rc, out, err = _cli(capsys, monkeypatch, "\n", "measure", "sim:gloss", "--calibrate", "--json")
    assert rc == 0, err
    assert "Step 1 of 1 — gloss standard" in err
    data = json.loads(out)
    assert [c["device"] for c in data["calibration"]] == ["sim:gloss"] and data["gloss_gu"]
