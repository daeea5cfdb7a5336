"""Every injectable fault against the real MA6 driver over a real pty: a successful retry or a typed
error, within a bounded time, and never a partial or wrong reading."""

from __future__ import annotations

import time

import numpy as np
import pytest

from simulators.physics import DEFAULT_DESIGN
from station.drivers import (
    BatteryLow,
    CalibrationNeeded,
    DeviceInUse,
    DeviceTimeout,
    Disconnected,
    HardwareFailure,
    Misread,
    ProtocolError,
    SpectralReading,
    TiltDetected,
)
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import SerialTransport
from station.model.angles import flake_equivalent_aspecular
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab
from tests.drivers.conftest import FAST, Ma6Bench

ANGLES = (-15, 15, 25, 45, 75, 110)


def assert_true_reading(r: SpectralReading, bench: Ma6Bench, tol_de: float = 0.15) -> None:
    """A complete reading of the right panel: 6×31 finite values, Lab close to the design."""
    assert r.reflectance.shape == (6, 31)
    assert np.all(np.isfinite(r.reflectance))
    lab = reflectance_to_lab(r.reflectance)
    de = delta_e(lab, bench.physics.design.lab_at(flake_equivalent_aspecular(ANGLES)), method="cie2000")
    assert float(np.max(de)) < tol_de


@pytest.mark.parametrize(
    "spec",
    [
        "no-reply@MS",
        "no-reply@RD",
        "slow-reply@MS",
        "slow-reply@RD",
        "corrupt-checksum",
        "partial-frame",
        "partial-frame@PO",
        "garbage@MS",
    ],
)
def test_transient_fault_recovers(ma6, spec):
    ma6.faults.add(spec)
    t0 = time.monotonic()
    r = ma6.inst.measure()
    assert time.monotonic() - t0 < 3.0
    assert_true_reading(r, ma6)
    assert not ma6.faults.active(spec.split("@")[0])  # it did fire


@pytest.mark.parametrize(
    ("spec", "error"),
    [
        ("lamp-failure", HardwareFailure),
        ("tilt", TiltDetected),
        ("battery-low", BatteryLow),
        ("out-of-range", Misread),
        ("stuck-busy", DeviceTimeout),
        ("corrupt-checksum:9", ProtocolError),
        ("device-busy", DeviceInUse),
    ],
)
def test_persistent_fault_is_typed_error(ma6, spec, error):
    ma6.faults.add(spec)
    t0 = time.monotonic()
    with pytest.raises(error):
        ma6.inst.measure()
    assert time.monotonic() - t0 < 3.0
    ma6.faults.clear()
    assert_true_reading(ma6.inst.measure(), ma6)  # the link is still in step afterwards


def test_calibration_expired_then_recalibrated(ma6):
    before = ma6.inst.status().calibration_id
    ma6.faults.add("cal-expired")
    with pytest.raises(CalibrationNeeded) as info:
        ma6.inst.measure()
    assert info.value.step == "white"
    assert ma6.inst.status().needed == "white"
    result = ma6.inst.calibrate()
    assert result.passed and result.verification_de < 0.3
    assert result.calibration_id != before
    r = ma6.inst.measure()
    assert r.calibration_id == result.calibration_id
    assert_true_reading(r, ma6)


def test_hang_after_long_run_reconnects(ma6):
    ma6.faults.add("hang-after:3")
    ma6.device.commands = 0
    t0 = time.monotonic()
    r = ma6.inst.measure()  # MS, PO..., the third command onwards hangs until the port is reopened
    assert time.monotonic() - t0 < 4.0
    assert_true_reading(r, ma6)


def test_unplug_mid_measurement_is_disconnected(ma6):
    ma6.faults.add("unplug@PO")
    t0 = time.monotonic()
    with pytest.raises(Disconnected):
        ma6.inst.measure()
    assert time.monotonic() - t0 < 2.0


def test_second_process_holding_port():
    bench = Ma6Bench()
    try:
        bench.host.hold_port()  # the same flock pyserial's exclusive=True takes, from another fd
        with pytest.raises(DeviceInUse):
            bench.inst.open()
    finally:
        bench.close()


def test_second_owner_in_process_refused(ma6):
    with pytest.raises(DeviceInUse):
        MA6Spectro(SerialTransport(ma6.host.path), **FAST).open()


def test_round_trip_within_repeatability():
    """design → simulated panel → driver → Lab: mean ΔE00 over 10 readings ≤ 0.05 (no bias)."""
    bench = Ma6Bench()
    try:
        bench.inst.open()
        labs = np.array([reflectance_to_lab(bench.inst.measure().reflectance) for _ in range(10)])
    finally:
        bench.close()
    target = DEFAULT_DESIGN.lab_at(flake_equivalent_aspecular(ANGLES))
    de_design = delta_e(labs, target[None], method="cie2000")
    de_mean = delta_e(labs, labs.mean(axis=0)[None], method="cie2000")  # repeatability (MCDM)
    assert float(de_design.mean()) <= 0.05
    assert float(de_mean.mean()) <= 0.05
    assert float(de_mean.mean()) > 0.002  # the noise is really there


def test_inter_instrument_bias_is_reported_size():
    """A second instrument with typical bias reads the same panel 0.1–0.6 ΔE00 away (mean over angles)."""
    bench = Ma6Bench(serial="600777", bias_scale=1.0)
    try:
        bench.inst.open()
        labs = np.array([reflectance_to_lab(bench.inst.measure().reflectance) for _ in range(5)])
    finally:
        bench.close()
    bias = delta_e(
        labs.mean(axis=0), DEFAULT_DESIGN.lab_at(flake_equivalent_aspecular(ANGLES)), method="cie2000"
    )
    assert 0.1 <= float(bias.mean()) <= 0.6


def test_port_held_by_another_process():
    """A real second process takes the exclusive flock pyserial uses; our open gets DeviceInUse."""
    import subprocess
    import sys

    from tests.processes import Child

    bench = Ma6Bench()
    hold = (
        "import fcntl, os, sys; fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY);"
        "fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB); print('held', flush=True); sys.stdin.read()"
    )
    try:
        with Child([sys.executable, "-c", hold, bench.host.path], stdin=subprocess.PIPE) as holder:
            assert holder.out is not None and holder.stdin is not None
            holder.out.wait_for("held", timeout=60)
            with pytest.raises(DeviceInUse):
                bench.inst.open()
            holder.stdin.close()  # the holder reads to the end of its input, then exits
            assert holder.finish(60) == 0
    finally:
        bench.close()
    bench2 = Ma6Bench()  # once the other process is gone the port opens
    try:
        bench2.inst.open()
        assert_true_reading(bench2.inst.measure(), bench2)
    finally:
        bench2.close()
