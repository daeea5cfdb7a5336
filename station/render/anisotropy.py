"""Anisotropic gloss by off-specular samples weighted by Ward's model (thesis §2.5.3, eqs 2.5.4–2.5.7).

Ward's anisotropic Gaussian (eq 2.5.4; Ward 1992), for unit L, V, N, tangent X, bitangent Y, half
vector H:

    f(L, V)·(L·N) = P_s (L·N)/√((L·N)(V·N)) · 1/(4π α_x α_y) · exp(−2 [(H·X/α_x)² + (H·Y/α_y)²] / (1 + H·N))

(the thesis prints the exponent without the α's; Ward's model divides each slope by its α, which is
what makes α the slope spread, so that form is used here; docs/design.md erratum 6).

Rendering (eqs 2.5.5–2.5.7): the isotropic Ward lobe of width α_x is first fitted once with the cosine
lobes (non-negative least squares over in-plane aspecular angles at 45° incidence, P_s = 1), giving
S(R) = Σ_i w_i h_i(R·N) C_i(R) / Σ_i w_i, the normalised blend of prefiltered maps (w_i the map weights,
h_i the horizon factors of the wide lobes; lobes whose lights were taken out of their maps add them back
exactly: the gloss terms exactly as the lobe renderers shade them). The normal is
then tilted by J offsets θ_j ∈ [−2.5 α_s, 2.5 α_s] about the principal direction X, the view is
reflected about each tilted normal to give R_j, and

    colour = P_s · A(N, V) · Σ_j W_j S(R_j) / Σ_j W_j                              (eq 2.5.7, normalised)
    W_j = (R_j·N)/√((R_j·N)(V·N)) · exp(−2 sin²θ_j / (α_s² (1 + cos θ_j)))        (eq 2.5.6, α_y → α_s)

with α_s = √(α_y² − α_x²). Each sample S(R_j) is itself a lobe of width α_x in every direction, so
weighting the samples with α_y itself (the thesis's W_j = Ward(R_j, N, V)) widens the highlight across X
to √(α_x² + α_y²); the spread α_s of the weights makes the sum's width α_y, and in the isotropic limit
α_x = α_y every θ_j is 0 and eq 2.5.7 is eq 2.5.5 exactly, whatever J is. (On the booth, sphere 32²,
α = (0.05, 0.25) both weightings give mean ΔE00 0.87 against the brute force from 15 samples on;
α = (0.1, 0.15): 1.02 with α_s, 1.21 with α_y; α = (0.08, 0.08): 0.84 with α_s, 1.14 with α_y.)

The division by Σ W_j (not in the thesis) separates the shape of the highlight from its energy; the
energy is the Ward lobe's directional albedo A(N, V) = ∫ f(ω, V)(N·ω) dω, computed per pixel by a
16 × 16 quadrature over half-vector slopes (p, q) ∈ [−3α_x, 3α_x] × [−3α_y, 3α_y] with
dω = 4(V·H) dp dq / (1 + p² + q²)^{3/2} (the GL renderer reads the same quadrature from a table over
N·V and the azimuth of V, :func:`albedo_table`). A constant environment then renders P_s·A·L exactly,
whatever J is, as the brute-force integral does.

Energy. Eq 2.5.4 as printed reflects A(N, V) ≈ N·V of P_s (its 1/√((L·N)(V·N)) and the half-vector
Jacobian 4 V·H leave a factor V·H ≈ N·V at the peak), so Ward's lobe dims towards grazing views, while a
design's own gloss lobes reflect their fitted energy Σ w_G,i at every view. ``energy="ward"`` (the
thesis's model, compared with :func:`ward_truth`) keeps A; ``energy="design"`` sets A = 1, the lobe
f/A(N, V) whose albedo is P_s at every view: the anisotropy reshapes a design's gloss and keeps its
energy, and in the isotropic limit it is the design's lobe path (eq 2.5.5) whatever J is. The GL
renderer renders designs with ``"design"``. Quality vs sample count is measured against a
brute-force integral of eq 2.5.4 over the environment (:func:`ward_truth`) in tests, in
``bench/anisotropy.py`` and in ``station reproduce --figure 2.10``.

The design parameters (α_x, α_y, direction) are :class:`station.model.anisotropy.Anisotropy`;
:meth:`WardLobe.from_design` makes the lobe of a design whose gloss energy is P_s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from station.model.anisotropy import ANISOTROPY_RANGES, Anisotropy
from station.render.camera import Camera
from station.render.cubemap import face_directions, sample_cube, texel_solid_angles
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.numpy_renderer import BACKGROUND, gbuffer, horizon_table, light_terms, lobe_factors
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
        lo, hi = ANISOTROPY_RANGES["alpha_x"]
        if not lo <= self.alpha_x <= hi:
            raise RenderInputError("alpha_x", f"{lo} <= alpha_x <= {hi}", self.alpha_x)
        hi_y = ANISOTROPY_RANGES["alpha_y"][1]
        if not self.alpha_x <= self.alpha_y <= hi_y:
            raise RenderInputError("alpha_y", f"alpha_x <= alpha_y <= {hi_y}", self.alpha_y)
        if min(self.p_s) < 0:
            raise RenderInputError("p_s", "non-negative RGB", self.p_s)

    @classmethod
    def from_design(cls, anisotropy: Anisotropy, p_s: float | tuple[float, float, float] = 1.0) -> WardLobe:
        """The lobe of a design's anisotropy with specular colour *p_s* (grey or RGB)."""
        ps = (float(p_s),) * 3 if isinstance(p_s, (int, float)) else tuple(float(c) for c in p_s)
        return cls(ps, anisotropy.alpha_x, anisotropy.alpha_y, anisotropy.tangent)  # type: ignore[arg-type]

    @property
    def spread(self) -> float:
        """α_s = √(α_y² − α_x²), the slope spread of the sample weights (module docstring)."""
        return float(np.sqrt(max(self.alpha_y**2 - self.alpha_x**2, 0.0)))


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


