"""Physics of the simulated instruments: a virtual panel, noise, inter-instrument bias, warm-up drift,
temperature and calibration state.

* Panel: a design (face/flop/travel/gloss, thesis §3.3) gives Lab at each aspecular angle
  (``FaceFlopTravelGloss.lab_at``), a negative angle evaluated where its flakes are as tilted
  (``station.model.angles.flake_equivalent_aspecular``: −15° reads like 12.5°, lighter than +15°, as on
  a real multi-angle instrument); spectral recovery (``reflectance_from_lab``, colour-science)
  turns it into reflectance factors at 400–700 nm / 10 nm. Or a recipe (:mod:`simulators.recipe`):
  the colorant model of :mod:`station.formulate` gives the reflectance at each aspecular angle directly.
* Noise: a common-mode relative scale term plus independent per-band relative noise, both Gaussian.
  The defaults (σ = 3e-4 and 8e-4) give a per-reading mean CIEDE2000 from the noise-free value of
  about 0.01–0.03, the 0.02–0.05 repeatability quoted for multi-angle instruments
  (research note instruments.md §1, UNCONFIRMED vendor figures).
* Inter-instrument bias: a fixed per-geometry, slowly varying spectral gain seeded by the serial
  number; ``bias_scale = 1`` gives about 0.2–0.3 ΔE00, the typical inter-instrument agreement.
* Warm-up: lamp output relaxes as ``1 + drift · exp(−t/τ)`` and the optics temperature as
  ``T_amb + (T_warm − T_amb)(1 − exp(−t/τ))``; a white calibration divides the drift at that moment
  out, so a reading drifts by the change since calibration.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from simulators.repeatability import run_gain, run_seed
from station.model import FaceFlopTravelGloss
from station.model.angles import flake_equivalent_aspecular
from station.model.difference import delta_e
from station.model.spectra import reflectance_from_lab, reflectance_to_lab

if TYPE_CHECKING:
    from simulators.recipe import RecipePanel

__all__ = [
    "DEFAULT_DESIGN",
    "CalibrationState",
    "InstrumentCharacter",
    "SpectroPhysics",
    "seed_for",
]

DEFAULT_DESIGN = FaceFlopTravelGloss(
    face=(78.0, -0.8, -1.5), flop=(32.0, -0.4, -4.5), travel_deg=80.0, gloss_gu=88.0
)
#: Radiance factor at which the simulated detector saturates: the simulated instruments' wire formats encode
#: reflectance factors up to 2.0; 5 % headroom keeps the bias, noise and drift inside it.
FULL_SCALE_R = 0.95 * 2.0
#: The L* of :data:`FULL_SCALE_R` (127.7). A bright silver's −15° (lighter than its face) can reach it.
FULL_SCALE_L = 116.0 * FULL_SCALE_R ** (1.0 / 3.0) - 16.0
# Certified Lab of the simulated verification tile (a mid-grey ceramic)
VERIFY_TILE_LAB = (52.0, -0.3, 1.2)


def seed_for(serial: str) -> int:
    """Stable 32-bit seed from an instrument serial number."""
    return int.from_bytes(hashlib.sha256(serial.encode()).digest()[:4], "little")


@dataclass
class InstrumentCharacter:
    """Per-instrument constants: noise (relative, 1σ), bias, warm-up drift and temperatures (°C, s)."""

    serial: str = "600123"
    noise_band: float = 8e-4
    noise_scale: float = 3e-4
    bias_scale: float = 0.0
    drift: float = 0.004
    warmup_tau_s: float = 120.0
    t_ambient_c: float = 23.0
    t_warm_c: float = 29.5
    calibration_life_s: float = 8 * 3600.0


@dataclass
class CalibrationState:
    """Zero / white / verification state and identifiers of the simulated instrument."""

    serial: str
    life_s: float
    zero_done: bool = True
    white_at: float | None = 0.0
    verified: bool = True
    counter: int = 1
    lamp_gain_at_white: float = 1.0
    expired: bool = False

    @property
    def calibration_id(self) -> str:
        """Identifier of the current white calibration, ``CAL-<serial>-<n>``."""
        return f"CAL-{self.serial}-{self.counter:04d}"

    def needed(self, now: float) -> str | None:
        """Next step needed: ``zero``, ``white``, ``verify`` or ``None``."""
        if not self.zero_done:
            return "zero"
        if self.white_at is None or self.expired or now - self.white_at > self.life_s:
            return "white"
        if not self.verified:
            return "verify"
        return None

    def expires(self, now: float, wall: dt.datetime) -> dt.datetime | None:
        """Expiry as wall-clock time, or ``None`` without a white calibration."""
        if self.white_at is None or self.expired:
            return None
        return wall + dt.timedelta(seconds=self.life_s - (now - self.white_at))


@dataclass
class SpectroPhysics:
    """A simulated multi-angle spectrophotometer looking at one virtual panel.

    ``measure(aspecular_deg)`` returns reflectance factors, shape ``(n, 31)``. The panel is *recipe*
    when one is given (its colorant-model reflectance), else *design*. *run_index* is this run's index and
    *drift_scale* the scale of the stated drift across runs (:func:`simulators.repeatability.run_gain`).
    """

    design: FaceFlopTravelGloss = DEFAULT_DESIGN
    character: InstrumentCharacter = field(default_factory=InstrumentCharacter)
    warm: bool = True
    clock: Callable[[], float] = time.monotonic
    seed: int | None = None
    recipe: RecipePanel | None = None
    run_index: int = 0
    drift_scale: float = 1.0

    def __post_init__(self) -> None:
        # a run's noise: the given seed's, else the serial's with fresh entropy (simulators.repeatability)
        self._rng = np.random.default_rng(run_seed(seed_for(self.character.serial), self.seed))
        self._bias_rng_seed = seed_for(self.character.serial + "/bias")
        self._t0 = self.clock() - (1e6 if self.warm else 0.0)
        self._cache: dict[tuple[float, ...], np.ndarray] = {}
        self._lock = threading.Lock()
        self.cal = CalibrationState(
            self.character.serial,
            self.character.calibration_life_s,
            white_at=self.clock(),
            lamp_gain_at_white=self.lamp_gain(),
        )

    def set_design(self, design: FaceFlopTravelGloss) -> None:
        """Put another panel under the instrument."""
        with self._lock:
            self.design = design
            self.recipe = None
            self._cache.clear()

    def set_recipe(self, recipe: RecipePanel) -> None:
        """Put a panel painted with *recipe* under the instrument."""
        with self._lock:
            self.recipe = recipe
            self._cache.clear()

    def uptime_s(self) -> float:
        """Seconds since power-on."""
        return self.clock() - self._t0

    def temperature_c(self) -> float:
        """Optics temperature (°C) after the warm-up exponential."""
        c = self.character
        return c.t_ambient_c + (c.t_warm_c - c.t_ambient_c) * (
            1.0 - math.exp(-self.uptime_s() / c.warmup_tau_s)
        )

    def lamp_gain(self) -> float:
        """Relative lamp output, ``1 + drift · exp(−t/τ)``."""
        c = self.character
        return 1.0 + c.drift * math.exp(-self.uptime_s() / c.warmup_tau_s)

    def true_reflectance(self, aspecular_deg: Sequence[float]) -> np.ndarray:
        """Noise-free reflectance of the panel at each aspecular angle, shape ``(n, 31)``."""
        key = tuple(float(a) for a in aspecular_deg)
        with self._lock:
            if key not in self._cache:
                if self.recipe is not None:
                    self._cache[key] = np.asarray(self.recipe.reflectance(key), dtype=float)
                else:
                    lab = self.design.lab_at(flake_equivalent_aspecular(key))
                    lab[..., 0] = np.minimum(lab[..., 0], FULL_SCALE_L)  # the detector saturates
                    self._cache[key] = np.asarray(reflectance_from_lab(lab), dtype=float)
            return self._cache[key]

    def bias_gain(self, n_geometries: int) -> np.ndarray:
        """Fixed spectral gain of this instrument per geometry, shape ``(n, 31)`` (1 = no bias)."""
        rng = np.random.default_rng(self._bias_rng_seed)
        lam = np.linspace(-1.0, 1.0, 31)
        a, b, c = (rng.normal(0.0, s, (n_geometries, 1)) for s in (0.012, 0.008, 0.006))
        return 1.0 + self.character.bias_scale * (a + b * lam + c * lam**2)

    def measure(self, aspecular_deg: Sequence[float]) -> np.ndarray:
        """One noisy reading of the panel (relative to the last white calibration)."""
        true = self.true_reflectance(aspecular_deg)
        c = self.character
        with self._lock:
            scale = 1.0 + self._rng.normal(0.0, c.noise_scale, (true.shape[0], 1))
            band = 1.0 + self._rng.normal(0.0, c.noise_band, true.shape)
        drift = self.lamp_gain() / self.cal.lamp_gain_at_white
        across_runs = run_gain(aspecular_deg, self.run_index, self.drift_scale)
        return true * self.bias_gain(true.shape[0]) * scale * band * drift * across_runs

    # -- calibration -------------------------------------------------------------------------------
    def calibrate_zero(self) -> None:
        """Black-trap reading: dark current known; white must follow."""
        self.cal.zero_done = True
        self.cal.white_at = None
        self.cal.verified = False

    def calibrate_white(self) -> str:
        """White-tile reading: lamp gain at this moment becomes the reference; returns the new id."""
        self.cal.white_at = self.clock()
        self.cal.expired = False
        self.cal.counter += 1
        self.cal.lamp_gain_at_white = self.lamp_gain()
        self.cal.verified = False
        return self.cal.calibration_id

    def verify(self, tolerance_de: float = 0.3) -> tuple[float, bool]:
        """Read the verification tile; return ``(ΔE00 against its certificate, passed)``."""
        tile = FaceFlopTravelGloss(face=VERIFY_TILE_LAB, flop=VERIFY_TILE_LAB, travel_deg=None, gloss_gu=5.0)
        r_true = np.asarray(reflectance_from_lab(np.asarray([VERIFY_TILE_LAB])), dtype=float)
        saved = self.design
        self.design = tile
        try:
            c = self.character
            with self._lock:
                noisy = r_true * (1.0 + self._rng.normal(0.0, c.noise_band, r_true.shape))
            noisy = noisy * self.bias_gain(1) * self.lamp_gain() / self.cal.lamp_gain_at_white
        finally:
            self.design = saved
        de = float(delta_e(reflectance_to_lab(noisy)[0], np.asarray(VERIFY_TILE_LAB), method="cie2000"))
        self.cal.verified = de <= tolerance_de
        return de, self.cal.verified

    def expire_calibration(self) -> None:
        """Fault injection: the white calibration has expired."""
        self.cal.expired = True
