"""A physical spray-out panel model, the measuring of every front's closed loop (SYNTHETIC).

A real spray-out differs from the formulation model's prediction: the colorants in the can are
not exactly the database's (batch-to-batch strength), the film is thicker or thinner, flakes lie
flatter or steeper, and the instrument adds noise. :class:`SprayOutModel` reproduces those effects
with a fixed seed:

* per-colorant strength: K_i and S_i multiplied by (1 + ε), ε ~ N(0, ``strength_sd``), with a gentle
  wavelength tilt (± ``tilt_sd`` across 400–700 nm);
* flake orientation: the r.m.s. tilt slope m of every effect pigment multiplied by (1 + N(0, ``flake_sd``)),
  its coverage σ by (1 + N(0, ``strength_sd``));
* measurement: Gaussian noise on L*, a*, b* (σ ``lab_noise``) and on gloss (σ ``gloss_noise`` GU).

``measure(recipe)`` returns :class:`station.model.AspecularMeasurements`, the same type a
spectrophotometer reading becomes, so the closed loop cannot tell it from an instrument.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from station.formulate.colorants import (
    WAVELENGTHS_NM,
    ColorantDatabase,
    default_database,
    predict_gloss,
    predict_lab,
)
from station.formulate.library import STANDARD_ANGLES
from station.model import AspecularMeasurements


def perturbed_database(
    db: ColorantDatabase, seed: int, strength_sd: float = 0.05, tilt_sd: float = 0.03, flake_sd: float = 0.05
) -> ColorantDatabase:
    """A copy of *db* whose colorants differ as real batches do (see module docstring)."""
    rng = np.random.default_rng(seed)
    tilt_axis = (WAVELENGTHS_NM - 550.0) / 150.0
    out = []
    for c in db.colorants:
        fk = (1.0 + rng.normal(0, strength_sd)) * (1.0 + rng.normal(0, tilt_sd) * tilt_axis)
        fs = (1.0 + rng.normal(0, strength_sd)) * (1.0 + rng.normal(0, tilt_sd) * tilt_axis)
        flake = c.flake
        if flake is not None:
            flake = dataclasses.replace(
                flake,
                orientation_m=flake.orientation_m * (1.0 + rng.normal(0, flake_sd)),
                coverage_per_fraction=flake.coverage_per_fraction * (1.0 + rng.normal(0, strength_sd)),
            )
        out.append(dataclasses.replace(c, k=c.k * fk, s=c.s * fs, flake=flake))
    return ColorantDatabase(
        tuple(out),
        db.max_total,
        db.max_effect,
        synthetic=True,
        flake_depth=db.flake_depth,
        scatter_extinction=db.scatter_extinction,
    )


class SprayOutModel:
    """Simulated spray-out + multi-angle spectrophotometer + gloss meter (SYNTHETIC).

    Parameters
    ----------
    seed
        Fixes the batch deviations and the measurement noise sequence.
    angles_deg
        Angles the "instrument" reports (degrees).
    lab_noise, gloss_noise
        Measurement noise σ (ΔE*ab units per channel; GU).
    """

    def __init__(
        self,
        seed: int = 7,
        angles_deg: tuple[float, ...] = STANDARD_ANGLES,
        lab_noise: float = 0.05,
        gloss_noise: float = 0.5,
        db: ColorantDatabase | None = None,
        **perturbation: float,
    ) -> None:
        self.model_db = db or default_database()
        self.true_db = perturbed_database(self.model_db, seed, **perturbation)
        self.angles_deg = tuple(float(a) for a in angles_deg)
        self.lab_noise = lab_noise
        self.gloss_noise = gloss_noise
        self._rng = np.random.default_rng(seed + 1)
        self.panels = 0

    def true_lab(self, c: NDArray[np.float64]) -> NDArray[np.float64]:
        """Noise-free Lab of the panel sprayed from concentration vector *c*, shape (A, 3)."""
        return predict_lab(c, self.angles_deg, self.true_db)

    def measure(self, recipe: dict[str, float]) -> AspecularMeasurements:
        """Spray a panel from *recipe* and measure it: Lab per angle + 60° gloss."""
        c = self.model_db.check(self.model_db.vector(recipe))
        self.panels += 1
        lab = self.true_lab(c) + self._rng.normal(0.0, self.lab_noise, (len(self.angles_deg), 3))
        lab[:, 0] = np.clip(lab[:, 0], 0.0, None)
        gloss = float(
            np.clip(predict_gloss(c, self.true_db) + self._rng.normal(0.0, self.gloss_noise), 0, 100)
        )
        return AspecularMeasurements(self.angles_deg, lab, gloss)
