"""Short-term repeatability of the simulated spectrophotometers, and the seed of a simulator run.

**Stated repeatability** (:data:`STATED_REPEATABILITY_DE00`): the mean CIEDE2000 of a reading from the
mean of its repeats (the "MCDM" of instrument data sheets), per aspecular angle, on a warm, calibrated
instrument. Vendor figures for multi-angle instruments are about 0.02–0.05 ΔE (research note
instruments.md, UNCONFIRMED); the simulators state at most 0.05 at every geometry, the near-specular
angles being the noisiest. :func:`measured_repeatability` measures a simulator against it; the noise
itself is :class:`simulators.physics.InstrumentCharacter`'s (a common-mode scale term and per-band
noise, both relative and Gaussian).

**Seed of a run** (:func:`run_seed`): with ``--seed`` the noise stream is that seed's, so a run is
reproducible; without one it combines the serial with fresh entropy, so two runs (two ``station
measure sim:ma6`` calls) give two different readings of the same panel, as a real instrument does,
instead of bit-identical repeats. Long-term drift is the lamp's warm-up drift of
:class:`simulators.physics.SpectroPhysics` (``--cold``), corrected by each white calibration.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

__all__ = ["STATED_REPEATABILITY_DE00", "measured_repeatability", "run_seed", "stated_repeatability"]

#: Stated short-term repeatability, mean ΔE00 from the mean of repeats, at most, by aspecular angle (°).
STATED_REPEATABILITY_DE00: dict[float, float] = {
    -15.0: 0.05,
    15.0: 0.05,
    25.0: 0.05,
    45.0: 0.04,
    75.0: 0.04,
    110.0: 0.04,
}


class _Measures(Protocol):
    def measure(self, aspecular_deg: Sequence[float]) -> np.ndarray: ...


def stated_repeatability(aspecular_deg: float) -> float:
    """The stated figure at *aspecular_deg*: the nearest stated angle's (ΔE00)."""
    nearest = min(STATED_REPEATABILITY_DE00, key=lambda a: abs(a - aspecular_deg))
    return STATED_REPEATABILITY_DE00[nearest]


def run_seed(serial_seed: int, seed: int | None) -> np.random.SeedSequence:
    """The noise seed of a run: *seed* when given (reproducible), else the serial's with fresh entropy."""
    if seed is not None:
        return np.random.SeedSequence(seed)
    fresh = np.random.SeedSequence()
    return np.random.SeedSequence([serial_seed, *fresh.generate_state(2).tolist()])


def measured_repeatability(physics: _Measures, aspecular_deg: Sequence[float], n: int = 30) -> np.ndarray:
    """Mean ΔE00 of *n* readings from their mean at each angle, shape ``(len(aspecular_deg),)``."""
    import colour

    from station.model.spectra import reflectance_to_lab

    labs = reflectance_to_lab(np.array([physics.measure(aspecular_deg) for _ in range(n)]))
    de = colour.delta_E(labs, labs.mean(axis=0)[None], method="CIE 2000")
    return np.asarray(de, dtype=float).mean(axis=0)
