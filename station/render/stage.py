"""The stage around the shape: the environment as backdrop, its rotation, and a ground with contact shadow.

Shared by the NumPy renderer and ``shaders/render.frag.glsl`` (the same formulas):

* **Rotation.** ``rotation_deg`` turns the environment about the vertical axis (+Y): a feature at
  direction e of the map appears in the world at R_y(θ)·e, so every lookup (diffuse map at N, lobe maps
  at R, point lights, backdrop) uses the direction R_y(−θ)·d (:func:`lookup_matrix`).
* **Backdrop.** Rays that miss the shape show the environment itself, looked up in one of the basis's
  prefiltered lobe maps: the one whose half width at half maximum arccos(2^(−1/E)) is nearest to
  ``backdrop_blur_deg`` (0: the sharpest lobe, :func:`backdrop_lobe`). Where the basis took the sun
  out of that map (a wide lobe), each light is added as p_E(d·l)·Φ, p_E = (E+1)/(2π) (d·l)₊^E.
* **Ground.** A horizontal disc at the shape's floor height (``station.render.shapes.GROUND_Y``), a grey
  Lambertian of albedo ``ground_albedo`` lit by the environment's irradiance from above, E(+Y)/π·albedo
  (the diffuse map at +Y), times the ambient visibility 1 − O. The occlusion O of a point on the ground
  by the shape is summed over sphere proxies of the shape (``station.render.shapes.OCCLUDERS``), each
  in closed form: a sphere of radius r whose centre lies at distance d in direction ĉ above the
  horizon hides the cosine-weighted fraction (r/d)²·(n·ĉ) of the sky (the projected solid angle
  π sin²α cos β of a cap of half-angle α = arcsin(r/d) at elevation angle 90° − β, over π), and the
  spheres' fractions combine as O = 1 − Π_k (1 − O_k) (:func:`sphere_occlusion`: a sum would count the
  sky behind overlapping proxies twice and turn the ground under a car black). That is the contact
  shadow. With lights taken out of the environment (the sun, a booth's
  lamps: ``PrefilteredBasis.lights``, directions l and flux Φ) each also casts a sun shadow: the ground is
  albedo · [(D(+Y) − Σ_l (l_y)₊Φ_l/π)₊ (1 − O) + Σ_l (l_y)₊Φ_l/π · V_l], the sky part with the contact
  shadow and each light's direct part with its visibility V_l (:func:`light_visibility`): the product
  over the sphere proxies of the unblocked share of a light of angular radius PENUMBRA_DEG, which a
  sphere seen at angular radius α = arcsin(r/d), its centre β away from l, covers for β < α − PENUMBRA_DEG
  and misses for β > α + PENUMBRA_DEG (smoothstep between). The shadow of a sphere thus falls around
  the ground point p = c − l (c_y − y_ground)/l_y (centre c), a disc stretched by 1/l_y along the light.
  The disc fades into the backdrop between half its radius and
  its radius (smoothstep), so the floor has no hard edge. The proxies' V and O are the closed form of this
  model; where the renderers have the shape's own (GL's shadow and ambient-occlusion maps, the NumPy
  renderer's ray cast and height columns, ``station.render.ground``), :func:`ground_radiance` takes those
  instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.render.errors import RenderInputError

#: Most sphere proxies one shape may use for its contact shadow (the shader's array size).
MAX_OCCLUDERS = 8
#: Angular radius of a light for its sun shadow's penumbra, degrees (the sun's 0.27° widened so the
#: sphere proxies' shadows stay smooth).
PENUMBRA_DEG = 1.0


def _finite(name: str, value: object, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise RenderInputError(name, f"a number in [{lo}, {hi}]", value)
    if not lo <= value <= hi:
        raise RenderInputError(name, f"{lo} <= {name} <= {hi}", value)
    return float(value)


@dataclass(frozen=True)
class Stage:
    """Backdrop, environment rotation and ground of a scene (module docstring).

    Attributes
    ----------
    backdrop
        Show the environment behind the shape (else the flat grey of ``numpy_renderer.BACKGROUND``).
    backdrop_blur_deg
        Blur of the backdrop as a lobe half width at half maximum, degrees in [0, 90].
    rotation_deg
        Turn of the environment about the vertical axis, degrees in [−360, 360].
    ground
        Draw the ground disc with its contact shadow.
    ground_albedo
        Reflectance of the grey ground, in [0, 1].
    ground_radius
        Radius of the ground disc (scene units, > 0 and <= 100).
    """

    backdrop: bool = True
    backdrop_blur_deg: float = 0.0
    rotation_deg: float = 0.0
    ground: bool = True
    ground_albedo: float = 0.3
    ground_radius: float = 6.0

    def __post_init__(self) -> None:
        for name in ("backdrop", "ground"):
            if not isinstance(getattr(self, name), bool):
                raise RenderInputError(name, "true | false", getattr(self, name))
        object.__setattr__(
            self, "backdrop_blur_deg", _finite("backdrop_blur_deg", self.backdrop_blur_deg, 0, 90)
        )
        object.__setattr__(self, "rotation_deg", _finite("rotation_deg", self.rotation_deg, -360, 360))
        object.__setattr__(self, "ground_albedo", _finite("ground_albedo", self.ground_albedo, 0, 1))
        object.__setattr__(self, "ground_radius", _finite("ground_radius", self.ground_radius, 1e-3, 100))


def lookup_matrix(rotation_deg: float) -> NDArray[np.float64]:
    """3 × 3 matrix taking a world direction to the environment map's frame: R_y(−θ) (module docstring)."""
    a = math.radians(-rotation_deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def half_width_deg(exponent: float) -> float:
    """Half width at half maximum of the Phong lobe cos^E ψ, degrees: arccos(2^(−1/E))."""
    return math.degrees(math.acos(2.0 ** (-1.0 / exponent)))


def backdrop_lobe(exponents: tuple[float, ...] | list[float], blur_deg: float) -> int:
    """Index of the basis lobe shown as backdrop for *blur_deg* (nearest half width; 0: the sharpest)."""
    if blur_deg <= 0.0:
        return int(np.argmax(exponents))
    widths = [half_width_deg(float(e)) for e in exponents]
    return int(np.argmin([abs(w - blur_deg) for w in widths]))


def stage_bits(
    stage: Stage | None, exponents: tuple[float, ...] | list[float], lights_out: list[bool]
) -> int:
    """The stage's features a GL frame compiles in: bit 0 a stage, 1 its backdrop, 2 its ground, 3 the
    backdrop lobe's lights (*lights_out*: per lobe, whether the lights were taken out of its map, so the
    backdrop's lookup adds them back exactly); 0 without a stage."""
    if stage is None:
        return 0
    out = bool(lights_out) and lights_out[backdrop_lobe(exponents, stage.backdrop_blur_deg)]
    return 1 | int(stage.backdrop) << 1 | int(stage.ground) << 2 | int(stage.backdrop and out) << 3


def sphere_occlusion(points: ArrayLike, occluders: ArrayLike) -> NDArray[np.float64]:
    """Cosine-weighted occluded fraction O (P,) of the sky above ground *points* (P, 3) (normal +Y) by
    spheres *occluders* (k, 4) = (centre x, y, z, radius): each sphere's fraction O_k in closed form,
    combined as O = 1 − Π_k (1 − O_k) (the spheres' shares taken as independent), in [0, 1]. A plain sum
    counts the sky behind two overlapping spheres twice and reaches 1 (a black ground) wherever the
    overlap does, e.g. all along the underside of a car's row of proxies; the product reaches 1 only
    where one sphere alone hides the whole sky (its contact point)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    open_sky = np.ones(p.shape[0])
    for cx, cy, cz, r in np.asarray(occluders, dtype=float).reshape(-1, 4):
        v = np.array([cx, cy, cz]) - p
        d2 = np.maximum(np.sum(v * v, axis=-1), r * r)
        cos_b = v[:, 1] / np.sqrt(d2)
        open_sky *= 1.0 - (r * r / d2) * np.clip(cos_b, 0.0, 1.0)
    return np.clip(1.0 - open_sky, 0.0, 1.0)


def ground_fade(distance: NDArray, radius: float) -> NDArray[np.float64]:
    """Weight of the ground over the backdrop at horizontal *distance* from the centre: 1 inside radius/2,
    smoothstep down to 0 at the radius."""
    x = np.clip((np.asarray(distance, dtype=float) - 0.5 * radius) / (0.5 * radius), 0.0, 1.0)
    return 1.0 - x * x * (3.0 - 2.0 * x)


def light_visibility(points: ArrayLike, occluders: ArrayLike, directions: ArrayLike) -> NDArray[np.float64]:
    """Visibility V (P, k) of lights in world *directions* (k, 3) from ground *points* (P, 3) past the
    sphere proxies *occluders* (n, 4): per sphere smoothstep(α − w, α + w, β) with α = arcsin(r/d) its
    angular radius, β the angle between the light and its centre, w = PENUMBRA_DEG (module docstring);
    lights below the horizon (l_y <= 0) get 0."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    ls = np.asarray(directions, dtype=float).reshape(-1, 3)
    w = math.radians(PENUMBRA_DEG)
    vis = np.ones((p.shape[0], ls.shape[0]))
    for cx, cy, cz, r in np.asarray(occluders, dtype=float).reshape(-1, 4):
        v = np.array([cx, cy, cz]) - p
        d = np.maximum(np.linalg.norm(v, axis=-1), r * (1.0 + 1e-9))
        alpha = np.arcsin(np.clip(r / d, 0.0, 1.0))
        beta = np.arccos(np.clip((v @ ls.T) / d[:, None], -1.0, 1.0))
        x = np.clip((beta - (alpha[:, None] - w)) / (2.0 * w), 0.0, 1.0)
        vis *= x * x * (3.0 - 2.0 * x)
    return vis * (ls[:, 1] > 0.0)[None, :]


def ground_radiance(
    points: ArrayLike,
    occluders: ArrayLike,
    albedo: float,
    sky_down: ArrayLike,
    light_dirs: ArrayLike | None = None,
    light_flux: ArrayLike | None = None,
    visibility: ArrayLike | None = None,
    occlusion: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Radiance (P, 3) of the ground at *points* (P, 3): albedo · [(D(+Y) − Σ (l_y)₊Φ/π)₊ (1 − O) +
    Σ (l_y)₊Φ/π · V] (module docstring) with *sky_down* = D(+Y) (3,), the diffuse map (irradiance / π)
    looking up, and optional lights (world directions (k, 3), flux (k, 3)) casting sun shadows.

    *visibility* (P, k) in [0, 1] and *occlusion* O (P,) in [0, 1], where given, replace the sphere proxies'
    V (:func:`light_visibility`) and O (:func:`sphere_occlusion`): the shape's own, e.g.
    ``station.render.ground``'s ray cast and ambient occlusion."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    sky = np.asarray(sky_down, dtype=float).reshape(3)
    occ = sphere_occlusion(p, occluders) if occlusion is None else np.asarray(occlusion, float).reshape(-1)
    open_sky = (1.0 - occ)[:, None]
    if light_dirs is None or light_flux is None or not len(np.asarray(light_dirs)):
        return albedo * sky[None, :] * open_sky
    ls = np.asarray(light_dirs, dtype=float).reshape(-1, 3)
    direct = (
        np.clip(ls[:, 1], 0.0, None)[:, None] * np.asarray(light_flux, dtype=float).reshape(-1, 3) / np.pi
    )
    rest = np.clip(sky - direct.sum(axis=0), 0.0, None)
    vis = light_visibility(p, occluders, ls) if visibility is None else np.asarray(visibility, float)
    return albedo * (rest[None, :] * open_sky + vis.reshape(p.shape[0], -1) @ direct)
