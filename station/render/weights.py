"""Per-design lobe weights: the interface between the lobe fitter and the renderers.

The designed BRDF is approximated as a sum of cosine lobes with a fixed, shared set of Phong
exponents ``E_i`` (thesis eqs 2.3.1–2.3.3), written for one light direction L and view V as

    f_r(L, V) · (L·N) ≈ K_D (L·N) + Σ_i K_G,i (R·V)^E_i + (L·N) Σ_i K_DD,i (R·V)^E_i,

with R the mirror direction of L about N, every dot product clamped at zero, and the weights in
BRDF units (sr⁻¹): a Lambertian surface of albedo ρ has K_D = ρ/π, and the lobes are *not*
normalised (the peak of lobe i is 1 before weighting). The renderers convert to their normalised
prefiltered maps themselves (see ``station.render.numpy_renderer``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LobeWeights:
    """Non-negative weights of one design over a shared lobe basis (eqs 2.3.1–2.3.3, 2.4.1–2.4.2)."""

    exponents: tuple[float, ...]      # Phong exponents E_i (shared basis)
    k_d: np.ndarray                   # (3,) linear-RGB diffuse weight K_D
    k_dd: np.ndarray                  # (m, 3) directionally-diffuse weights K_DD,i (RGB), >= 0
    k_g: np.ndarray                   # (m,) gloss weights K_G,i (grey), >= 0