def sample_offsets(lobe: WardLobe, samples: int) -> np.ndarray:
    """The J normal tilts θ_j (radians) about X: evenly over ±2.5 α_s, one at 0 for J = 1 (eq 2.5.7)."""
    if not (isinstance(samples, int) and not isinstance(samples, bool) and 1 <= samples <= 1024):
        raise RenderInputError("samples", "integer 1..1024", samples)
    if samples == 1:
        return np.zeros(1)
    return np.linspace(-2.5, 2.5, samples) * lobe.spread


def sample_weight(theta: float, r_dot_n: np.ndarray, v_dot_n: np.ndarray, spread: float) -> np.ndarray:
    """W_j of the module docstring (eq 2.5.6 with α_s); 0 where R_j is below the horizon."""
    ok = r_dot_n > 0
    cosine = np.where(ok, r_dot_n, 0.0) / np.sqrt(np.where(ok, r_dot_n * v_dot_n, 1.0))
    if spread <= 0.0:
        return cosine
    return cosine * np.exp(-2.0 * np.sin(theta) ** 2 / (spread**2 * (1.0 + np.cos(theta))))


def lobe_blend(
    basis: PrefilteredBasis, w: np.ndarray, r: np.ndarray, n: np.ndarray, table: np.ndarray
) -> np.ndarray:
    """S(R) = Σ_i w_i h_i(R·N) C_i(R) / Σ_i w_i (P, 3): the lobes' gloss terms as the lobe renderers
    shade them (horizon factors h_i of *table*, :func:`station.render.numpy_renderer.horizon_table`,
    and the lights of wide lobes added exactly, :func:`station.render.numpy_renderer.light_terms`)."""
    out = np.zeros(r.shape[:-1] + (3,))
    _, h = lobe_factors(table, np.sum(r * n, axis=-1))
    for i, c in enumerate(basis.cubes):
        if w[i] <= 0:
            continue
        out += w[i] * h[:, i : i + 1] * sample_cube(c, r)
        lights = light_terms(basis, i, n, r)
        if lights is not None:
            out += w[i] * lights[0]
    return out / w.sum()


#: Energy conventions of the anisotropic lobe (module docstring).
ENERGIES = ("ward", "design")


def shade_anisotropic(
    basis: PrefilteredBasis,
    lobe: WardLobe,
    samples: int,
    normals: np.ndarray,
    views: np.ndarray,
    energy: str = "ward",
) -> np.ndarray:
    """Linear radiance (P, 3) of the anisotropic gloss alone at unit *normals*, *views* (P, 3) (eq 2.5.7);
    *energy*: one of :data:`ENERGIES`."""
    if energy not in ENERGIES:
        raise RenderInputError("energy", " | ".join(ENERGIES), energy)
    offsets = sample_offsets(lobe, samples)
    w = fit_isotropic(basis.exponents, lobe.alpha_x)
    n = np.asarray(normals, dtype=np.float64)
    v = np.asarray(views, dtype=np.float64)
    x, y = _frames(n, np.asarray(lobe.tangent, dtype=np.float64))
    vn = np.sum(v * n, axis=-1)
    acc = np.zeros_like(n)
    wsum = np.zeros(n.shape[0])
    table = horizon_table(basis.exponents)
    for theta in offsets:
        # rotate N about X by θ: N_j = cos θ N + sin θ (X × N) = cos θ N − sin θ Y
        nj = np.cos(theta) * n - np.sin(theta) * y
        rj = 2.0 * np.sum(nj * v, axis=-1, keepdims=True) * nj - v
        wj = sample_weight(float(theta), np.sum(rj * n, axis=-1), vn, lobe.spread)
        acc += wj[:, None] * lobe_blend(basis, w, rj, n, table)
        wsum += wj
    albedo = ward_albedo(lobe, n, v, x, y) if energy == "ward" else np.ones(n.shape[0])
    return np.asarray(lobe.p_s) * (albedo / np.maximum(wsum, 1e-30))[:, None] * acc


