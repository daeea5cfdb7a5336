"""Flake sparkle in the renderer: scale, level of detail, and the shader's uniforms.

The flake layer's parameters are :class:`station.model.flakes.FlakeLayer`. Per pixel the GL renderer
(``shaders/render.frag.glsl``) and the NumPy renderer add the zero-mean sparkle

    tint · reflectance · Σ_k w_k (L_sharp(R_m,k) − C_E(R))

over two levels k of a fixed hierarchy of surface cells (:func:`flake_levels`, in the manner of
Zirr & Kaplanyan 2016's multiscale glints): level k has cubic cells of side s·2^k (s the flake size)
fixed in world space, which is the objects' own space (shapes and meshes never move; the camera and the
environment do), so the sparkle sticks to the surface while orbiting or dollying. Each cell hashes
(pcg3d) to one random flake normal m about the shading normal with the layer's spread, and, where a cell
holds n_k = density · (s·2^k)² < 1 flakes on average, to whether it holds one (probability n_k). The
lattice is turned against the scene's axes (LATTICE_ROTATION), and each cell's term is weighted by a
smooth bump b about the cell's centre that vanishes on its faces (:func:`flake_window`): a glint is a soft
spot a few pixels wide and the sparkle is continuous from cell to cell. The pixel uses the level
λ = log2(CELL_PIXELS · footprint / s) (footprint: the pixel's side on the surface, divided by √(N·V)),
blended with the next coarser level by the fraction of λ, with weights

    w_k = present_k b_k (1 − f) / √max(1, n_k) / √((1 − f)² + f²),   w_{k+1} likewise with f,

so the sparkle's variance stays that of N flakes at every distance and the blend changes smoothly with
distance. R_m,k is the view mirrored about level k's flake normal, L_sharp the sharpest prefiltered map
(the environment with its sun and lights), C_E(R) the expected flake reflection: the sharpest map prefiltered
with the Phong lobe of the flakes' reflected spread, E ≈ 1/(2σ)² (:func:`flake_mean_cube`), tint the paint's directionally diffuse colour Σ w_DD,i.
Each term has zero mean, so the colour averaged over an area is the design's
(:func:`station.model.flakes.sparkle_amplitude`), and with distance the amplitude 1/√n_k falls and the
pixel converges to it, except where the sparkle would darken a pixel by more than the flakes' share
(reflectance × the pixel's radiance): there it is clipped (beside the sun's reflection, where the expected
flake reflection holds the sun and a flake that misses it reflects sky), a small brightening of those
pixels.

Scale: one scene unit is UNIT_MM millimetres (the shapes are desk-size models: the speed shape is 24 cm
long). Level of detail (:func:`flake_lod`): flakes smaller than a pixel are averaged; when the sparkle
amplitude 1/√N of a pixel falls below SPARKLE_MIN the layer is switched off, and the choice says why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from station.model.flakes import FlakeLayer, sparkle_amplitude
from station.render.camera import Camera

#: Millimetres per scene unit.
UNIT_MM = 100.0
#: Pixel footprints per side of the finest cell level a pixel uses: cells four pixels wide or more, whose
#: glint bump (GLINT_RADIUS, below) is two pixels in radius or more, so a glint is a few pixels wide and a
#: sub-pixel move of the camera shifts it instead of re-rolling it (with cells of two pixels and a hard
#: cell edge, a pixel sample half a pixel away fell in another cell for a quarter of the pixels).
CELL_PIXELS = 4.0
#: Sparkle amplitude 1/√N below which the layer is switched off (2 %: under ~0.5 ΔE00 on a bright glint).
SPARKLE_MIN = 0.02


def _lattice_rotation(ax: float, ay: float, az: float) -> np.ndarray:
    """R_z(az) R_y(ay) R_x(ax), angles in radians."""
    cx, sx = math.cos(ax), math.sin(ax)
    cy, sy = math.cos(ay), math.sin(ay)
    cz, sz = math.cos(az), math.sin(az)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


#: The cell lattice's axes in the scene's frame (rows; a fixed generic rotation, 0.9, 0.7, 0.5 rad about
#: x, y, z): a surface at a constant scene coordinate (a flat panel) cuts the cells at every depth instead
#: of all at one, so the glint window below samples its whole range on every surface.
LATTICE_ROTATION = _lattice_rotation(0.9, 0.7, 0.5)
#: Radius of a glint in cell sides: a cell's flake term is weighted by the bump (1 − |x|²/r²)² about the
#: cell's centre (x its offset in cell sides), which is zero on the cell's faces, so the sparkle is
#: continuous across cells (a glint is a soft spot a few pixels wide, and a sub-pixel move of the camera or
#: of a pixel's sample changes it a little instead of switching to another cell).
GLINT_RADIUS = 0.5
#: 1/√E[bump²] over a cell (E = 4π r³ ∫₀¹ (1 − u²)⁴ u² du = 4π r³ · 1024/27720): the weighted term
#: keeps the variance of its cell's flakes on average, and, as the bump multiplies a zero-mean term that
#: does not depend on the flake normal, its mean stays zero.
WINDOW_NORM = 1.0 / math.sqrt(4.0 * math.pi * GLINT_RADIUS**3 * 1024.0 / 27720.0)


@dataclass(frozen=True)
class FlakeChoice:
    """What the level of detail chose for the flakes of one frame."""

    on: bool
    pixel_mm: float  # footprint of one pixel at the camera's target distance
    flakes_per_pixel: float
    amplitude: float  # 1/√N
    reason: str


def pixel_footprint_mm(camera: Camera, height: int, distance: float | None = None) -> float:
    """Side of one pixel on a surface facing the camera at *distance* (default: eye to target), mm."""
    d = float(np.linalg.norm(np.subtract(camera.target, camera.eye))) if distance is None else distance
    return 2.0 * d * math.tan(math.radians(camera.fov_deg) / 2.0) / height * UNIT_MM


def flake_lod(flakes: FlakeLayer | None, camera: Camera, height: int) -> FlakeChoice:
    """Flakes on or off for this view (module docstring), with the numbers and the reason."""
    px = pixel_footprint_mm(camera, height)
    if flakes is None:
        return FlakeChoice(False, px, 0.0, 0.0, "no flake layer")
    cell = max(px, flakes.size_um / 1000.0)
    n = flakes.flakes_in(cell * cell)
    amp = sparkle_amplitude(flakes, cell * cell)
    size = "larger than a pixel" if flakes.size_um / 1000.0 >= px else "smaller than a pixel"
    if amp < SPARKLE_MIN:
        return FlakeChoice(
            False, px, n, amp, f"flakes {size}: {n:.0f} per pixel, sparkle {amp:.1%} < {SPARKLE_MIN:.0%}: off"
        )
    return FlakeChoice(True, px, n, amp, f"flakes {size}: {max(n, 1.0):.0f} per pixel, sparkle {amp:.1%}: on")


def flake_uniforms(flakes: FlakeLayer) -> dict[str, float | tuple[float, ...]]:
    """Uniform values of the layer for ``render.frag.glsl``."""
    return {
        "u_flake_size_mm": flakes.size_um / 1000.0,
        "u_flake_density": flakes.density_per_mm2,
        "u_flake_sigma": math.radians(flakes.spread_deg),
        "u_flake_reflectance": flakes.reflectance,
        "u_unit_mm": UNIT_MM,
        "u_flake_lattice": tuple(float(v) for v in LATTICE_ROTATION.T.ravel()),  # column-major
    }


#: Face size of the flakes' mean map (:func:`flake_mean_cube`) and the largest face of its source.
MEAN_FACE = 16
MEAN_SOURCE_FACE = 16


def glint_lobe(exponents: tuple[float, ...] | list[float]) -> int:
    """Index of the basis lobe whose map the flakes' glints read (L_sharp): the sharpest."""
    return int(np.argmax(exponents))


