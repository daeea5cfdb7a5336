"""Repeat statistics, outlier rule, instrument bias and SPC limits against hand calculations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.qc.errors import QcInputError
from station.qc.readings import Reading
from station.qc.repeats import correlate, summarise
from station.qc.spc import control_limits


def _r(*lab: tuple[float, float, float], angles: tuple[float, ...] = (45.0,), inst: str = "A") -> Reading:
    return Reading(angles, lab, instrument=inst)


def test_outlier_by_hand() -> None:
    # one geometry, L* 50, 50.1, 49.9, 50, 53 (a* = b* = 0). Median L* 50, so d = 0, .1, .1, 0, 3;
    # median d = 0.1, |d − 0.1| = .1, 0, 0, .1, 2.9 → MAD 0.1, scale 1.4826 · 0.1 = 0.14826;
    # z = −0.674, 0, 0, −0.674, 19.56: only the fifth is an outlier (> 3.5).
    readings = [_r((v, 0.0, 0.0)) for v in (50.0, 50.1, 49.9, 50.0, 53.0)]
    s = summarise(readings)
    assert s.reading_de == pytest.approx((0.0, 0.1, 0.1, 0.0, 3.0))
    assert s.robust_z == pytest.approx((-0.1 / 0.14826, 0.0, 0.0, -0.1 / 0.14826, 2.9 / 0.14826), rel=1e-9)
    assert s.outliers == (False, False, False, False, True)
    assert s.mean.lab[0][0] == pytest.approx(253.0 / 5)
    assert s.mean_kept.lab[0][0] == pytest.approx(50.0)
    # sample sd of L*: mean 50.6, deviations −.6, −.5, −.7, −.6, 2.4 → Σ² = 7.22, /4 → sd √1.805
    assert s.sd is not None and s.sd[0][0] == pytest.approx(math.sqrt(1.805))
    assert s.sd[0][1] == 0.0
    assert s.sd_de is not None and s.sd_de[0] == pytest.approx(math.sqrt(1.805))
    assert s.to_dict()["outliers"] == [4]


def test_two_geometries_and_small_n() -> None:
    a = _r((50.0, 0.0, 0.0), (30.0, 1.0, 1.0), angles=(15.0, 110.0))
    b = _r((50.0, 0.3, 0.4), (30.0, 1.0, 1.0), angles=(110.0, 15.0))  # rows in another order
    s = summarise([a, b])
    # matched by angle: a at 15° is (50, 0, 0), b at 15° is its second row (30, 1, 1) → mean (40, .5, .5)
    assert s.aspecular_deg == (15.0, 110.0)
    assert s.mean.lab[0] == pytest.approx((40.0, 0.5, 0.5))
    assert s.sd is not None and s.sd[0][0] == pytest.approx(math.sqrt(200.0))  # (±10)² · 2 / 1
    assert s.outliers == (False, False)  # N < 3 flags nothing
    one = summarise([a])
    assert one.sd is None and one.mean.lab == a.lab
    with pytest.raises(QcInputError, match="readings"):
        summarise([])


def test_identical_readings_do_not_divide_by_zero() -> None:
    s = summarise([_r((50.0, 0.0, 0.0))] * 4 + [_r((50.05, 0.0, 0.0))])
    # MAD = 0, so the scale is the floor 0.02: z = 0.05 / 0.02 = 2.5, not an outlier
    assert s.robust_z[-1] == pytest.approx(2.5)
    assert not any(s.outliers)


def test_instrument_bias_by_hand() -> None:
    a = [_r((50.0, 1.0, 0.0), inst="MA6 1"), _r((50.2, 1.0, 0.0), inst="MA6 1")]
    b = [_r((50.5, 1.3, -0.4), inst="MA3 2"), _r((50.9, 1.3, -0.4), inst="MA3 2")]
    c = correlate(a, b)
    g = c.per_geometry[0]
    # means: A (50.1, 1, 0), B (50.7, 1.3, −0.4); bias (0.6, 0.3, −0.4), ΔE*ab √(0.36 + 0.09 + 0.16)
    assert (g.dl, g.da, g.db) == pytest.approx((0.6, 0.3, -0.4))
    assert g.de == pytest.approx(math.sqrt(0.61))
    # sd of one B − A difference: √(s_A² + s_B²) = √(0.02 + 0.08) for L*, 0 for a*, b*
    assert g.sd_l == pytest.approx(math.sqrt(0.1)) and g.sd_a == 0.0
    assert (c.instrument_a, c.instrument_b, c.n_a, c.n_b) == ("MA6 1", "MA3 2", 2, 2)
    assert correlate(a[:1], b).per_geometry[0].sd_l is None


def test_control_limits_by_hand() -> None:
    x = [1.0, 2.0, 1.0, 3.0, 1.0]
    # MR = 1, 1, 2, 2 → MR̄ 1.5, σ̂ = 1.5/1.128, centre 1.6, UCL 1.6 + 4.5/1.128 = 5.589, LCL < 0 → 0
    cl = control_limits(x)
    assert cl.mr_bar == pytest.approx(1.5) and cl.centre == pytest.approx(1.6)
    assert cl.ucl == pytest.approx(1.6 + 3 * 1.5 / 1.128) and cl.lcl == 0.0
    assert cl.out_of_control == ()
    steady = [0.5, 0.52, 0.48, 0.5, 0.51, 0.49, 0.5, 0.5, 0.52, 0.48, 2.0]
    cl2 = control_limits(steady)
    mr = np.abs(np.diff(steady)).mean()
    assert cl2.ucl == pytest.approx(np.mean(steady) + 3 * mr / 1.128)
    assert cl2.out_of_control == (10,)
    with pytest.raises(QcInputError, match="values"):
        control_limits([1.0])
    with pytest.raises(QcInputError, match="values"):
        control_limits([1.0, float("nan")])
