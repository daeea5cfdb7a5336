"""Simulator physics: warm-up, temperature, bias, noise, calibration state, fault plans."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simulators.faults import FaultPlan, FaultSpecError
from simulators.physics import DEFAULT_DESIGN, InstrumentCharacter, SpectroPhysics
from station.model.angles import flake_equivalent_aspecular
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab

ANGLES = (-15, 15, 25, 45, 75, 110)


class Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def test_warm_up_temperature_and_drift_follow_the_exponential():
    clock = Clock()
    ch = InstrumentCharacter(warmup_tau_s=100.0, drift=0.004, t_ambient_c=23.0, t_warm_c=29.5)
    p = SpectroPhysics(character=ch, warm=False, clock=clock)
    assert p.temperature_c() == pytest.approx(23.0)
    assert p.lamp_gain() == pytest.approx(1.004)
    clock.t += 100.0  # one time constant
    assert p.temperature_c() == pytest.approx(23.0 + 6.5 * (1 - math.exp(-1)))
    assert p.lamp_gain() == pytest.approx(1 + 0.004 * math.exp(-1))


def test_drift_since_calibration_shows_in_readings():
    clock = Clock()
    ch = InstrumentCharacter(warmup_tau_s=100.0, drift=0.02, noise_band=0.0, noise_scale=0.0)
    p = SpectroPhysics(character=ch, warm=False, clock=clock)
    p.calibrate_zero()
    p.calibrate_white()  # cold: reference taken at gain 1.02
    fresh = p.measure(ANGLES)
    np.testing.assert_allclose(fresh, p.true_reflectance(ANGLES), rtol=1e-12)
    clock.t += 1e4  # warm: lamp gain back to 1, readings 1/1.02 of the truth
    np.testing.assert_allclose(p.measure(ANGLES), p.true_reflectance(ANGLES) / 1.02, rtol=1e-12)
    p.calibrate_white()
    np.testing.assert_allclose(p.measure(ANGLES), p.true_reflectance(ANGLES), rtol=1e-12)


def test_bias_is_fixed_per_serial_and_scales():
    a = SpectroPhysics(character=InstrumentCharacter(serial="A1", bias_scale=1.0))
    b = SpectroPhysics(character=InstrumentCharacter(serial="A1", bias_scale=1.0))
    c = SpectroPhysics(character=InstrumentCharacter(serial="B2", bias_scale=1.0))
    np.testing.assert_array_equal(a.bias_gain(6), b.bias_gain(6))
    assert not np.allclose(a.bias_gain(6), c.bias_gain(6))
    zero = SpectroPhysics(character=InstrumentCharacter(serial="A1", bias_scale=0.0))
    np.testing.assert_array_equal(zero.bias_gain(6), np.ones((6, 31)))


def test_noise_gives_published_repeatability():
    p = SpectroPhysics(seed=3)
    labs = reflectance_to_lab(np.array([p.measure(ANGLES) for _ in range(20)]))
    mcdm = delta_e(labs, labs.mean(axis=0)[None], method="cie2000").mean()
    assert 0.01 <= mcdm <= 0.05
    truth = DEFAULT_DESIGN.lab_at(flake_equivalent_aspecular(ANGLES))
    assert delta_e(reflectance_to_lab(p.true_reflectance(ANGLES)), truth, method="cie2000").max() < 1e-6


def test_calibration_state_machine():
    clock = Clock()
    p = SpectroPhysics(character=InstrumentCharacter(calibration_life_s=100.0), clock=clock)
    assert p.cal.needed(clock()) is None
    p.calibrate_zero()
    assert p.cal.needed(clock()) == "white"
    cid = p.calibrate_white()
    assert cid == "CAL-600123-0002" and p.cal.needed(clock()) == "verify"
    de, ok = p.verify()
    assert ok and de < 0.3 and p.cal.needed(clock()) is None
    clock.t += 101.0
    assert p.cal.needed(clock()) == "white"


def test_fault_plan_parsing_and_counting():
    f = FaultPlan(["no-reply@RD:2", "tilt", "hang-after:5"])
    assert f.hang_after == 5
    assert not f.fire("no-reply", "MS")
    assert f.fire("no-reply", "RD") and f.fire("no-reply", "RD") and not f.fire("no-reply", "RD")
    assert f.fire("tilt", "MS") and f.fire("tilt", "MS")  # persistent
    f.clear("tilt")
    assert not f.active("tilt")
    for bad in ("nonsense", "tilt:x"):
        with pytest.raises(FaultSpecError):
            FaultPlan([bad])