def render_anisotropic(
    scene: Scene,
    basis: PrefilteredBasis,
    lobe: WardLobe,
    samples: int,
    width: int,
    height: int,
    energy: str = "ward",
) -> np.ndarray:
    """Linear radiance (H, W, 3) of the anisotropic gloss alone (eq 2.5.7, normalised), J = *samples*."""
    sample_offsets(lobe, samples)  # validates *samples* before any work
    g = gbuffer(scene, width, height)
    img = np.full((height, width, 3), BACKGROUND, np.float64)
    img[g.mask] = shade_anisotropic(basis, lobe, samples, g.normal[g.mask], g.view[g.mask], energy)
    return img.astype(np.float32)


#: Albedo table of the GL renderer: N·V from ALBEDO_COS_MIN to 1 (rows) × azimuth of V from X, 0..90°.
ALBEDO_COS_MIN = 0.02
ALBEDO_TABLE_SIZE = (64, 16)


def albedo_table(lobe: WardLobe) -> np.ndarray:
    """A(N, V) of :func:`ward_albedo` on a (azimuth, N·V) grid, float32 (ALBEDO_TABLE_SIZE[::-1]).

    Column k holds N·V = c0 + (1 − c0) k/(n − 1), row l the azimuth φ = 90° l/(n_φ − 1) of V's tangent
    component from X; by the lobe's symmetry in ±X and ±Y that covers every view."""
    n_cos, n_phi = ALBEDO_TABLE_SIZE
    c = ALBEDO_COS_MIN + (1.0 - ALBEDO_COS_MIN) * np.linspace(0.0, 1.0, n_cos)
    phi = np.linspace(0.0, np.pi / 2, n_phi)
    cc, pp = np.meshgrid(c, phi)
    s = np.sqrt(1.0 - cc**2)
    v = np.stack([s * np.cos(pp), s * np.sin(pp), cc], axis=-1).reshape(-1, 3)
    k = v.shape[0]
    n = np.broadcast_to([0.0, 0.0, 1.0], (k, 3))
    x = np.broadcast_to([1.0, 0.0, 0.0], (k, 3))
    y = np.broadcast_to([0.0, 1.0, 0.0], (k, 3))
    return ward_albedo(lobe, n, v, x, y).reshape(n_phi, n_cos).astype(np.float32)


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


def ward_truth_pixels(
    src_cube: np.ndarray, lobe: WardLobe, normals: np.ndarray, views: np.ndarray
) -> np.ndarray:
    """Brute-force ∫ L(ω) f(ω, V)(N·ω) dω of eq 2.5.4 over every texel of *src_cube*, per pixel (P, 3)."""
    s = src_cube.shape[1]
    dirs = face_directions(s).reshape(-1, 3)
    rad = src_cube.reshape(-1, 3) * np.tile(texel_solid_angles(s).reshape(-1), 6)[:, None]
    n = np.asarray(normals, dtype=np.float64)
    v = np.asarray(views, dtype=np.float64)
    x, y = _frames(n, np.asarray(lobe.tangent, dtype=np.float64))
    out = np.empty((n.shape[0], 3))
    for i in range(0, n.shape[0], 64):
        sl = slice(i, i + 64)
        f = ward_cos(lobe, dirs[None], n[sl, None], v[sl, None], x[sl, None], y[sl, None])
        out[sl] = f @ rad
    return np.asarray(lobe.p_s) * out


def ward_truth(scene: Scene, src_cube: np.ndarray, lobe: WardLobe, width: int, height: int) -> np.ndarray:
    """Brute-force ∫ L(ω) f(ω, V)(N·ω) dω of eq 2.5.4 over every texel of *src_cube* (small sizes only)."""
    g = gbuffer(scene, width, height)
    img = np.full((height, width, 3), BACKGROUND, np.float64)
    img[g.mask] = ward_truth_pixels(src_cube, lobe, g.normal[g.mask], g.view[g.mask])
    return img.astype(np.float32)