def flake_mean_cube(basis, flakes: FlakeLayer, sharp: np.ndarray | None = None) -> np.ndarray:
    """C_E: the expected flake reflection (6, MEAN_FACE, MEAN_FACE, 3), the sharpest map of *basis* (the
    glints' own map, with its sun and lights) prefiltered by brute-force quadrature
    (:func:`station.render.prefilter.prefilter_brute`) with the Phong lobe of the flakes' reflected
    spread, E = 1/(2σ)². Prefiltering the glints' own map makes the sparkle's mean zero whatever lights
    the basis took out of its wide lobes (a lobe map plus its lights need not hold the same energy).
    *sharp*: another glint map of that lobe's size instead (a light's share of it: the mean of that share,
    ``station.render.gl_light_maps``)."""
    from station.render.cubemap import downsample_cube
    from station.render.prefilter import prefilter_brute

    glints = basis.cubes[glint_lobe(basis.exponents)] if sharp is None else sharp
    src = np.asarray(glints, dtype=np.float64)
    while src.shape[1] > MEAN_SOURCE_FACE:
        src = downsample_cube(src)
    return prefilter_brute(src, flakes.reflected_exponent, MEAN_FACE).astype(np.float32)


def flake_lobes(exponents: tuple[float, ...] | list[float], flakes: FlakeLayer) -> tuple[int, int]:
    """(sharp, mean) lobe indices of a basis for the sparkle: the sharpest map (L_sharp, the glint) and the
    map whose exponent is nearest in log to the flakes' E ≈ 1/(2σ)² (C_E, the expected flake reflection)."""
    sharp = glint_lobe(exponents)
    target = math.log(flakes.reflected_exponent)
    mean = int(np.argmin([abs(math.log(float(e)) - target) for e in exponents]))
    return sharp, mean


