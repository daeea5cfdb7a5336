"""The designed BRDF and its real-time non-negative fit to the lobe basis (thesis §2.4, eqs 2.4.1–2.4.2).

Designed BRDF (what is fitted; docs/render-fit.md). For light L, view V, normal N, mirror direction
R = 2(N·L)N − L and aspecular angle α = ∠(R, V):

    f(L, V)·(N·L) = (N·L) ρ(α)/π + ρ_s (n + 1)/(2π) · max(R·V, 0)^n       (N·L, N·V > 0)

* ρ(α) (linear sRGB, per channel) is the reflectance factor of the clamped-quadratic colour at α:
  Lab from :meth:`FaceFlopTravelGloss.lab_at` → :func:`station.model.colorimetry.lab_to_linear_srgb`.
  Below the model's face angle (15°) the colour is held at the face: the quadratic's extrapolation
  towards specular grows without bound as θ_clamp approaches 15° (s(0)² = (θ_c/(θ_c − 15))², 256 at
  θ_c = 16°), and near specular the gloss lobe dominates anyway.
  A reflectance factor compares the sample with the perfect white diffuser (BRDF 1/π) under the same
  geometry, so the colour part of the BRDF is ρ(α)/π (the thesis's I·f = C, eq 4.3.3–4.3.4).
* the gloss lobe is the energy-conserving Phong lobe of :func:`station.model.gloss.lobe_from_gloss`
  (:mod:`station.model.lobe`; the shading is :func:`station.model.shading.shade_reflectance`):
  exponent n, specular albedo ρ_s (grey, the coat's Fresnel reflectance at 60°). The model defines it
  as the distribution (n + 1)/(2π) cosⁿψ of the reflected flux about the mirror direction, so the
  reflected radiance is ρ_s times the normalised-lobe average of the incident radiance about R (a
  constant environment L gives ρ_s L): exactly the K_G form of eq 2.3.2 with K_G = ρ_s (n+1)/(2π).
  GU → (n, ρ_s) is :func:`station.model.lobe.phong_lobe` (a table of the forward gloss-meter
  simulation, log n interpolated), because one call of the inverse takes ~0.1 s.

The lobe model (eqs 2.3.1–2.3.3, :mod:`station.render.weights`) splits the same way, so the fit solves
two fixed-matrix problems per design, each over the sample geometries of :mod:`station.render.lobes`
weighted by √(solid angle):

* colour rows, per RGB channel:   (N·L)[K_D + Σ K_DD,i cos^E_i α + K_A min(1, 1 + cos α)] ≈ (N·L) ρ(α)/π
                                   (m + 2 unknowns; with ``fall_off=False`` no K_A: m + 1, the thesis)
* gloss rows, grey:                Σ K_G,i cos^E_i α ≈ ρ_s (n+1)/(2π) cos^n α         (m unknowns)

(``gloss_form="cosine"`` instead folds the gloss into grey K_DD over all rows; kept for comparison.)
K_A is the aspecular fall-off term of :mod:`station.render.weights` (not in the thesis): the only column
that is non-zero past α = 90° besides K_D, and there it falls linearly in cos α to zero at 180°, so the fit
can follow a colour that keeps darkening past 90° (a 180° travel) without lifting K_D (docs/render.md).

Methods (all return weights ≥ 0; compare them with ``python -m bench.lobe_fit``):

* ``perceptual`` (default): the same two problems with every row's residual divided by the target's
  own magnitude to the power 2/3, per design and channel, then exact NNLS (Lawson–Hanson) per design.
  CIELAB lightness is L* = 116 (Y/Y_n)^(1/3) − 16, so dL* = (116/3) Y_n^(−1/3) Y^(−2/3) dY: a residual
  ΔY weighted by Y^(−2/3) is proportional to the ΔL* it causes. The radiance-weighted fit of eq 2.4.2
  lets the dark flop of a silver (L* 25–40, reflectance ~0.05 against ~2 at the face) carry almost no
  weight, and a sun samples the BRDF at one geometry per pixel, so that error shows (docs/render.md,
  accuracy). Colour rows weigh by the channel's (N·L)ρ(α)/π, gloss rows by the lobe plus the grey
  colour term at the same geometry; both floored at PERCEPTUAL_FLOOR. ~0.6 ms per design.
* ``auto``: the radiance-weighted rows of eq 2.4.2: ``nnls`` for one design or a few, ``kkt`` for
  batches (both exact, same weights).
* ``kkt``: exact NNLS for batches: guess each passive set from the unconstrained solution, verify the
  KKT conditions with the precomputed passive-set map, repair up to four times, Lawson–Hanson for the
  rest; O(k²) per design, vectorised.
* ``enum``: exact NNLS by enumerating the passive sets. For a fixed matrix the solution on
  each subset P of columns is a precomputed linear map of the right-hand side, so one batched matrix
  product gives every candidate; the optimum is the non-negative candidate with the largest projection
  (residual = ‖b‖² − bᵀA x_P). Branch-free, vectorised over designs, bounded time.
* ``nnls``: Lawson–Hanson (:func:`scipy.optimize.nnls`) on the QR-reduced problem, one call per RHS.
* ``lp-l1``: the thesis's linear programme, L1 objective, HiGHS with a time limit (falls back to
  ``enum`` and says so when the limit is hit).
* ``clamped-lsq``: least squares, negative weights clamped to zero (the thesis's rejected baseline).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from station.model.colorimetry import lab_to_linear_srgb
from station.model.domain import FACE_ANGLE_DEG
from station.model.lobe import lobe_brdf_cos, phong_lobe
from station.model.representations import shape_factor
from station.model.shading import design_reflectance, shade_reflectance
from station.render.errors import RenderError, RenderInputError
from station.render.lobe_energy import ENERGY_ROW_WEIGHT as ENERGY_ROW_WEIGHT
from station.render.lobe_energy import PERCEPTUAL_FLOOR as PERCEPTUAL_FLOOR
from station.render.lobe_energy import PERCEPTUAL_POWER as PERCEPTUAL_POWER
from station.render.lobe_energy import _solve_perceptual
from station.render.lobe_energy import conserve_gloss_energy as conserve_gloss_energy
from station.render.lobe_energy import lobe_energies as lobe_energies
from station.render.lobe_solvers import ENUM_MAX_UNKNOWNS as ENUM_MAX_UNKNOWNS
from station.render.lobe_solvers import PINV_RCOND as PINV_RCOND
from station.render.lobe_solvers import _Part, _solve_clamped, _solve_enum, _solve_kkt, _solve_nnls
from station.render.lobes import (
    COLOUR_ALPHAS_DEG,
    GLOSS_ALPHAS_DEG,
    LobeBasis,
    SampleGeometries,
    default_basis,
    sample_geometries,
)
from station.render.weights import LobeWeights

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

__all__ = [
    "METHODS",
    "DesignedBRDF",
    "FitProblem",
    "FitReport",
    "LobeFitError",
    "default_basis",
    "designed_brdf",
    "fit_design",
    "fit_designs",
    "fit_error_de",
    "fit_problem",
]

#: Fit methods by name; the first is the default (chosen from docs/render-fit.png).
METHODS = ("perceptual", "auto", "kkt", "enum", "nnls", "lp-l1", "clamped-lsq")
#: ``auto`` fits batches of at least this many designs with ``kkt``, smaller ones with ``nnls``.
AUTO_BATCH = 16
#: Time limit (s) of one HiGHS solve (thesis §2.4: "a time limit for finding a solution must be set").
LP_TIME_LIMIT_S = 0.05
#: Grid (degrees) of the tabulated reflectance factor ρ(α) of a designed BRDF.
ALPHA_GRID_DEG = np.linspace(0.0, 180.0, 721)
#: Aspecular angles (degrees) at which targets sample ρ(α): every angle of the sample geometries.
TARGET_ALPHAS_DEG = tuple(sorted(set(COLOUR_ALPHAS_DEG) | set(GLOSS_ALPHAS_DEG)))
#: Where the gloss lobe goes: "thesis" fits it with the K_G lobes of eq 2.3.2 (the designed lobe's own
#: form); "cosine" folds it into (N·L)-weighted grey K_DD lobes (eq 2.3.3 form), kept for comparison.
GLOSS_FORMS = ("thesis", "cosine")
#: What the colour fit matches: "brdf" weights the K_DD lobes by N·L, eq 2.3.3 (default); "renderer"
#: weights them by N·V = R·N as the prefiltered renderers evaluate eq 2.5.1. Measured against ground
#: truth (bench.basis_accuracy, docs/render-fit.md) "renderer" is worse in both modes, so it is kept
#: only for that comparison.
TARGETS = ("brdf", "renderer")


class LobeFitError(RenderError):
    """A fit could not be produced (a solver failed in a way no fallback covers)."""


@dataclass(frozen=True)
class DesignedBRDF:
    """A designed BRDF in the form the fitter and ground truth evaluate (module docstring).

    Attributes
    ----------
    reflectance
        (721, 3) reflectance factor ρ(α), linear sRGB, on ALPHA_GRID_DEG (0–180° by 0.25°).
    phong_exponent
        Gloss lobe exponent n (dimensionless).
    specular_albedo
        Gloss lobe albedo ρ_s (dimensionless, grey).
    name
        Label for reports.
    out_of_gamut
        True when some ρ(α) channel is negative (outside the sRGB gamut; weights ≥ 0 cannot reach it).
        Values above 1 are real near specular (bright metallics) and are kept.
    """

    reflectance: NDArray[np.float64] = field(repr=False)
    phong_exponent: float
    specular_albedo: float
    name: str = ""
    out_of_gamut: bool = False

    def rho(self, alpha_deg: NDArray[np.float64]) -> NDArray[np.float64]:
        """Reflectance factor ρ(α) (linear sRGB, shape (..., 3)) by linear interpolation in α (degrees)."""
        a = np.clip(np.asarray(alpha_deg, dtype=float), 0.0, 180.0) * 4.0
        i = np.minimum(a.astype(np.int64), 719)
        t = (a - i)[..., None]
        return self.reflectance[i] * (1.0 - t) + self.reflectance[i + 1] * t

    def gloss_cos(self, cos_alpha: NDArray[np.float64]) -> NDArray[np.float64]:
        """Gloss term of BRDF·cos, ρ_s (n+1)/(2π) max(cos α, 0)^n, sr⁻¹, same shape as *cos_alpha*."""
        return lobe_brdf_cos(self.phong_exponent, self.specular_albedo, cos_alpha)

    def brdf_cos(self, n_dot_l: NDArray[np.float64], cos_alpha: NDArray[np.float64]) -> NDArray[np.float64]:
        """BRDF × (N·L) in sr⁻¹, linear sRGB, shape (..., 3); zero for light below the horizon."""
        alpha = np.degrees(np.arccos(np.clip(cos_alpha, -1.0, 1.0)))
        # the model's reference point-light shading as a reflectance factor, ÷ π for sr⁻¹
        return shade_reflectance(n_dot_l, self.rho(alpha), np.pi * self.gloss_cos(cos_alpha)) / np.pi


def _rgb_table(lab: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.asarray(lab_to_linear_srgb(lab), dtype=float)


def _lobe(gloss_gu: float) -> tuple[float, float]:
    n, rho_s = phong_lobe(gloss_gu)
    return float(n), float(rho_s)


def designed_brdf(design: FaceFlopTravelGloss) -> DesignedBRDF:
    """Tabulate the designed BRDF of *design* (clamped-quadratic colour + Phong gloss lobe)."""
    rgb = design_reflectance(design, np.maximum(ALPHA_GRID_DEG, FACE_ANGLE_DEG))
    n, rho_s = _lobe(float(design.gloss_gu))
    oog = bool(np.any(rgb < 0.0))
    return DesignedBRDF(rgb, n, rho_s, getattr(design, "name", ""), oog)


@dataclass(frozen=True)
class Targets:
    """Sampled designed BRDFs of a batch of designs, the right-hand sides of eq 2.4.2.

    Attributes
    ----------
    rho
        (d, a, 3) reflectance factor at TARGET_ALPHAS_DEG.
    phong_exponent, specular_albedo
        (d,) gloss lobe parameters.
    """

    rho: NDArray[np.float64]
    phong_exponent: NDArray[np.float64]
    specular_albedo: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.rho.shape[0])


def sample_targets(designs: Sequence[FaceFlopTravelGloss]) -> Targets:
    """Sample each design's colour at TARGET_ALPHAS_DEG and its gloss lobe (one colour conversion)."""
    theta = np.maximum(np.asarray(TARGET_ALPHAS_DEG), FACE_ANGLE_DEG)
    face = np.array([d.face for d in designs], dtype=float).reshape(-1, 3)
    flop = np.array([d.flop for d in designs], dtype=float).reshape(-1, 3)
    travel = np.array([np.nan if d.travel_deg is None else d.travel_deg for d in designs], dtype=float)
    # The model's X(θ) = flop + (face − flop)·s(θ)² (eq 3.3.2, station.model.representations.shape_factor),
    # broadcast over designs; a solid (no travel) is its face.
    tc = np.where(np.isnan(travel), 2 * FACE_ANGLE_DEG, travel)[:, None]
    s2 = np.where(np.isnan(travel)[:, None], 1.0, shape_factor(theta[None, :], tc))
    lab = flop[:, None, :] + (face - flop)[:, None, :] * s2[:, :, None]
    n, rho_s = phong_lobe(np.array([float(d.gloss_gu) for d in designs]))
    return Targets(_rgb_table(lab), np.atleast_1d(n), np.atleast_1d(rho_s))


