"""NumPy reference renderer of the lobe-blend model (thesis eqs 2.5.1–2.5.3).

Per pixel, with N the normal, V the unit vector to the eye and R = 2(N·V)N − V the reflected view:

    radiance = π K_D · D(N) + Σ_i (2π/(E_i+1)) · (h_i(R·N) K_G,i C_i(R) + g_i(R·N) K_DD,i C_i(B_i))

where C_i is the environment prefiltered with the normalised lobe of exponent E_i and D the diffuse
map E(N)/π (:mod:`station.render.prefilter`), and the factors π and 2π/(E+1) convert the sr⁻¹
weights of unnormalised lobes (:mod:`station.render.weights`) to these normalised maps
(:meth:`LobeWeights.map_weights`). The directionally diffuse sum is scaled by R·N (= N·V), the
thesis's stand-in for L·N under environment lighting (§2.5.2: "R in this case is an approximation of
the light source direction"); it is exact for narrow lobes and errs for wide ones, as the thesis notes.
With ``horizon="none"`` g_i(c) = c and h_i(c) = 1: the thesis's equations as printed. The default
``horizon="lut"`` uses, for the wide lobes (E_i < HORIZON_MAX_EXPONENT), the horizon factors of
:func:`station.render.lobes.horizon_factors`: g_i = ∫ p_i(ω)(N·ω)₊ dω and h_i = ∫ p_i(ω) 1[N·ω > 0] dω
for the normalised lobe p_i about R, tabulated at HORIZON_TABLE_SIZE values of c = R·N and
interpolated linearly (the same table is a texture in GL). They make a constant environment exact:
a wide lobe about R spills below the surface, which the cube lookup C_i(R) cannot know. Against the
ground truth (:mod:`station.render.truth`, booth, default basis) this halves the mean ΔE00. Narrow
lobes keep (c, 1): within 0.004 of the tables except at grazing pixels, and it lets the GL renderer
pre-sum them (``gl_renderer``).
Bent lookups (default ``horizon="lut"``): the directionally diffuse integrand of a wide lobe,
(N·ω)₊(R·ω)₊^E_i, is a lobe about B_i = normalize(E_i R + 2.133 N), not about R (the product of two
spherical Gaussians, :func:`station.render.lobes.bent_direction`), so its map is read at B_i; narrow
lobes and the gloss keep R (B_i = R with ``horizon="lut-r"`` or ``"none"``). Measured against the ground
truth it is what makes environments with a bright extended region near the horizon (a sunset, a low
sun) meet the bar: with every lookup at R the directionally diffuse term of a strong-flop silver reads
the glow along R at grazing pixels, where the true integrand, weighted by N·ω, sees the sky above
(docs/benchmarks.md, "Accuracy on every environment").
Lights: when :func:`~station.render.prefilter.prefilter_basis` took compact bright sources (the
sun) out of the environment, the wide lobes' maps hold the rest and each light (direction l, flux Φ)
is added exactly per wide lobe: w_G,i 1[N·l>0] p_i(l) Φ + w_DD,i (N·l)₊ p_i(l) Φ, with
p_i(l) = (E_i+1)/(2π)(R·l)₊^E_i — the exact eqs 2.3.1–2.3.3 for a directional light. Narrow lobes
and the diffuse map keep the lights in their maps (exact there already).
The diffuse map is either the exponent-1 cube (``diffuse="cube"``, default — exact up to resolution)
or the 9-coefficient SH irradiance (``diffuse="sh"``, thesis §2.5.3; up to ~10 % off beside a sun).

Aspecular fall-off (K_A, :mod:`station.render.weights`; not in the thesis): the term
(N·L) K_A min(1, 1 + R·V) integrates to K_A (E(N) − A) with A = ∫ L(ω)(N·ω)₊(a·ω)₊ dω, a = −R, the
directionally diffuse integral of the exponent-1 lobe about −R (the mirror of the view through the tangent
plane: a·N = −N·V ≤ 0, so the lobe lies mostly below the horizon). With ``horizon="lut"`` it is shaded
like a wide lobe's directionally diffuse term, from the diffuse map (which is the normalised exponent-1
map, D = E/π):

    radiance_A = π K_A · max(0, D(N) − g₁(−N·V) D'(B_A) − (1/π) Σ_l (N·l)₊ (a·l)₊ Φ_l),
    B_A = normalize(N − R),   g₁(c) = (2/(3π)) ((π − β) c + sin β),  β = arccos c,

of which π K_A D(N) is in the diffuse term (``LobeWeights.map_weights`` gives w_D = π (K_D + K_A)) and
:func:`fall_off_term` is the rest, −min(D(N), g₁ D'(B_A) + (1/π) Σ_l …), with weight π K_A. g₁ is
the horizon factor g of :func:`station.render.lobes.horizon_factors` for E = 1 in closed form (the
integral of two clamped cosines whose axes are β apart), B_A the product-of-spherical-Gaussians direction
of two exponent-1 lobes about a and N (equal sharpness, so the bisector), and D' the diffuse map without
the extracted lights, D(B_A) − (1/π) Σ_l (B_A·l)₊ Φ_l, whose lights are added exactly instead (the sum).
The true value is ≥ 0 (min(1, 1 + cos α) ≥ 0), hence the clamp. ``"lut-r"`` evaluates the term as
``"lut"`` does (so lut against lut-r still measures the bend of the wide lobes' DD lookups alone);
``"none"`` uses g₁ → (a·N)₊ = 0, i.e. a plain diffuse term π K_A D(N) (the correction is zero). Against the exact integral
(:meth:`station.render.truth.TruthScene.lobes`) the mean |error| / E(N) over a sphere is 0.3 % (booth),
0.8 % (sky), 0.7 % (overcast), 0.5 % (sunrise), 3.1 % (studio), 1.1 % (sunset); reading D' at a instead
of B_A gives 0.7–3.3 %, at normalize(a + 2.133 N) (the wide lobes' bend) 0.5–3.3 %.

Clear coat: with a :class:`station.model.gloss.ClearCoat` every gloss term (w_G,i, lobe maps and
lights) is multiplied per pixel by s(N·V) = F(N·V)/ρ_ref, the coat's exact dielectric Fresnel, and every
base term (diffuse, directionally diffuse, fall-off) by what the coat transmits, 1 − F(N·V) (energy
conserving: a white furnace returns at most its light); ``coat=None`` is the thesis's model as printed.
The diffuse term π K_D reads the coat-transmitted diffuse map D_coat instead of D (light entering the
coat weighted by (1 − F(N·l))/(1 − F_dr,ext), ``ClearCoat.entry_scale``, Mitsuba's ``plastic``;
:func:`station.render.prefilter.coat_diffuse_map`); the effect terms (directionally diffuse, fall-off,
flakes) keep D and the outgoing factor only (``ClearCoat``'s docstring says why).

Shadows on the object: on a stage each extracted light is shadowed by the shape itself, one ray per pixel
and light at the shape (``station.render.shapes.ray_cast_visibility``, hard: a point light); a shadowed
light loses its exact wide-lobe terms and its share of the diffuse base, Σ_l (N·l)₊Φ_l/π times π (K_D +
K_A), under a coat π K_A + π K_D t(N·l) (:func:`light_shadow`): what the GL shadow maps take.

Pixels that miss the object show a constant grey background, or with a scene's
:class:`~station.render.stage.Stage` the environment as backdrop over a ground disc with its contact
shadow and the extracted lights' sun shadows, the environment turned about +Y (:func:`stage_background`;
formulas in ``station.render.stage``; the shape's own shadows and occlusion on the ground, as the GL
renderer's maps draw them, in ``station.render.ground``).

Flakes: with a :class:`station.model.flakes.FlakeLayer` each paint pixel gets the zero-mean sparkle of
:func:`station.render.flakes.sparkle_pixels` (the shader's cells, flake normals and maps), added as
max(sparkle, −reflectance · radiance), where :func:`~station.render.flakes.flake_lod` keeps the layer on.

Output is linear sRGB radiance; the display transform is :mod:`station.render.tonemap`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render.cubemap import sample_cube
from station.render.environment import spread_exponent
from station.render.errors import RenderInputError
from station.render.flakes import clip_sparkle, flake_lod, flake_tint, sparkle_pixels
from station.render.ground import CLOSED_SHAPES, ground_light_visibility, ground_occlusion, shadow_lights
from station.render.light_maps import light_lobe_maps
from station.render.lobes import bent_direction
from station.render.prefilter import WIDE_EXPONENT, PrefilteredBasis, coat_diffuse_map
from station.render.sh import sh_diffuse
from station.render.shapes import GROUNDS, OCCLUDERS, Scene, intersect, ray_cast_visibility
from station.render.stage import backdrop_lobe, ground_fade, ground_radiance, lookup_matrix
from station.render.weights import LobeWeights

BACKGROUND = 0.18
HORIZON_MAX_EXPONENT = WIDE_EXPONENT
HORIZON_TABLE_SIZE = 128
#: Shading methods: "lut" horizon tables with the wide lobes' directionally diffuse lookups bent towards
#: N (default); "lut-r" the same tables with every lookup at R (the method before the bend); "none" the
#: thesis's equations as printed.
HORIZONS = ("lut", "lut-r", "none")


def horizon_wide(exponents: Sequence[float], horizon: str = "lut") -> list[bool]:
    """Per lobe: whether the horizon table holds its factors (g, h) (a wide lobe, E < HORIZON_MAX_EXPONENT,
    with the tables on) rather than (c, 1)."""
    return [horizon != "none" and float(e) < HORIZON_MAX_EXPONENT for e in exponents]


def horizon_table(exponents: Sequence[float], horizon: str = "lut") -> np.ndarray:
    """(m, HORIZON_TABLE_SIZE, 2) float32 table of (g_i, h_i) at c = k/(N−1) (module doc)."""
    if horizon not in HORIZONS:
        raise RenderInputError("horizon", " | ".join(HORIZONS), horizon)
    from station.render.lobes import horizon_factors

    c = np.linspace(0.0, 1.0, HORIZON_TABLE_SIZE)
    table = np.empty((len(exponents), c.size, 2), np.float32)
    for i, (e, wide) in enumerate(zip(exponents, horizon_wide(exponents, horizon), strict=True)):
        if wide:
            g, h = horizon_factors(float(e), c)
            table[i, :, 0], table[i, :, 1] = g, h
        else:
            table[i, :, 0], table[i, :, 1] = c, 1.0
    return table


def lobe_factors(table: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(g, h), each (P, m), by linear interpolation of *table* at c = R·N (P,) in [0, 1]."""
    n = table.shape[1]
    x = np.clip(c, 0.0, 1.0) * (n - 1)
    i0 = np.minimum(x.astype(np.int64), n - 2)
    f = (x - i0)[:, None]
    lo = table[:, i0].transpose(1, 0, 2)
    hi = table[:, i0 + 1].transpose(1, 0, 2)
    v = lo * (1 - f[..., None]) + hi * f[..., None]
    return v[..., 0], v[..., 1]


