"""Anisotropic gloss by off-specular samples weighted by Ward's model (thesis §2.5.3, eqs 2.5.4–2.5.7).

Ward's anisotropic Gaussian (eq 2.5.4; Ward 1992), for unit L, V, N, tangent X, bitangent Y, half
vector H:

    f(L, V)·(L·N) = P_s (L·N)/√((L·N)(V·N)) · 1/(4π α_x α_y) · exp(−2 [(H·X/α_x)² + (H·Y/α_y)²] / (1 + H·N))

(the thesis prints the exponent without the α's; Ward's model divides each slope by its α, which is
what makes α the slope spread, so that form is used here; docs/design.md erratum 6).

Rendering (eqs 2.5.5–2.5.7): the isotropic Ward lobe of width α_x is first fitted once with the cosine
lobes (non-negative least squares over in-plane aspecular angles at 45° incidence, P_s = 1), giving
S(R) = Σ_i w_i C_i(R) / Σ_i w_i, the normalised blend of prefiltered maps (w_i the map weights). The
normal is then tilted by J offsets θ_j ∈ [−2.5 α_y, 2.5 α_y] about the principal direction X, the view
is reflected about each tilted normal to give R_j, and

    colour = P_s · A(N, V) · Σ_j W_j S(R_j) / Σ_j W_j,   W_j = Ward(R_j, N, V)   (eq 2.5.7, normalised)

The division by Σ W_j (not in the thesis) separates the shape of the highlight from its energy; the
energy is the Ward lobe's directional albedo A(N, V) = ∫ f(ω, V)(N·ω) dω, computed per pixel by a
16 × 16 quadrature over half-vector slopes (p, q) ∈ [−3α_x, 3α_x] × [−3α_y, 3α_y] with
dω = 4(V·H) dp dq / (1 + p² + q²)^{3/2}. A constant environment then renders P_s·A·L exactly,
whatever J is, as the brute-force integral does. Quality vs
sample count is measured against a brute-force integral of eq 2.5.4 over the environment
(:func:`ward_truth`) in tests and docs/render.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from station.render.cubemap import face_directions, sample_cube, texel_solid_angles
from station.render.errors import RenderInputError
from station.render.numpy_renderer import BACKGROUND, gbuffer
from station.render.prefilter import PrefilteredBasis
from station.render.shapes import Scene


@dataclass(frozen=True)
class WardLobe:
    """Anisotropic Ward parameters: specular colour P_s (3,), slopes α_x ≤ α_y, world tangent hint."""

    p_s: tuple[float, float, float]
    alpha_x: float
    alpha_y: float
    tangent: tuple[float, float, float] = (1.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not 0.005 <= self.alpha_x <= 0.5:
            raise RenderInputError("alpha_x", "0.005 <= alpha_x <= 0.5", self.alpha_x)
        if not self.alpha_x <= self.alpha_y <= 1.0:
            raise RenderInputError("alpha_y", "alpha_x <= alpha_y <= 1", self.alpha_y)
        if min(self.p_s) < 0:
            raise RenderInputError("p_s", "non-negative RGB", self.p_s)


def ward_cos(
    lobe: WardLobe, light: np.ndarray, normal: np.ndarray, view: np.ndarray, x: np.ndarray, y: np.ndarray
) -> np.ndarray:
    """Grey Ward BRDF × (L·N) with P_s = 1 (eq 2.5.4), broadcasting over leading axes; 0 below horizon."""
    ln = np.sum(light * normal, axis=-1)
    vn = np.sum(view * normal, axis=-1)
    ok = (ln > 0) & (vn > 0)
    h = light + view
    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-30)
    hx = np.sum(h * x, axis=-1) / lobe.alpha_x
    hy = np.sum(h * y, axis=-1) / lobe.alpha_y
    hn = np.sum(h * normal, axis=-1)
    val = (
        np.where(ok, ln, 0.0)
        / np.sqrt(np.where(ok, ln * vn, 1.0))
        / (4 * np.pi * lobe.alpha_x * lobe.alpha_y)
        * np.exp(-2.0 * (hx * hx + hy * hy) / (1.0 + hn))
    )
    return np.where(ok, val, 0.0)


def fit_isotropic(exponents: tuple[float, ...], alpha: float) -> np.ndarray:
    """Map weights w_i ≥ 0 blending normalised lobe maps into the isotropic Ward lobe of slope α."""
    inc = np.radians(45.0)
    n = np.array([0.0, 0.0, 1.0])
    light = np.array([np.sin(inc), 0.0, np.cos(inc)])
    mirror = np.array([-np.sin(inc), 0.0, np.cos(inc)])
    e1 = np.array([np.cos(inc), 0.0, np.sin(inc)])
    asp = np.radians(np.linspace(0.0, min(60.0, np.degrees(6 * alpha) + 2.0), 120))
    views = np.cos(asp)[:, None] * mirror + np.sin(asp)[:, None] * e1
    iso = WardLobe((1.0, 1.0, 1.0), alpha, alpha)
    target = ward_cos(iso, light, n, views, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    e = np.asarray(exponents)
    a = np.cos(asp)[:, None] ** e[None, :] * ((e + 1) / (2 * np.pi))[None, :]  # normalised lobes
    w, _ = nnls(a * np.sin(asp + 1e-3)[:, None] ** 0.5, target * np.sin(asp + 1e-3) ** 0.5)
    if w.sum() <= 0:
        raise RenderInputError("alpha", "a slope some basis lobe can represent", alpha)
    return w


def _frames(normal: np.ndarray, hint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    x = hint - np.sum(hint * normal, axis=-1, keepdims=True) * normal
    bad = np.linalg.norm(x, axis=-1) < 1e-6
    alt = np.array([0.0, 1.0, 0.0]) - normal[..., 1:2] * normal
    x = np.where(bad[..., None], alt, x)
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    return x, np.cross(normal, x)


def render_anisotropic(
    scene: Scene, basis: PrefilteredBasis, lobe: WardLobe, samples: int, width: int, height: int
) -> np.ndarray:
    """Linear radiance (H, W, 3) of the anisotropic gloss alone (eq 2.5.7, normalised), J = *samples*."""
    if not (isinstance(samples, int) and 1 <= samples <= 1024):
        raise RenderInputError("samples", "integer 1..1024", samples)
    w = fit_isotropic(basis.exponents, lobe.alpha_x)
    g = gbuffer(scene, width, height)
    n, v = g.normal[g.mask], g.view[g.mask]
    x, y = _frames(n, np.asarray(lobe.tangent, dtype=np.float64))
    offsets = np.linspace(-2.5, 2.5, samples) * lobe.alpha_y if samples > 1 else np.zeros(1)
    acc = np.zeros_like(n)
    wsum = np.zeros(n.shape[0])
    for theta in offsets:
        # rotate N about X by θ: N_j = cos θ N + sin θ (X × N) = cos θ N − sin θ Y
        nj = np.cos(theta) * n - np.sin(theta) * y
        rj = 2.0 * np.sum(nj * v, axis=-1, keepdims=True) * nj - v
        wj = ward_cos(lobe, rj, n, v, x, y)
        s = sum(w[i] * sample_cube(c, rj) for i, c in enumerate(basis.cubes) if w[i] > 0) / w.sum()
        acc += wj[:, None] * s
        wsum += wj
    img = np.full((height, width, 3), BACKGROUND, np.float64)
    albedo = ward_albedo(lobe, n, v, x, y)
    img[g.mask] = np.asarray(lobe.p_s) * (albedo / np.maximum(wsum, 1e-30))[:, None] * acc
    return img.astype(np.float32)


def ward_albedo(
    lobe: WardLobe, n: np.ndarray, v: np.ndarray, x: np.ndarray, y: np.ndarray, grid: int = 16
) -> np.ndarray:
    """Directional albedo ∫ f(ω, V)(N·ω) dω (P_s = 1) per row of n, v, x, y (see module doc)."""
    ps = (np.arange(grid) + 0.5) / grid * 6.0 - 3.0
    total = np.zeros(n.shape[0])
    dp, dq = 6.0 * lobe.alpha_x / grid, 6.0 * lobe.alpha_y / grid
    for a in ps * lobe.alpha_x:
        for b in ps * lobe.alpha_y:
            h = n + a * x + b * y
            h /= np.linalg.norm(h, axis=-1, keepdims=True)
            vh = np.sum(v * h, axis=-1)
            light = 2.0 * vh[:, None] * h - v
            jac = 4.0 * np.maximum(vh, 0.0) * dp * dq / (1.0 + a * a + b * b) ** 1.5
            total += ward_cos(lobe, light, n, v, x, y) * jac
    return total


def ward_truth(scene: Scene, src_cube: np.ndarray, lobe: WardLobe, width: int, height: int) -> np.ndarray:
    """Brute-force ∫ L(ω) f(ω, V)(N·ω) dω of eq 2.5.4 over every texel of *src_cube* (small sizes only)."""
    s = src_cube.shape[1]
    dirs = face_directions(s).reshape(-1, 3)
    rad = src_cube.reshape(-1, 3) * np.tile(texel_solid_angles(s).reshape(-1), 6)[:, None]
    g = gbuffer(scene, width, height)
    n, v = g.normal[g.mask], g.view[g.mask]
    x, y = _frames(n, np.asarray(lobe.tangent, dtype=np.float64))
    out = np.empty((n.shape[0], 3))
    for i in range(0, n.shape[0], 64):
        sl = slice(i, i + 64)
        f = ward_cos(lobe, dirs[None], n[sl, None], v[sl, None], x[sl, None], y[sl, None])
        out[sl] = f @ rad
    img = np.full((height, width, 3), BACKGROUND, np.float64)
    img[g.mask] = np.asarray(lobe.p_s) * out
    return img.astype(np.float32)
