"""``station serve --drift SCALE --state DIR`` hands the simulators their drift scale and a run counter per
family: each start of the service is the simulators' next run (the counter the child itself advances in
DIR/FAMILY.json), and a scale outside the simulators' range is refused with one line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient

from station.drivers.families import SIM_DRIFT_SCALE_MAX


def _start(tmp_path: Path, state: Path, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """``station serve --simulators ma6 --drift 0.5 --state STATE`` started (its app's lifespan run, which
    spawns the simulator) and stopped; the simulator's command line."""
    import uvicorn

    from station.cli import main

    started: list[Any] = []

    def run(app: Any, **_kw: Any) -> None:
        started.append(app)

    monkeypatch.setattr(uvicorn, "run", run)
    argv = ["serve", "--data-dir", str(tmp_path), "--no-demo-library", "--simulators", "ma6"]
    assert main([*argv, "--drift", "0.5", "--state", str(state)]) == 0
    app = started[-1]
    with TestClient(app):
        while not isinstance(app, FastAPI):  # the service's middleware wraps the application
            app = app.app
        hub = app.state.instruments
        (sim,) = [a.simulator for a in hub._attached.values() if a.simulator is not None]
        return [str(a) for a in sim.proc.args]


def test_each_start_is_the_simulators_next_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    state = tmp_path / "runs"  # made by the service
    for run in (1, 2):
        args = _start(tmp_path, state, monkeypatch)
        assert args[args.index("--drift") + 1] == "0.5"
        assert Path(args[args.index("--state") + 1]) == (state / "ma6.json").resolve()
        assert json.loads((state / "ma6.json").read_text()) == {"runs": run}  # the child counted its run


def test_a_drift_outside_the_simulators_range_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from station.cli import main

    for bad in (str(SIM_DRIFT_SCALE_MAX * 2), "-1", "nan"):
        argv = ["serve", "--data-dir", str(tmp_path), "--simulators", "", "--drift", bad]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "simulator_drift" in err and len(err.strip().splitlines()) == 1, err