@dataclass(frozen=True)
class GBuffer:
    """Per-pixel geometry of one view: mask, unit normal, unit view (to eye), reflected view, paint id."""

    mask: np.ndarray  # (H, W) bool
    normal: np.ndarray  # (H, W, 3)
    view: np.ndarray  # (H, W, 3)
    reflect: np.ndarray  # (H, W, 3)
    paint: np.ndarray  # (H, W) int8, −1 off the object
    position: np.ndarray  # (H, W, 3)

    @property
    def n_dot_v(self) -> np.ndarray:
        """N·V = R·N per pixel (H, W), ≥ 0."""
        return np.clip(np.sum(self.normal * self.view, axis=-1), 0.0, 1.0)


def check_size(width: int, height: int) -> None:
    """Validate an image size (1..8192 each)."""
    for name, v in (("width", width), ("height", height)):
        if not (isinstance(v, (int, np.integer)) and 1 <= v <= 8192):
            raise RenderInputError(name, "integer 1..8192", v)


def gbuffer(scene: Scene, width: int, height: int) -> GBuffer:
    """Ray-cast the scene from its camera: per-pixel geometry (row 0 at the top)."""
    check_size(width, height)
    origin, dirs = scene.view_camera.rays(width, height)
    hits = intersect(scene, origin, dirs)
    v = -dirs
    n = hits.normal
    r = 2.0 * np.sum(n * v, axis=-1, keepdims=True) * n - v
    return GBuffer(hits.mask, n, v, r, hits.paint, hits.position)