def flake_tint(dd_map_weights: np.ndarray) -> np.ndarray:
    """Tint (3,) of a paint's flakes: its directionally diffuse colour Σ_i w_DD,i (map weights (m, 3),
    :meth:`station.render.weights.LobeWeights.map_weights`)."""
    return np.asarray(dd_map_weights, dtype=np.float64).reshape(-1, 3).sum(axis=0)


def flake_levels(
    flakes: FlakeLayer,
    positions: np.ndarray,
    normals: np.ndarray,
    distance: np.ndarray,
    n_dot_v: np.ndarray,
    tan_half_fov: float,
    height: int,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The two cell levels of each pixel (module docstring), as the shader picks them: [(w (P,), m (P, 3))]
    for level k and k + 1, w the level's weight (blend, presence and 1/√n_k) and m its flake normal.

    *positions* (P, 3) world, *normals* (P, 3) unit shading normals (the environment's frame),
    *distance* (P,) from the eye in scene units, *n_dot_v* (P,) the cosine of the view, *tan_half_fov*
    and *height* the camera's: the finest cell is CELL_PIXELS footprints of
    2 d tan(fov/2) / height · UNIT_MM / √max(N·V, 0.05) mm."""
    d = np.asarray(distance, dtype=np.float64).reshape(-1)
    ndv = np.maximum(np.asarray(n_dot_v, dtype=np.float64).reshape(-1), 0.05)
    px = CELL_PIXELS * 2.0 * d * tan_half_fov / height * UNIT_MM / np.sqrt(ndv)
    size = flakes.size_um / 1000.0
    lam = np.maximum(np.log2(px / size), 0.0)
    k = np.floor(lam)
    f = lam - k
    norm = 1.0 / np.sqrt((1.0 - f) ** 2 + f**2)
    out = []
    for level, blend in ((k, (1.0 - f) * norm), (k + 1.0, f * norm)):
        cell = size * np.exp2(level)
        count = flakes.density_per_mm2 * cell * cell
        m, u = flake_normals(flakes, positions, cell, normals, level.astype(np.int64))
        win = flake_window(positions, cell)
        out.append((blend * win * (u < count) / np.sqrt(np.maximum(count, 1.0)), m))
    return out


def _lattice(positions: np.ndarray, cells_mm: np.ndarray | float) -> np.ndarray:
    """Positions (P, 3) world in lattice coordinates of cells of side *cells_mm* (P,) or scalar, mm."""
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    scale = (UNIT_MM / np.broadcast_to(np.asarray(cells_mm, dtype=np.float64), p.shape[:1])).reshape(-1, 1)
    return (p @ LATTICE_ROTATION.T) * scale


def flake_window(positions: np.ndarray, cells_mm: np.ndarray | float) -> np.ndarray:
    """The glint bump (P,) of each position's cell: WINDOW_NORM (1 − |x|²/r²)² for |x| < r, 0 beyond, x the
    offset (cell sides) from the cell's centre and r = GLINT_RADIUS (constants above)."""
    q = _lattice(positions, cells_mm)
    d2 = np.sum((q - np.floor(q) - 0.5) ** 2, axis=-1) / GLINT_RADIUS**2
    return WINDOW_NORM * np.maximum(1.0 - d2, 0.0) ** 2


#: Abramowitz & Stegun 7.1.26 (|error| ≤ 1.5e-7): erf(x) = 1 − t(a1 + t(a2 + …)) e^(−x²), t = 1/(1 + p x),
#: x ≥ 0; the shader evaluates the same polynomial (GLSL has no erf).
ERF_P = 0.3275911
ERF_A = (0.254829592, -0.284496736, 1.421413741, -1.453152027, 1.061405429)


def flake_horizon(flakes: FlakeLayer, n_dot_v: np.ndarray) -> np.ndarray:
    """Fraction (P,) of the flakes' mirrored views R_m above the surface at *n_dot_v* (P,) = R·N:
    Φ(asin(N·V) / (2σ)). A flake tilted by σ g tilts its reflection by 2σ g, so R_m's elevation is that of R,
    asin(N·V), less a normal deviate of deviation 2σ, and the glint lookups below the horizon are zero: the
    expected flake reflection is this fraction of C_E(R) (at N·V 0.2 and 8° spread 0.77; C_E alone made
    the grazing sparkle's mean 23 % negative)."""
    x = np.arcsin(np.clip(np.asarray(n_dot_v, dtype=np.float64), 0.0, 1.0)) / (
        2.0 * math.radians(flakes.spread_deg)
    )
    z = x / math.sqrt(2.0)
    t = 1.0 / (1.0 + ERF_P * z)
    poly = t * (ERF_A[0] + t * (ERF_A[1] + t * (ERF_A[2] + t * (ERF_A[3] + t * ERF_A[4]))))
    return 0.5 * (1.0 + (1.0 - poly * np.exp(-z * z)))


def _pcg3d(v: np.ndarray) -> np.ndarray:
    """The shader's ``pcg3d`` hash on (P, 3) uint32 (wrapping arithmetic)."""
    v = v.astype(np.uint32) * np.uint32(1664525) + np.uint32(1013904223)
    x, y, z = v[:, 0].copy(), v[:, 1].copy(), v[:, 2].copy()
    x += y * z
    y += z * x
    z += x * y
    x ^= x >> np.uint32(16)
    y ^= y >> np.uint32(16)
    z ^= z >> np.uint32(16)
    x += y * z
    y += z * x
    z += x * y
    return np.stack([x, y, z], axis=-1)


def flake_normals(
    flakes: FlakeLayer,
    positions: np.ndarray,
    cells_mm: np.ndarray | float,
    normals: np.ndarray,
    level: np.ndarray | int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """One flake normal m (P, 3) per surface cell, as ``render.frag.glsl`` draws it, and the cell's third
    uniform (P,) (its flake is present when below the cell's mean count): the cell of a world *position*
    (P, 3) is floor(p · UNIT_MM / cell) (+ 2^20, *level* · 2^24 added to z) hashed with pcg3d to three
    uniforms, Box–Muller on the first two to a standard normal pair g, and m = normalize(N + σ (g_x T +
    g_y B)) about the shading normal N (P, 3) with σ = spread_deg in radians and the frame
    T = normalize(N × Y) (N × X near ±Y), B = N × T."""
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    cells = np.floor(_lattice(p, cells_mm)).astype(np.int64) + (1 << 20)
    cells[:, 2] += np.broadcast_to(np.asarray(level, dtype=np.int64), p.shape[:1]) << 24
    h = _pcg3d((cells & 0xFFFFFFFF).astype(np.uint32))
    u = ((h >> np.uint32(8)).astype(np.float64) + 0.5) / 16777216.0
    rad = np.sqrt(-2.0 * np.log(u[:, 0]))
    g = rad[:, None] * np.stack([np.cos(2.0 * np.pi * u[:, 1]), np.sin(2.0 * np.pi * u[:, 1])], axis=-1)
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    helper = np.where(np.abs(n[:, 1:2]) < 0.9, np.array([[0.0, 1.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    t = np.cross(n, helper)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    b = np.cross(n, t)
    sigma = math.radians(flakes.spread_deg)
    m = n + sigma * (g[:, :1] * t + g[:, 1:] * b)
    return m / np.linalg.norm(m, axis=-1, keepdims=True), u[:, 2]


def clip_sparkle(sparkle: np.ndarray, radiance: np.ndarray, flakes: FlakeLayer) -> np.ndarray:
    """The sparkle added to a pixel of *radiance*: never darker by more than the flakes' share,
    max(sparkle, −reflectance · radiance) (module docstring)."""
    return np.maximum(sparkle, -flakes.reflectance * np.asarray(radiance))


def sparkle_pixels(
    basis,
    flakes: FlakeLayer,
    tint: np.ndarray,
    positions: np.ndarray,
    distance: np.ndarray,
    normal: np.ndarray,
    view: np.ndarray,
    reflect: np.ndarray,
    tan_half_fov: float,
    height: int,
    mean_cube: np.ndarray | None = None,
) -> np.ndarray:
    """Zero-mean sparkle (P, 3) of the NumPy renderer: tint · reflectance · Σ_k w_k (L_sharp(R_m,k) − H C_E(R))
    (module docstring, H = :func:`flake_horizon`), the same terms as the shader. *positions* (P, 3) world, *distance* (P,) to the eye,
    *normal*, *view*, *reflect* (P, 3) in the environment's frame, *basis* a
    :class:`~station.render.prefilter.PrefilteredBasis`, *mean_cube* its :func:`flake_mean_cube` (computed
    when not given)."""
    from station.render.cubemap import sample_cube

    if mean_cube is None:
        mean_cube = flake_mean_cube(basis, flakes)

    ndv = np.clip(np.sum(normal * view, axis=-1), 0.0, 1.0)
    sharp = glint_lobe(basis.exponents)
    total = np.zeros((np.asarray(normal).reshape(-1, 3).shape[0], 3))
    weight = np.zeros(total.shape[0])
    for w, m in flake_levels(flakes, positions, normal, distance, ndv, tan_half_fov, height):
        rm = 2.0 * np.sum(m * view, axis=-1, keepdims=True) * m - view
        up = np.sum(rm * normal, axis=-1) > 0.0
        total += w[:, None] * np.where(up[:, None], sample_cube(basis.cubes[sharp], rm), 0.0)
        weight += w
    mean = sample_cube(mean_cube, reflect).astype(np.float64) * flake_horizon(flakes, ndv)[:, None]
    return np.asarray(tint)[None, :] * flakes.reflectance * (total - weight[:, None] * mean)
