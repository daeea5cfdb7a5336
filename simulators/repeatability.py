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
instead of bit-identical repeats. Warm-up drift within a run is the lamp's of
:class:`simulators.physics.SpectroPhysics` (``--cold``), corrected by each white calibration.

**Drift across runs** (:data:`STATED_DRIFT_PER_RUN`, :func:`run_gain`): a run is one start of a simulator
process (a day at the bench). Run *k* reads every reflectance factor at geometry θ multiplied by
``1 + drift · k · g(θ)``, *g* the stated relative drift per run (the white tile's reference ageing, the
near-specular geometries the most) and *drift* the ``--drift`` scale (1 = stated). The run index is
``--run-index K`` or the counter kept in ``--state FILE`` (:func:`next_run_index`: each start takes the
file's count and writes one more), so drift across days is deterministic and survives a restart. A
relative change g of every reflectance moves L* by (L* + 16)/3 · g (L* = 116 (Y/Yn)^⅓ − 16, for
Y/Yn > 0.008856): at L* 50, g = 0.0012 is ΔL* 0.026 a run, about one short-term repeatability. The
drift stops at :data:`MAX_RUN_DRIFT` (4 %, inside the detector's 5 % headroom), where a lab would have
re-certified its white tile long before (at g = 0.0015, after 27 runs).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

import numpy as np

from station.errors import InputError

__all__ = [
    "MAX_RUN_DRIFT",
    "MAX_RUN_INDEX",
    "STATED_DRIFT_PER_RUN",
    "STATED_REPEATABILITY_DE00",
    "RunStateError",
    "measured_repeatability",
    "next_run_index",
    "run_gain",
    "run_seed",
    "stated_drift",
    "stated_repeatability",
]

#: Stated short-term repeatability, mean ΔE00 from the mean of repeats, at most, by aspecular angle (°).
STATED_REPEATABILITY_DE00: dict[float, float] = {
    -15.0: 0.05,
    15.0: 0.05,
    25.0: 0.05,
    45.0: 0.04,
    75.0: 0.04,
    110.0: 0.04,
}


#: Stated slow drift across runs: relative change of every reflectance factor per run, by aspecular angle (°).
STATED_DRIFT_PER_RUN: dict[float, float] = {
    -15.0: 0.0015,
    15.0: 0.0012,
    25.0: 0.0010,
    45.0: 0.0008,
    75.0: 0.0006,
    110.0: 0.0005,
}
#: The largest relative drift across runs: the simulated detector's headroom (physics.FULL_SCALE_R) is 5 %.
MAX_RUN_DRIFT = 0.04
#: The largest run index a state file or ``--run-index`` may hold (about 27 years of daily runs).
MAX_RUN_INDEX = 10_000


class RunStateError(InputError):
    """A run-state file that cannot be read or written (names ``state``)."""


class _Measures(Protocol):
    def measure(self, aspecular_deg: Sequence[float]) -> np.ndarray: ...


def stated_repeatability(aspecular_deg: float) -> float:
    """The stated figure at *aspecular_deg*: the nearest stated angle's (ΔE00)."""
    nearest = min(STATED_REPEATABILITY_DE00, key=lambda a: abs(a - aspecular_deg))
    return STATED_REPEATABILITY_DE00[nearest]


def stated_drift(aspecular_deg: float) -> float:
    """The stated relative drift per run at *aspecular_deg*: the nearest stated angle's (dimensionless)."""
    nearest = min(STATED_DRIFT_PER_RUN, key=lambda a: abs(a - aspecular_deg))
    return STATED_DRIFT_PER_RUN[nearest]


def run_gain(aspecular_deg: Sequence[float], run_index: int, scale: float = 1.0) -> np.ndarray:
    """Relative gain of run *run_index* per geometry, ``1 + min(scale · run_index · g(θ), MAX_RUN_DRIFT)``,
    shape ``(n, 1)`` (dimensionless)."""
    g = np.array([stated_drift(a) for a in aspecular_deg], dtype=float)
    return (1.0 + np.minimum(scale * run_index * g, MAX_RUN_DRIFT))[:, None]


def next_run_index(state: Path) -> int:
    """This run's index from the state file *state* (0 when it does not exist yet), the count written back
    one higher (atomically: a crash leaves the old count). :class:`RunStateError` for a file that is not
    ``{"runs": N}`` with 0 <= N <= :data:`MAX_RUN_INDEX`, or that cannot be written."""
    runs: object = 0
    try:
        if state.exists():
            runs = json.loads(state.read_text(encoding="utf-8")).get("runs")
    except (OSError, ValueError, AttributeError) as exc:
        raise RunStateError("state", 'a JSON file {"runs": N}', str(state)) from exc
    if not isinstance(runs, int) or isinstance(runs, bool) or not 0 <= runs <= MAX_RUN_INDEX:
        raise RunStateError("state", f'{{"runs": N}} with 0 <= N <= {MAX_RUN_INDEX}', runs)
    tmp = state.with_name(state.name + ".tmp")
    try:
        tmp.write_text(json.dumps({"runs": runs + 1}), encoding="utf-8")
        os.replace(tmp, state)
    except OSError as exc:
        raise RunStateError("state", "a writable file", str(state)) from exc
    return runs


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