def check_paints(basis: PrefilteredBasis, paints: Sequence[LobeWeights]) -> list[LobeWeights]:
    """One or two paints whose exponents match the basis; one paint is used for both halves."""
    paints = list(paints)
    if not 1 <= len(paints) <= 2:
        raise RenderInputError("paints", "one or two LobeWeights", len(paints))
    for i, w in enumerate(paints):
        if len(w.exponents) != len(basis.exponents) or not np.allclose(w.exponents, basis.exponents):
            raise RenderInputError(
                f"paints[{i}].exponents", f"the basis exponents {basis.exponents}", w.exponents
            )
    return paints if len(paints) == 2 else paints * 2


def dd_direction(
    exponent: float, normal: np.ndarray, reflect: np.ndarray, horizon: str = "lut"
) -> np.ndarray | None:
    """Lookup direction of a lobe's directionally diffuse term, (P, 3), or None for R itself.

    Wide lobes with horizon tables (E < HORIZON_MAX_EXPONENT, ``horizon="lut"``) look their map up at
    B = normalize(E·R + 2.133·N) (:func:`station.render.lobes.bent_direction`, module docstring);
    narrow lobes, ``"lut-r"`` and ``"none"`` (the thesis as printed) at R.
    """
    if horizon != "lut" or exponent >= HORIZON_MAX_EXPONENT:
        return None
    return bent_direction(exponent, reflect, normal)