def targets_from_brdfs(brdfs: Sequence[DesignedBRDF]) -> Targets:
    """Targets of already tabulated designed BRDFs."""
    alphas = np.asarray(TARGET_ALPHAS_DEG)
    rho = np.stack([b.rho(alphas) for b in brdfs]) if brdfs else np.zeros((0, alphas.size, 3))
    return Targets(
        rho,
        np.array([b.phong_exponent for b in brdfs], dtype=float),
        np.array([b.specular_albedo for b in brdfs], dtype=float),
    )


# ----------------------------------------------------------------------------------------------------
# Fixed-matrix problems


@dataclass(frozen=True)
class FitProblem:
    """The precomputed fit of one basis over the sample geometries (eq 2.4.2).

    Attributes
    ----------
    basis, geometry, gloss_form
        The lobe basis, the sample geometries and where the gloss lobe goes (GLOSS_FORMS).
    colour
        Part with columns w·(N·L)·[1, cos^E_i α, min(1, 1 + cos α)] (K_D, K_DD,i and, with *fall_off*, K_A)
        over its rows.
    gloss
        ``thesis`` form only: part with columns w·cos^E_i α (K_G,i) over the gloss rows.
    colour_rows, gloss_rows
        Indices into the geometry of each part's rows.
    """

    basis: LobeBasis
    geometry: SampleGeometries
    gloss_form: str
    colour: _Part
    gloss: _Part | None
    colour_rows: NDArray[np.intp]
    gloss_rows: NDArray[np.intp]
    alpha_index: NDArray[np.intp]  # (rows,) index of each geometry row's α in TARGET_ALPHAS_DEG
    fall_off: bool = True

    def _gloss_values(self, t: Targets, rows: NDArray[np.intp]) -> NDArray[np.float64]:
        """Gloss term of BRDF·cos, ρ_s (n+1)/(2π) cos^n α, at *rows*, shape (d, len(rows))."""
        cos_alpha = self.geometry.cos_alpha[rows][None, :]
        return lobe_brdf_cos(t.phong_exponent[:, None], t.specular_albedo[:, None], cos_alpha)

    def colour_b(self, t: Targets) -> NDArray[np.float64]:
        """Weighted RHS of the colour part, shape (d, rows_c, 3)."""
        rows = self.colour_rows
        g = self.geometry
        f = t.rho[:, self.alpha_index[rows], :] * (g.n_dot_l[rows] / np.pi)[None, :, None]
        if self.gloss_form == "cosine":
            f = f + self._gloss_values(t, rows)[:, :, None]
        return f * g.weight[rows][None, :, None]

    @cached_property
    def colour_map(self) -> NDArray[np.float64]:
        """(k, a) map from ρ at TARGET_ALPHAS_DEG to the reduced colour RHS Qᵀb (÷π folded in)."""
        rows, g = self.colour_rows, self.geometry
        scale = g.weight[rows] * g.n_dot_l[rows] / np.pi
        onehot = np.zeros((rows.size, len(TARGET_ALPHAS_DEG)))
        onehot[np.arange(rows.size), self.alpha_index[rows]] = scale
        return self.colour.q.T @ onehot

    def colour_d(self, t: Targets) -> NDArray[np.float64]:
        """Reduced colour RHS Qᵀb, shape (k, d·3) (design-major, channel-minor)."""
        if self.gloss_form == "cosine":
            return np.einsum("rk,drc->kdc", self.colour.q, self.colour_b(t)).reshape(
                self.colour.q.shape[1], -1
            )
        return self.colour_map @ t.rho.transpose(1, 0, 2).reshape(t.rho.shape[1], -1)

    @cached_property
    def _gloss_map(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(m, u) map from the lobe at the u distinct gloss-row angles to Qᵀb, and those cos α (u,)."""
        assert self.gloss is not None  # noqa: S101 - only built for the thesis form
        rows, g = self.gloss_rows, self.geometry
        cos_u, inverse = np.unique(np.clip(g.cos_alpha[rows], 0.0, 1.0).round(12), return_inverse=True)
        onehot = np.zeros((rows.size, cos_u.size))
        onehot[np.arange(rows.size), inverse] = g.weight[rows]
        return self.gloss.q.T @ onehot, cos_u

    def gloss_d(self, t: Targets) -> NDArray[np.float64]:
        """Reduced gloss RHS Qᵀb, shape (m, d)."""
        gmap, cos_u = self._gloss_map
        return gmap @ lobe_brdf_cos(t.phong_exponent[None, :], t.specular_albedo[None, :], cos_u[:, None])

    def gloss_b(self, t: Targets) -> NDArray[np.float64]:
        """Weighted RHS of the ``thesis`` gloss part, shape (d, rows_g, 1)."""
        rows = self.gloss_rows
        g = self.geometry
        return (self._gloss_values(t, rows) * g.weight[rows][None, :])[:, :, None]


def fall_off_factor(cos_alpha: NDArray[np.float64]) -> NDArray[np.float64]:
    """The aspecular fall-off min(1, 1 + cos α) = 1 − (−cos α)₊ (dimensionless, in [0, 1]; weights module doc)."""
    return np.minimum(1.0, 1.0 + np.clip(np.asarray(cos_alpha, dtype=float), -1.0, 1.0))


@lru_cache(maxsize=64)
def fit_problem(
    basis: LobeBasis, gloss_form: str = "thesis", target: str = "brdf", fall_off: bool = True
) -> FitProblem:
    """Build (and cache) the fixed matrices of eq 2.4.2 for *basis* over :func:`sample_geometries`.

    *fall_off*: add the K_A column (the aspecular fall-off term, module docstring); False: the thesis's
    m + 1 colour columns.
    """
    if gloss_form not in GLOSS_FORMS:
        raise RenderInputError("gloss_form", " | ".join(GLOSS_FORMS), gloss_form)
    if target not in TARGETS:
        raise RenderInputError("target", " | ".join(TARGETS), target)
    g = sample_geometries()
    all_rows = np.arange(len(g))
    colour_rows = all_rows if gloss_form == "cosine" else all_rows[~g.gloss]
    gloss_rows = all_rows[g.gloss]
    alphas = np.asarray(TARGET_ALPHAS_DEG)
    alpha_index = np.abs(g.alpha_deg[:, None] - alphas[None, :]).argmin(axis=1)
    w = g.weight[colour_rows]
    dd_cos = g.n_dot_v[colour_rows] if target == "renderer" else g.n_dot_l[colour_rows]
    lobes_c = basis.lobes(g.cos_alpha[colour_rows]) * (w * dd_cos)[:, None]
    columns = [(w * g.n_dot_l[colour_rows])[:, None], lobes_c]
    if fall_off:
        fade = fall_off_factor(g.cos_alpha[colour_rows])
        columns.append((w * g.n_dot_l[colour_rows] * fade)[:, None])
    a_c = np.concatenate(columns, axis=1)
    gloss = None
    if gloss_form == "thesis":
        gloss = _Part.build(g.weight[gloss_rows][:, None] * basis.lobes(g.cos_alpha[gloss_rows]))
    return FitProblem(
        basis, g, gloss_form, _Part.build(a_c), gloss, colour_rows, gloss_rows, alpha_index, fall_off
    )


# ----------------------------------------------------------------------------------------------------
# Solvers: each maps weighted RHS (d, rows, c) of one part to weights (d, k, c) >= 0


def _solve_lp(part: _Part, b: NDArray[np.float64]) -> tuple[NDArray[np.float64], int]:
    """L1 fit min Σ|A x − b| s.t. x ≥ 0 by HiGHS (eq 2.4.2, thesis §2.4); returns (x, fallbacks)."""
    from scipy.optimize import linprog
    from scipy.sparse import csc_array, eye_array, hstack

    rows, k = part.a.shape
    a_eq = hstack([csc_array(part.a), -eye_array(rows), eye_array(rows)], format="csc")
    cost = np.concatenate([np.zeros(k), np.ones(2 * rows)])
    out = np.zeros((b.shape[0], k, b.shape[2]))
    fallbacks = 0
    for i in range(b.shape[0]):
        for c in range(b.shape[2]):
            res = linprog(
                cost,
                A_eq=a_eq,
                b_eq=b[i, :, c],
                bounds=(0, None),
                method="highs",
                options={"time_limit": LP_TIME_LIMIT_S, "presolve": True},
            )
            if res.status == 0 and res.x is not None:
                out[i, :, c] = np.maximum(res.x[:k], 0.0)
            else:
                fallbacks += 1
                out[i, :, c] = _solve_enum(part, part.q.T @ b[i, :, c : c + 1])[:, 0]
    return out, fallbacks


def resolvable_targets(targets: Targets, basis: LobeBasis) -> Targets:
    """The targets with each gloss lobe's exponent capped at the basis's sharpest, E_max.

    No non-negative blend of cos^E_i lobes is sharper than its sharpest lobe, and point samples of a
    lobe sharper than that (a 100 GU design: n = 10⁷) see only its spike at α = 0, which a fit matches
    with the widest lobes (a mirror drawn as haze). Capped, the best stand-in for such a lobe is the
    sharpest basis lobe itself, and :func:`conserve_gloss_energy` keeps its energy ρ_s.
    """
    top = float(max(basis.exponents))
    capped = np.minimum(targets.phong_exponent, top)
    if np.array_equal(capped, targets.phong_exponent):
        return targets
    return Targets(targets.rho, capped, targets.specular_albedo)


@dataclass(frozen=True)
class FitReport:
    """Weights of a batch plus what the fit did.

    Attributes
    ----------
    k_d, k_dd, k_g
        (d, 3), (d, m, 3), (d, m) weights (sr⁻¹).
    k_a
        (d, 3) aspecular fall-off weights K_A (sr⁻¹); None: a fit without the term (zeros).
    method
        Solver used.
    seconds
        Wall time of the solve (excluding the sampling of the designs).
    fallbacks
        LP solves that hit the time limit or failed and were replaced by ``enum``.
    """

    basis: LobeBasis
    k_d: NDArray[np.float64]
    k_dd: NDArray[np.float64]
    k_g: NDArray[np.float64]
    method: str
    seconds: float
    fallbacks: int = 0
    target: str = "brdf"
    k_a: NDArray[np.float64] | None = None

    def weights(self, i: int) -> LobeWeights:
        """The LobeWeights of design *i*."""
        k_a = np.zeros(3) if self.k_a is None else self.k_a[i]
        return LobeWeights(self.basis.exponents, self.k_d[i], self.k_dd[i], self.k_g[i], k_a)


def fit_targets(
    targets: Targets,
    basis: LobeBasis | None = None,
    method: str = METHODS[0],
    gloss_form: str = "thesis",
    target: str = "brdf",
    fall_off: bool = True,
    energy: bool = True,
) -> FitReport:
    """Fit a batch of sampled designs to *basis* (default: the shipped one) with *method*.

    *fall_off*: fit the aspecular fall-off weight K_A too (module docstring); False: the thesis's model.
    *energy*: the gloss lobes reflect exactly ρ_s, a lobe sharper than the basis fitted as its sharpest
    (:func:`resolvable_targets`, :func:`conserve_gloss_energy`); False: the thesis's point-sample fit.
    """
    if method not in METHODS:
        raise RenderInputError("method", " | ".join(METHODS), method)
    basis = default_basis() if basis is None else basis
    prob = fit_problem(basis, gloss_form, target, fall_off)
    if energy:
        targets = resolvable_targets(targets, basis)
    n, m = len(targets), basis.size
    t0 = time.perf_counter()
    fallbacks = 0
    if method == "perceptual":
        x_c, x_g = _solve_perceptual(prob, targets, energy)
    elif method == "lp-l1":
        x_c, fallbacks = _solve_lp(prob.colour, prob.colour_b(targets))
        x_c = x_c.transpose(1, 0, 2)  # (k, d, 3)
    else:
        if method == "auto":
            method = "kkt" if n >= AUTO_BATCH else "nnls"
        solve = {"kkt": _solve_kkt, "enum": _solve_enum, "nnls": _solve_nnls, "clamped-lsq": _solve_clamped}[
            method
        ]
        x_c = solve(prob.colour, prob.colour_d(targets)).reshape(prob.colour.a.shape[1], n, 3)
    if method != "perceptual":
        if prob.gloss is None:
            x_g = np.zeros((n, m))
        elif method == "lp-l1":
            x_g3, f_g = _solve_lp(prob.gloss, prob.gloss_b(targets))
            x_g, fallbacks = x_g3[:, :, 0], fallbacks + f_g
        else:
            x_g = solve(prob.gloss, prob.gloss_d(targets)).T
    if prob.gloss is not None and energy:
        x_g = conserve_gloss_energy(x_g, basis, targets.specular_albedo)
    seconds = time.perf_counter() - t0
    if not (np.all(np.isfinite(x_c)) and np.all(np.isfinite(x_g))):
        raise LobeFitError(f"lobe fit ({method}) produced non-finite weights")
    k_a = x_c[m + 1] if fall_off else None
    k_dd = x_c[1 : m + 1].transpose(1, 0, 2)
    return FitReport(basis, x_c[0], k_dd, x_g, method, seconds, fallbacks, target, k_a)


def fit_designs(
    designs: Sequence[FaceFlopTravelGloss],
    basis: LobeBasis | None = None,
    method: str = METHODS[0],
    gloss_form: str = "thesis",
    target: str = "brdf",
    fall_off: bool = True,
) -> FitReport:
    """Fit every design of a batch (vectorised for ``kkt``, ``enum`` and ``clamped-lsq``)."""
    return fit_targets(sample_targets(designs), basis, method, gloss_form, target, fall_off)


def fit_design(
    design: FaceFlopTravelGloss, basis: LobeBasis | None = None, method: str = "default"
) -> LobeWeights:
    """Fit one design's lobe weights K_D, K_DD,i, K_G,i and the fall-off K_A, all ≥ 0 (eqs 2.4.1–2.4.2).

    Parameters
    ----------
    design
        The face/flop/travel/gloss design.
    basis
        Lobe basis; default: the shipped optimal basis (:func:`default_basis`).
    method
        ``"default"`` (= ``perceptual``) or one of METHODS.
    """
    method = METHODS[0] if method == "default" else method
    return fit_designs([design], basis, method).weights(0)


# ----------------------------------------------------------------------------------------------------
# Fit error (eq 2.3.4's Error(E, B))


def fitted_reflectance(report: FitReport, geometry: SampleGeometries | None = None) -> NDArray[np.float64]:
    """Reflectance factor π·BRDF·cos/(N·L) of the fitted lobes at every sample geometry, (d, rows, 3).

    For ``target="renderer"`` fits the K_DD lobes carry N·V (= R·N, eq 2.5.1) instead of N·L.
    """
    g = sample_geometries() if geometry is None else geometry
    lobes = report.basis.lobes(g.cos_alpha)  # (rows, m)
    dd = lobes * (g.n_dot_v / np.maximum(g.n_dot_l, 1e-9))[:, None] if report.target == "renderer" else lobes
    colour = report.k_d[:, None, :] + np.einsum("rm,dmc->drc", dd, report.k_dd)
    if report.k_a is not None:
        colour = colour + fall_off_factor(g.cos_alpha)[None, :, None] * report.k_a[:, None, :]
    gloss = np.einsum("rm,dm->dr", lobes, report.k_g) / np.maximum(g.n_dot_l, 1e-9)[None, :]
    return np.pi * (colour + gloss[:, :, None])


def designed_reflectance(
    brdfs: Sequence[DesignedBRDF], geometry: SampleGeometries | None = None
) -> NDArray[np.float64]:
    """Reflectance factor π·f of the designed BRDFs at every sample geometry, (d, rows, 3)."""
    g = sample_geometries() if geometry is None else geometry
    inv_nl = 1.0 / np.maximum(g.n_dot_l, 1e-9)
    return np.stack(
        [b.rho(g.alpha_deg) + (np.pi * b.gloss_cos(g.cos_alpha) * inv_nl)[:, None] for b in brdfs]
    )


def fit_error_de(brdfs: Sequence[DesignedBRDF], report: FitReport) -> NDArray[np.float64]:
    """RMS CIEDE2000 over the sample geometries between designed and fitted reflectance factor, (d,).

    This is Error(E, B_i) of eq 2.3.4: what a multi-angle instrument would read at each geometry
    (colour and gloss together), compared as CIE Lab (D65/10°).
    """
    from station.model.colorimetry import linear_srgb_to_lab

    return fit_error_de_lab(linear_srgb_to_lab(designed_reflectance(brdfs)), report)


def fit_error_de_lab(reference_lab: NDArray[np.float64], report: FitReport) -> NDArray[np.float64]:
    """:func:`fit_error_de` against precomputed reference Lab (d, rows, 3) (the basis search reuses it)."""
    from station.model.colorimetry import linear_srgb_to_lab
    from station.model.difference import delta_e

    de = delta_e(reference_lab, linear_srgb_to_lab(fitted_reflectance(report)), "cie2000")
    return np.sqrt(np.mean(de**2, axis=-1))