#: Sample counts of the error-against-samples sweep (odd: one sample on the specular direction).
SWEEP_COUNTS = (1, 3, 5, 7, 9, 11, 15, 21, 25, 31, 35, 41, 51, 61, 71, 81)
#: The scene of the sweep: the sphere seen slightly from above.
SWEEP_SCENE = Scene("sphere", camera=Camera((0.0, 0.5, 5.0), (0.0, 0.0, 0.0), fov_deg=28))
#: The lobe basis of the sweep (normalised cosine lobes spanning the anisotropic widths).
SWEEP_EXPONENTS = (1.0, 4.0, 16.0, 64.0, 256.0, 1024.0, 4096.0)


@dataclass(frozen=True)
class SampleSweep:
    """Error of the sampled reconstruction against the brute-force integral, per sample count.

    ΔE00 between tone-mapped display colours (ACES curve, Lab of the decoded sRGB) per object pixel;
    ``images`` holds the linear radiance (H, W, 3) of the counts asked for, ``truth`` the reference."""

    samples: tuple[int, ...]
    mean_de: tuple[float, ...]
    p95_de: tuple[float, ...]
    images: dict[int, np.ndarray]
    truth: np.ndarray
    seconds: float

    def converged(self, slack: float = 0.1) -> int:
        """Fewest samples whose mean ΔE00 is within *slack* of the most-sampled count's."""
        floor = self.mean_de[-1]
        return next(s for s, e in zip(self.samples, self.mean_de, strict=True) if e <= floor + slack)

    def meets(self, mean_bar: float, p95_bar: float) -> int | None:
        """Fewest samples meeting both bars (mean and 95th percentile ΔE00), None when none does."""
        for s, m, p in zip(self.samples, self.mean_de, self.p95_de, strict=True):
            if m <= mean_bar and p <= p95_bar:
                return s
        return None


def point_light_environment(
    direction: tuple[float, float, float] = (0.35, 0.55, 0.76),
    radius_deg: float = 2.0,
    flux: float = 4.0,
    ambient: float = 0.03,
    height: int = 128,
) -> Environment:
    """One small bright disc (the thesis's Fig 2.10 "one point light source") over a dim constant sky:
    radiance *ambient* everywhere plus *flux* / (disc solid angle) inside the disc."""
    from station.render.cubemap import equirect_directions

    d = equirect_directions(height, 2 * height)
    c = np.asarray(direction, dtype=np.float64)
    c /= np.linalg.norm(c)
    inside = d @ c > np.cos(np.radians(radius_deg))
    omega = 2.0 * np.pi * (1.0 - np.cos(np.radians(radius_deg)))
    img = np.full(d.shape, ambient) + inside[..., None] * (flux / omega)
    return Environment("point light", img.astype(np.float32))


def sample_sweep(
    environment: Environment,
    lobe: WardLobe,
    counts: tuple[int, ...] = SWEEP_COUNTS,
    size: int = 48,
    truth_face: int = 64,
    keep: tuple[int, ...] = (),
) -> SampleSweep:
    """Mean and 95th-percentile ΔE00 of eq 2.5.7 with each sample count against :func:`ward_truth`
    (thesis's energy, ``energy="ward"``) on :data:`SWEEP_SCENE` at *size*², NumPy prefiltered basis of
    :data:`SWEEP_EXPONENTS`; the truth integrates a *truth_face*² cube of the environment."""
    import time

    from station.model.colorimetry import linear_srgb_to_lab
    from station.model.difference import delta_e
    from station.render import prefilter, tonemap

    t0 = time.perf_counter()
    basis = prefilter.prefilter_basis(environment, SWEEP_EXPONENTS, engine="numpy")
    g = gbuffer(SWEEP_SCENE, size, size)
    truth = ward_truth(SWEEP_SCENE, environment.to_cube(truth_face), lobe, size, size)

    def lab(x: np.ndarray) -> np.ndarray:
        return linear_srgb_to_lab(tonemap.srgb_decode(tonemap.to_display(x) / 255.0))

    ref = lab(truth[g.mask])
    means, p95s, images = [], [], {}
    for j in counts:
        img = np.full((size, size, 3), BACKGROUND, np.float32)
        img[g.mask] = shade_anisotropic(basis, lobe, j, g.normal[g.mask], g.view[g.mask])
        d = delta_e(lab(img[g.mask]), ref, "cie2000")
        means.append(float(d.mean()))
        p95s.append(float(np.percentile(d, 95)))
        if j in keep:
            images[j] = img
    return SampleSweep(tuple(counts), tuple(means), tuple(p95s), images, truth, time.perf_counter() - t0)