def light_terms(
    basis: PrefilteredBasis,
    i: int,
    normal: np.ndarray,
    reflect: np.ndarray,
    vis: np.ndarray | None = None,
    n_dot_l: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Exact (gloss, directionally diffuse) radiance per unit map weight of lobe i from the lights.

    For each light (direction l, flux Φ, spread s²): gloss Σ_l 1[N·l > 0] p_i(l) Φ_l, DD Σ_l (N·l)₊ p_i(l) Φ_l,
    with p_i(l) = (E'+1)/(2π) (R·l)₊^E', E' = E_i / (1 + E_i s²) the lobe smoothed over the light's extent
    (:func:`station.render.environment.spread_exponent`; E_i for a point light); each (P, 3), each light
    times its visibility *vis* (P, k) when given (:func:`light_shadow`). *n_dot_l*: N·l (P, k) of *normal*
    and the lights when the caller has it (:func:`lights_n_dot_l`). None when lobe i keeps the lights in
    its map.
    """
    if basis.lights is None or not basis.wide or not basis.wide[i]:
        return None
    e = spread_exponent(basis.exponents[i], basis.lights.spreads())[None, :]  # (1, k)
    nl = lights_n_dot_l(basis, normal) if n_dot_l is None else n_dot_l  # (P, k)
    p = (e + 1.0) / (2.0 * np.pi) * np.clip(reflect @ basis.lights.directions.T, 0.0, None) ** e
    if vis is not None:
        p = p * vis
    gloss = ((nl > 0) * p) @ basis.lights.flux
    dd = (np.clip(nl, 0.0, None) * p) @ basis.lights.flux
    return gloss, dd


def fall_off_g1(c: np.ndarray) -> np.ndarray:
    """g₁(c) = ∫ (1/π)(a·ω)₊ (N·ω)₊ dω for unit a, N with a·N = c ∈ [−1, 1] (module docstring), dimensionless."""
    c = np.clip(np.asarray(c, dtype=float), -1.0, 1.0)
    beta = np.arccos(c)
    return 2.0 / (3.0 * np.pi) * ((np.pi - beta) * c + np.sin(beta))


def diffuse_lookup(
    basis: PrefilteredBasis, directions: np.ndarray, diffuse: str = "cube", coat: ClearCoat | None = None
) -> np.ndarray:
    """The normalised diffuse map D (..., 3) at unit *directions* (..., 3): the exponent-1 cube
    (``diffuse="cube"``) or the 9-coefficient SH irradiance (``"sh"``), module docstring; with *coat* the
    coat-transmitted map D_coat (:func:`station.render.prefilter.coat_diffuse_map`, its SH twin)."""
    if diffuse == "cube":
        return sample_cube(basis.diffuse if coat is None else coat_diffuse_map(basis, coat), directions)
    return sh_diffuse(basis.sh, directions, coat)


def fall_off_term(
    basis: PrefilteredBasis,
    normal: np.ndarray,
    reflect: np.ndarray,
    n_dot_v: np.ndarray,
    diffuse: str = "cube",
    horizon: str = "lut",
    d_normal: np.ndarray | None = None,
) -> np.ndarray:
    """Fall-off correction (P, 3) per unit map weight π K_A, ≤ 0 (module docstring): with w_D D(N) it
    gives the term's radiance π K_A max(0, D(N) − A/π).

    *normal*, *reflect* (P, 3) unit, *n_dot_v* (P,) = R·N; *d_normal*: D(N) when the caller has it
    already. Units: the diffuse map's (radiance).
    """
    if horizon == "none":
        return np.zeros((np.asarray(normal).shape[0], 3))
    d_n = np.asarray(diffuse_lookup(basis, normal, diffuse) if d_normal is None else d_normal, dtype=float)
    out = d_n.copy()
    anti = -reflect
    look = normal - reflect
    look = look / np.maximum(np.linalg.norm(look, axis=-1, keepdims=True), 1e-12)
    d_look = np.asarray(diffuse_lookup(basis, look, diffuse), dtype=float)
    lights = basis.lights
    if lights is not None and lights.count:
        l_dirs, flux = lights.directions, lights.flux
        d_look = d_look - (np.clip(look @ l_dirs.T, 0.0, None) @ flux) / np.pi
        exact = (np.clip(normal @ l_dirs.T, 0.0, None) * np.clip(anti @ l_dirs.T, 0.0, None)) @ flux
        out = out - exact / np.pi
    out = out - fall_off_g1(-np.asarray(n_dot_v, dtype=float))[:, None] * np.maximum(d_look, 0.0)
    return np.maximum(out, 0.0) - d_n


def lights_n_dot_l(basis: PrefilteredBasis, normal: np.ndarray) -> np.ndarray:
    """N·l (P, k) of unit normals *normal* (P, 3) and the basis's extracted lights (the environment's frame),
    unclamped; (P, 0) without lights."""
    if basis.lights is None:
        return np.zeros((np.asarray(normal).shape[0], 0))
    return np.asarray(normal @ basis.lights.directions.T)


def light_shadow(
    basis: PrefilteredBasis,
    weights: LobeWeights,
    n_dot_l: np.ndarray,
    vis: np.ndarray,
    coat: ClearCoat | None = None,
) -> np.ndarray:
    """What the extracted lights' shadows take from the diffuse base, (P, 3) radiance before the coat's
    outgoing factor: Σ_l (1 − V_l) (N·l)₊ Φ_l/π times π (K_D + K_A) (*coat* None), or under a coat
    π K_A + π K_D t(N·l), t = ``ClearCoat.entry_scale`` (the share the coat-transmitted map holds), as the
    GL shader's shadow maps do (``shaders/render.frag.glsl``). *n_dot_l* (P, k) N·l of the pixels' normals
    and the lights in the environment's frame (:func:`lights_n_dot_l`, unclamped), *vis* (P, k) each
    light's visibility in [0, 1] (:func:`station.render.shapes.ray_cast_visibility`)."""
    lights = basis.lights
    w_d = weights.map_weights()[0]
    if lights is None or not lights.count:
        return np.zeros((np.asarray(n_dot_l).shape[0], 3))
    nl = np.clip(n_dot_l, 0.0, None)  # (P, k)
    lost = (1.0 - vis) * nl / np.pi
    if coat is None:
        return (lost @ lights.flux) * w_d[None, :]
    w_a = weights.fall_off_map_weight()
    return (lost @ lights.flux) * w_a[None, :] + ((lost * coat.entry_scale(nl)) @ lights.flux) * (w_d - w_a)


def light_share_loss(
    basis: PrefilteredBasis, weights: LobeWeights, n_dot_l: np.ndarray, vis: np.ndarray
) -> tuple[np.ndarray, list[int], set[int]]:
    """What each pixel has lost (P, k) of each extracted light's share of the maps that keep the whole
    environment, 1 − V where the surface faces the light and 1 where it faces away (as the GL shader's
    ``lost``); the lights whose share is to be taken (those lost somewhere that carry their pixels) and the
    lobes it is taken from (those that keep the lights and that the paint weights), both empty when there
    is none: :func:`station.render.light_maps.light_lobe_maps`."""
    lost = np.where(np.asarray(n_dot_l) > 0.0, 1.0 - np.asarray(vis, dtype=float), 1.0)
    lights = basis.lights
    _, w_dd, w_g = weights.map_weights()
    lobes = {
        i
        for i in range(len(basis.cubes))
        if not (basis.wide and basis.wide[i]) and (w_g[i] != 0.0 or np.any(w_dd[i] != 0.0))
    }
    if lights is None or lights.pixels is None or not lobes:
        return lost, [], set()
    return lost, [k for k in range(lights.count) if np.any(lost[:, k] > 0.0)], lobes


def shade_pixels(
    basis: PrefilteredBasis,
    weights: LobeWeights,
    normal: np.ndarray,
    reflect: np.ndarray,
    n_dot_v: np.ndarray,
    diffuse: str = "cube",
    horizon: str = "lut",
    coat: ClearCoat | None = None,
    vis: np.ndarray | None = None,
) -> np.ndarray:
    """Radiance (P, 3) of pixels with normals/reflected views (P, 3) and N·V (P,) (module equation).

    *coat*: the clear coat's Fresnel factor on the gloss terms (module docstring); None: none. The
    aspecular fall-off term (K_A > 0) is π K_A D(N) (in w_D) plus π K_A · :func:`fall_off_term`.
    *vis*: (P, k) visibility of the extracted lights (:func:`light_shadow`); None: all visible. The
    lobes that keep the lights in their maps lose the shadowed lights' share of them
    (:func:`light_share_loss`).
    """
    w_d, w_dd, w_g = weights.map_weights()
    d = diffuse_lookup(basis, normal, diffuse)
    g, h = lobe_factors(horizon_table(basis.exponents, horizon), n_dot_v)
    if coat is None:
        base = w_d * d
    else:  # π K_D through the coat (D_coat), π K_A (in w_d, fall-off) with D: module docstring
        w_a = weights.fall_off_map_weight()
        base = (w_d - w_a) * diffuse_lookup(basis, normal, diffuse, coat) + w_a * d
    if weights.has_fall_off:
        base = base + weights.fall_off_map_weight() * fall_off_term(
            basis, normal, reflect, n_dot_v, diffuse, horizon, d_normal=d
        )
    gloss = np.zeros_like(base)
    nl = lights_n_dot_l(basis, normal)  # once for every lobe's lights and the shadows
    lost, shadowed, lobes = light_share_loss(basis, weights, nl, vis) if vis is not None else (nl, [], set())
    for i, cube in enumerate(basis.cubes):
        c_r = sample_cube(cube, reflect)
        if i in lobes:  # a lobe that keeps the lights in its map loses the shadowed lights' share of it at R
            for k in shadowed:
                c_r = c_r - lost[:, k : k + 1] * sample_cube(light_lobe_maps(basis, k, [i])[i], reflect)
        bent = dd_direction(basis.exponents[i], normal, reflect, horizon)
        c_dd = c_r if bent is None else sample_cube(cube, bent)
        gloss = gloss + h[:, i : i + 1] * w_g[i] * c_r
        base = base + g[:, i : i + 1] * w_dd[i] * c_dd
        lights = light_terms(basis, i, normal, reflect, vis, n_dot_l=nl)
        if lights is not None:
            gloss = gloss + w_g[i] * lights[0]
            base = base + w_dd[i] * lights[1]
    if vis is not None:
        base = base - light_shadow(basis, weights, nl, vis, coat)
    if coat is None:
        return base + gloss
    return coat.base_scale(n_dot_v)[:, None] * base + coat.gloss_scale(n_dot_v)[:, None] * gloss


def stage_background(
    scene: Scene,
    basis: PrefilteredBasis,
    origin: np.ndarray,
    dirs: np.ndarray,
    diffuse: str = "cube",
) -> np.ndarray:
    """Radiance (P, 3) seen along rays *dirs* (P, 3) from *origin* (3,) that miss the shape.

    BACKGROUND grey without a stage; else the backdrop lobe map at R_y(−θ)·d (plus its extracted lights)
    blended with the ground disc: its sky part with the contact shadow, the extracted lights with their
    sun shadows (:func:`station.render.stage.ground_radiance`), both by the shape itself where the GL
    renderer's maps are (:mod:`station.render.ground`: the strongest lights as discs of their angular
    radius by ray cast, soft as GL's, the closed
    solids' sky occlusion by their height columns), else by the sphere proxies.
    """
    d = np.asarray(dirs, dtype=float).reshape(-1, 3)
    stage = scene.stage
    out = np.full(d.shape, BACKGROUND)
    if stage is None:
        return out
    m = lookup_matrix(stage.rotation_deg)
    if stage.backdrop:
        i = backdrop_lobe(basis.exponents, stage.backdrop_blur_deg)
        de = d @ m.T
        out = sample_cube(basis.cubes[i], de).astype(float)
        if basis.lights is not None and basis.wide and basis.wide[i]:
            e = basis.exponents[i]
            p = (e + 1.0) / (2.0 * np.pi) * np.clip(de @ basis.lights.directions.T, 0.0, None) ** e
            out = out + p @ basis.lights.flux
    if stage.ground:
        cx, gy, cz = GROUNDS[scene.shape]
        down = d[:, 1] < -1e-9
        t = np.where(down, (gy - origin[1]) / np.where(down, d[:, 1], -1.0), -1.0)
        hit = t > 0
        pts = origin + np.where(hit, t, 0.0)[:, None] * d
        w = ground_fade(np.hypot(pts[:, 0] - cx, pts[:, 2] - cz), stage.ground_radius) * hit
        on = w > 0.0  # the ground's points that show: only they cast rays
        up = np.array([[0.0, 1.0, 0.0]])
        sky = diffuse_lookup(basis, up, diffuse)[0]
        lights = basis.lights
        world = None if lights is None else lights.directions @ m  # the lights' world directions
        vis = occ = None
        slots = shadow_lights(lights)
        # as GL: the shape's own ground where it has maps
        if lights is not None and world is not None and slots:
            vis = ground_light_visibility(scene, pts[on], world, slots, lights.spreads())
            if scene.shape in CLOSED_SHAPES:
                occ = ground_occlusion(scene, pts[on], gy, (cx, cz), stage.ground_radius)
        ground = ground_radiance(
            pts[on],
            OCCLUDERS[scene.shape],
            stage.ground_albedo,
            sky,
            world,
            None if lights is None else lights.flux,
            visibility=vis,
            occlusion=occ,
        )
        out[on] = out[on] * (1.0 - w[on, None]) + ground * w[on, None]
    return out


def render_linear(
    scene: Scene,
    basis: PrefilteredBasis,
    paints: Sequence[LobeWeights],
    width: int,
    height: int,
    diffuse: str = "cube",
    horizon: str = "lut",
    coat: ClearCoat | None = None,
    flakes: FlakeLayer | None = None,
) -> np.ndarray:
    """Linear sRGB radiance image (H, W, 3) float32 of the scene lit by the prefiltered basis.

    *coat*: clear-coat Fresnel on the gloss terms (module docstring); None: the thesis's model.
    On a stage the extracted lights are shadowed by the shape itself (one ray per pixel and light,
    :func:`station.render.shapes.ray_cast_visibility`; :func:`light_shadow`), as the GL renderer's maps do.
    *flakes*: the paints' flake layer, drawn as the GL renderer draws it when the level of detail
    (:func:`station.render.flakes.flake_lod` of this view and height, which says why) keeps it on.
    """
    if diffuse not in ("cube", "sh"):
        raise RenderInputError("diffuse", "cube | sh", diffuse)
    pair = check_paints(basis, paints)
    g = gbuffer(scene, width, height)
    img = np.full((height, width, 3), BACKGROUND, dtype=np.float64)
    if scene.stage is not None:
        origin, dirs = scene.view_camera.rays(width, height)
        img[~g.mask] = stage_background(scene, basis, origin, dirs[~g.mask], diffuse)
    rot = lookup_matrix(scene.stage.rotation_deg if scene.stage is not None else 0.0)
    ndv = g.n_dot_v
    on = flakes is not None and flake_lod(flakes, scene.view_camera, height).on
    tan_half = float(np.tan(np.radians(scene.view_camera.fov_deg) / 2.0))
    for k in (0, 1):
        m = g.mask & (g.paint == k)
        if m.any():
            n_env, r_env = g.normal[m] @ rot.T, g.reflect[m] @ rot.T
            vis = None
            if scene.stage is not None and basis.lights is not None and basis.lights.count:
                vis = ray_cast_visibility(scene, g.position[m], g.normal[m], basis.lights.directions @ rot)
            img[m] = shade_pixels(basis, pair[k], n_env, r_env, ndv[m], diffuse, horizon, coat, vis)
            if flakes is not None and on:
                eye = np.asarray(scene.view_camera.eye, dtype=float)
                dist = np.linalg.norm(g.position[m] - eye, axis=-1)
                sparkle = sparkle_pixels(
                    basis,
                    flakes,
                    flake_tint(pair[k].map_weights()[1]),
                    g.position[m],
                    dist,
                    n_env,
                    g.view[m] @ rot.T,
                    r_env,
                    tan_half,
                    height,
                )
                img[m] = img[m] + clip_sparkle(sparkle, img[m], flakes)
    return img.astype(np.float32)
