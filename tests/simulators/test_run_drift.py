"""Drift across runs: a simulator started again reads the same panel a stated amount brighter per run, the
run counter kept in its state file across processes; N runs measured show the configured slope, and
``station qc spc`` over them flags the drift before a sample fails.

Expectations are independent of the simulator's code: the reflectance ratio of two runs with the same noise
seed is the stated gain, and the slope of L* against the run index is the closed form
dL*/dk = (L*₀ + 16)/3 · g (L* = 116 (Y/Yn)^⅓ − 16 with Y scaled by 1 + g·k).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from simulators.config import SimulatorConfig, SimulatorConfigError, spectro_physics
from simulators.repeatability import (
    MAX_RUN_DRIFT,
    STATED_DRIFT_PER_RUN,
    RunStateError,
    next_run_index,
    stated_drift,
)
from station.drivers import open_instrument
from station.drivers.simproc import spawn_simulator
from station.model.domain import ANGLES_6
from station.model.spectra import reflectance_to_lab
from tests.qc._stored import store_job
from tests.qc.test_cli import inproc, set_standard

ANGLES = (15.0, 45.0, 110.0)


def test_a_restarted_simulator_reads_one_stated_step_brighter(tmp_path: Path) -> None:
    """Two processes with one state file and one noise seed: the second run's spectra are the first's
    times 1 + g(θ), and the file counts two runs."""
    state = tmp_path / "ma6.state.json"
    spectra = []
    for _ in range(2):
        sim = spawn_simulator(
            "ma6", extra_args=["--state", str(state), "--seed", "5", "--measure-time", "0.01"]
        )
        try:
            with open_instrument(sim.address, timeout_s=2.0) as inst:
                r = inst.measure()
        finally:
            sim.close()
        spectra.append((r.aspecular_deg, np.asarray(r.reflectance)))
    (angles0, r0), (angles1, r1) = spectra
    assert tuple(angles0) == tuple(angles1)
    ratio = np.median(r1 / r0, axis=1)
    expected = [1.0 + stated_drift(a) for a in angles0]
    assert ratio == pytest.approx(expected, abs=2e-4)  # the wire format's precision
    assert json.loads(state.read_text()) == {"runs": 2}


def _run_labs(state: Path, runs: int, readings: int, drift: float = 1.0) -> list[np.ndarray]:
    """*runs* runs, each a fresh simulator on the state file (its own noise seed), *readings* readings each."""
    out = []
    for k in range(runs):
        physics = spectro_physics(SimulatorConfig("ma6", state=state, seed=100 + k, drift=drift), "600123")
        assert physics.run_index == k
        out.append(reflectance_to_lab(np.array([physics.measure(ANGLES) for _ in range(readings)])))
    return out


def test_n_runs_drift_at_the_configured_slope(tmp_path: Path) -> None:
    labs = _run_labs(tmp_path / "state.json", runs=10, readings=5)
    mean_l = np.array([lab[..., 0].mean(axis=0) for lab in labs])  # (runs, geometries)
    quiet = spectro_physics(SimulatorConfig("ma6", noise=0.0), "600123")
    l0 = reflectance_to_lab(quiet.measure(ANGLES))[..., 0]
    for i, a in enumerate(ANGLES):
        slope = np.polyfit(np.arange(10), mean_l[:, i], 1)[0]
        expected = (l0[i] + 16.0) / 3.0 * STATED_DRIFT_PER_RUN[a]
        assert slope == pytest.approx(expected, rel=0.15), (a, slope, expected)
    assert set(STATED_DRIFT_PER_RUN) == set(ANGLES_6)


def test_qc_spc_flags_the_drift_before_a_fail(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """One panel a day for 24 days at twice the stated drift, judged at 0.5 ΔE00 against day 0's reading."""
    labs = _run_labs(tmp_path / "state.json", runs=24, readings=1, drift=2.0)
    url = f"sqlite:///{tmp_path / 'qc.sqlite3'}"
    ids = store_job(url, "J-DRIFT", [lab[0].tolist() for lab in labs], angles=ANGLES)
    assert set_standard(capsys, tmp_path, "J-DRIFT", ids[0], url).returncode == 0
    tol = inproc(capsys, tmp_path, "qc", "tolerance", "--formula", "cie2000", "--limit", "0.5", "--json")
    (tmp_path / "tol.json").write_text(tol.stdout)
    args = ("qc", "spc", "--job", "J-DRIFT", "--part", "fender", "--baseline", "6", "--tolerance", "tol.json")
    res = inproc(capsys, tmp_path, *args, "--db", url, "--json")
    assert res.returncode == 0, res.stderr
    face = next(g for g in json.loads(res.stdout)["geometries"] if g["geometry"] == "45as15")
    assert face["first_fail"] is not None  # the drift does reach the tolerance
    assert face["drift_before_fail"] is True, face["drift"]


def test_run_settings_are_checked(tmp_path: Path) -> None:
    with pytest.raises(SimulatorConfigError) as err:
        SimulatorConfig("ma6", run_index=3, state=tmp_path / "s.json")
    assert err.value.field == "run_index"
    with pytest.raises(SimulatorConfigError) as err:
        SimulatorConfig("ma6", run_index=-1)
    assert err.value.field == "run_index"
    with pytest.raises(SimulatorConfigError) as err:
        SimulatorConfig("ma6", drift=-0.5)
    assert err.value.field == "drift"
    bad = tmp_path / "bad.json"
    for text in ("not json", '{"runs": -2}', '{"runs": true}', "[1]"):
        bad.write_text(text)
        with pytest.raises(RunStateError) as state_err:
            next_run_index(bad)
        assert state_err.value.field == "state"
    physics = spectro_physics(SimulatorConfig("ma6", run_index=10_000, noise=0.0), "600123")
    base = spectro_physics(SimulatorConfig("ma6", noise=0.0), "600123")
    assert np.allclose(physics.measure(ANGLES) / base.measure(ANGLES), 1.0 + MAX_RUN_DRIFT)  # saturates
