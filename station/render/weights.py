"""Per-design lobe weights: the hand-off between the fitter and the renderers (thesis eqs 2.3.1–2.3.3).

The fitted reflectance, written as BRDF × cosine (units: sr⁻¹, linear sRGB per channel), is

    f(L, V)·(L·N) ≈ K_D (L·N)                                   (eq 2.3.1, diffuse)
                  + Σ_i K_G,i (R·V)^E_i                        (eq 2.3.2, gloss, grey)
                  + (L·N) Σ_i K_DD,i (R·V)^E_i                 (eq 2.3.3, directionally diffuse, RGB)
                  + (L·N) K_A min(1, 1 + R·V)                   (aspecular fall-off, RGB)

with R the mirror direction of L about N, negative dot products clamped to zero, and the Phong
exponents E_i shared by every design (the basis). The weights multiply the *raw* cosine lobes
(R·V)^E, not normalised ones. A white Lambertian surface is K_D = 1/π, K_DD = K_G = K_A = 0.

The aspecular fall-off term is not in the thesis. Every cosine lobe (R·V)^E is zero past the aspecular
angle α = 90°, so eqs 2.3.1–2.3.3 hold the colour constant (K_D) from 90° to 180°; a design whose colour
keeps darkening there (a flop travel of 180°) cannot be followed. min(1, 1 + cos α) = 1 − (−R·V)₊ is 1 up to
90° and falls linearly in cos α to 0 at 180°, so K_D + K_A·min(1, 1 + cos α) is a diffuse level that fades
past 90° (docs/render.md, "accuracy"). Under an environment it is K_A (E(N) − A), with E(N) the irradiance
and A = ∫ L(ω)(N·ω)₊(−R·ω)₊ dω the directionally diffuse integral of an exponent-1 lobe about −R
(:mod:`station.render.numpy_renderer` evaluates it from the diffuse map).

Renderers that look up *normalised* prefiltered environment maps (each lobe divided by its integral
over the sphere, so a constant environment of radiance 1 prefilters to 1) use
:meth:`LobeWeights.map_weights`, which folds the normalisation in:

    diffuse map   D(N) = (1/π) ∫ L(ω) max(N·ω, 0) dω          → weight π·K_D
    lobe map      C_E(R) = (E+1)/(2π) ∫ L(ω) max(R·ω, 0)^E dω  → weight 2π/(E+1)·K

so that, following eqs 2.5.1–2.5.3, radiance = π K_D D(N) + (R·N) Σ w_DD,i C_i(R) + Σ w_G,i C_i(R).
With the fall-off term the model is rewritten as (L·N)(K_D + K_A) − (L·N) K_A (−R·V)₊: the diffuse map
weight is w_D = π (K_D + K_A), exact for α ≤ 90°, and the renderers subtract π K_A times the exponent-1
lobe about −R (:meth:`LobeWeights.fall_off_map_weight`, ``numpy_renderer.fall_off_term``). A renderer
that knows nothing of K_A and reads :meth:`map_weights` is therefore exact up to α = 90° and too bright
past it, instead of missing the term altogether.
(The renderers may equally do this conversion themselves, see ``station.render.numpy_renderer``.)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class LobeWeights:
    """Non-negative weights of the lobe-blend BRDF for one design (eqs 2.3.1–2.3.3, 2.4.1).

    Attributes
    ----------
    exponents
        Phong exponents E_i of the shared basis (dimensionless, > 0), length m.
    k_d
        (3,) diffuse weight K_D, linear sRGB, sr⁻¹.
    k_dd
        (m, 3) directionally diffuse weights K_DD,i, linear sRGB, sr⁻¹, ≥ 0.
    k_g
        (m,) grey gloss weights K_G,i, sr⁻¹, ≥ 0.
    k_a
        (3,) aspecular fall-off weight K_A, linear sRGB, sr⁻¹, ≥ 0 (module doc); default zeros (the
        thesis's model).
    """

    exponents: tuple[float, ...]
    k_d: np.ndarray
    k_dd: np.ndarray
    k_g: np.ndarray
    k_a: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        m = len(self.exponents)
        k_d = np.asarray(self.k_d, dtype=float).reshape(3)
        k_dd = np.asarray(self.k_dd, dtype=float).reshape(m, 3)
        k_g = np.asarray(self.k_g, dtype=float).reshape(m)
        k_a = np.asarray(self.k_a, dtype=float).reshape(3)
        for name, arr in (("k_d", k_d), ("k_dd", k_dd), ("k_g", k_g), ("k_a", k_a)):
            if not np.all(np.isfinite(arr)) or np.any(arr < 0.0):
                raise ValueError(f"LobeWeights.{name}: expected finite values >= 0, got {arr!r}")
        for arr in (k_d, k_dd, k_g, k_a):
            arr.setflags(write=False)
        object.__setattr__(self, "exponents", tuple(float(e) for e in self.exponents))
        object.__setattr__(self, "k_d", k_d)
        object.__setattr__(self, "k_dd", k_dd)
        object.__setattr__(self, "k_g", k_g)
        object.__setattr__(self, "k_a", k_a)

    @property
    def lobe_count(self) -> int:
        """Number m of basis lobes."""
        return len(self.exponents)

    def map_weights(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return (w_d (3,), w_dd (m,3), w_g (m,)) for normalised prefiltered maps (see module doc).

        w_d = π (K_D + K_A): the diffuse map carries the fall-off term's part up to α = 90° (module doc).
        """
        scale = 2.0 * np.pi / (np.asarray(self.exponents) + 1.0)
        return np.pi * (self.k_d + self.k_a), self.k_dd * scale[:, None], self.k_g * scale

    @property
    def has_fall_off(self) -> bool:
        """True when the aspecular fall-off term is used (some K_A > 0)."""
        return bool(np.any(self.k_a > 0.0))

    def fall_off_map_weight(self) -> np.ndarray:
        """(3,) weight π·K_A of the fall-off correction (≤ 0 per unit weight, ``numpy_renderer.fall_off_term``)
        that the renderers add to w_D D(N) (module doc)."""
        return np.pi * self.k_a

    def brdf_cos(self, n_dot_l: np.ndarray, r_dot_v: np.ndarray) -> np.ndarray:
        """Evaluate BRDF·cos (sr⁻¹, linear sRGB, shape (..., 3)) from N·L and R·V (eqs 2.3.1–2.3.3 and the
        fall-off term of the module doc; R·V unclamped, in [−1, 1])."""
        nl = np.maximum(np.asarray(n_dot_l, dtype=float), 0.0)[..., None]
        rv_raw = np.clip(np.asarray(r_dot_v, dtype=float), -1.0, 1.0)[..., None]
        rv = np.maximum(rv_raw, 0.0)
        lobes = rv ** np.asarray(self.exponents)  # (..., m)
        colour = nl * (self.k_d + lobes @ self.k_dd + np.minimum(1.0, 1.0 + rv_raw) * self.k_a)
        gloss = (lobes @ self.k_g)[..., None]
        return colour + gloss * (nl > 0.0)
