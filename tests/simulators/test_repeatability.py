"""The simulators' repeatability measured against the figure they state per geometry; runs without a
seed differ (no bit-identical repeats), runs with one repeat exactly."""

from __future__ import annotations

import numpy as np
import pytest

from simulators.physics import InstrumentCharacter, SpectroPhysics
from simulators.repeatability import STATED_REPEATABILITY_DE00, measured_repeatability, stated_repeatability
from station.model.domain import ANGLES_6


def test_measured_repeatability_within_the_stated_figure_per_geometry() -> None:
    measured = measured_repeatability(SpectroPhysics(seed=11), ANGLES_6, n=30)
    for angle, de in zip(ANGLES_6, measured, strict=True):
        # within the stated figure, and a real spread (repeats are not identical)
        assert 0.005 < de <= stated_repeatability(angle), (angle, de)
    assert set(STATED_REPEATABILITY_DE00) == set(ANGLES_6)


def test_a_noise_free_instrument_measures_zero() -> None:
    quiet = SpectroPhysics(character=InstrumentCharacter(noise_band=0.0, noise_scale=0.0))
    assert np.all(measured_repeatability(quiet, ANGLES_6, n=3) < 1e-9)


@pytest.mark.parametrize("seed", [None, 7])
def test_runs_repeat_only_with_a_seed(seed: int | None) -> None:
    a = SpectroPhysics(seed=seed).measure(ANGLES_6)
    b = SpectroPhysics(seed=seed).measure(ANGLES_6)
    assert np.array_equal(a, b) == (seed is not None)
