"""Self-contained NumPy scenes: the per-pixel buffers the styling tools take, and a reference shader.

The renderer (``station.render``) produces the same buffers on the GPU; :mod:`station.design` may not
import it, so every tool takes plain arrays, and this module makes them for tests, benchmarks and the
CLI's built-in scenes.

Geometry and conventions (thesis §3.6.2, §3.7.1)
-------------------------------------------------
* Orthographic camera on the +z axis; the view vector ``V = (0, 0, 1)`` points from the surface to the
  eye. Image row 0 is the top (world +y).
* ``L`` is the unit vector from the surface towards a directional ("point at infinity") light.
* Aspecular angle θ (degrees) = angle between the mirror direction of the light ``R = 2(N·L)N − L``
  and ``V`` (the thesis's "angle between the reflected light and view vectors").
* Lambert term ϕ = max(N·L, 0) (docs/design.md erratum 2: Lambert's cosine is L·N).
* Light-direction buffer: the light that would centre the highlight on the pixel, ``2(N·V)N − V``
  (thesis §3.6.2 "Move light").
* Shading of a design (the clamped-quadratic model, eq 3.3.2) under irradiance ``E`` is the model's
  reference point-light shading (:func:`station.model.shading.point_light_rgb`)::

      c = E · ϕ · rgb(θ)  +  E · ρ_s (n + 1) / 2 · cos(θ)^n        (lit pixels, θ < 90°)

  where ``rgb(θ)`` is the linear-sRGB colour of ``Lab(min(θ, θ_clamp))`` (reflectance factor 1 = white)
  and ``(n, ρ_s)`` is the Phong lobe of the design's gloss (:func:`station.model.lobe.phong_lobe`; the
  model's normalised lobe ``(n + 1)/(2π) cosⁿψ``; ``(n + 1)/2`` is π times it). The first term is
  eq 3.7.1 read forwards. Display encoding is :mod:`station.model.display` (re-exported here as
  ``srgb_encode``, ``srgb_decode`` and ``to_uint8``).

Buffers are float64 with background pixels set to 0 (θ, ϕ) and ``mask`` False, never NaN.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.design.errors import DesignInputError
from station.model import FaceFlopTravelGloss
from station.model.display import decode_display as srgb_decode
from station.model.display import encode_display as srgb_encode
from station.model.display import to_uint8
from station.model.shading import aspecular_deg, point_light_rgb

__all__ = [
    "BUILTIN_SCENES",
    "DEFAULT_LIGHT",
    "VIEW",
    "EnvironmentScene",
    "LobeBasis",
    "Scene",
    "aspecular_and_lambert",
    "builtin_scene",
    "environment_sphere_scene",
    "lobe_basis",
    "panel_scene",
    "scene_from_buffers",
    "scene_from_normals",
    "shade",
    "shade_environment",
    "sphere_scene",
    "srgb_decode",
    "srgb_encode",
    "studio_lights",
    "to_uint8",
]

VIEW = np.array([0.0, 0.0, 1.0])
#: Default light of the built-in point-light scenes: 45° off the view axis, up and to the left.
DEFAULT_LIGHT = (-0.5, 0.5, float(np.sqrt(0.5)))
MIN_SIZE, MAX_SIZE = 8, 2048


def _unit(v: ArrayLike, field_name: str) -> NDArray[np.float64]:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0:
        raise DesignInputError(field_name, "a finite non-zero 3-vector", v)
    return a / np.linalg.norm(a)


def _check_size(size: int) -> int:
    if not isinstance(size, (int, np.integer)) or not MIN_SIZE <= size <= MAX_SIZE:
        raise DesignInputError("size", f"integer {MIN_SIZE}..{MAX_SIZE} pixels", size)
    return int(size)


def _reflect(d: NDArray, n: NDArray) -> NDArray:
    """Mirror *d* (…,3) about *n* (…,3): ``2(n·d)n − d``."""
    return 2.0 * np.sum(n * d, axis=-1, keepdims=True) * n - d


def aspecular_and_lambert(
    normals: NDArray, mask: NDArray, light: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per-pixel aspecular angle θ (degrees, 0–180) and Lambert term ϕ = max(N·L, 0) (thesis §3.7.1)."""
    theta = np.where(mask, aspecular_deg(light, VIEW, normals), 0.0)
    phi = np.where(mask, np.maximum(normals @ light, 0.0), 0.0)
    return theta, phi


@dataclass(frozen=True, eq=False)
class Scene:
    """Per-pixel buffers of one point-lit view (all ``(H, W)`` or ``(H, W, 3)``, float64).

    Attributes
    ----------
    name : str
    normals : (H, W, 3) unit surface normals (zero in the background)
    mask : (H, W) bool foreground (the material being designed)
    light_dir : (3,) unit vector towards the light
    aspecular_deg : (H, W) θ in degrees
    lambert : (H, W) ϕ = max(N·L, 0)
    light_dirs : (H, W, 3) the light that would centre the highlight on each pixel
    irradiance : E, linear units (1 = a white diffuser facing the light reads 1)
    """

    name: str
    normals: NDArray[np.float64]
    mask: NDArray[np.bool_]
    light_dir: NDArray[np.float64]
    aspecular_deg: NDArray[np.float64]
    lambert: NDArray[np.float64]
    light_dirs: NDArray[np.float64]
    irradiance: float = 1.0

    @property
    def shape(self) -> tuple[int, int]:
        """Image size ``(H, W)`` in pixels."""
        return self.mask.shape

    def with_light(self, light_dir: ArrayLike) -> Scene:
        """Return the same geometry under a new light direction (recomputes θ and ϕ)."""
        return scene_from_normals(self.name, self.normals, self.mask, light_dir, self.irradiance)


def scene_from_normals(
    name: str, normals: ArrayLike, mask: ArrayLike, light_dir: ArrayLike, irradiance: float = 1.0
) -> Scene:
    """Build a :class:`Scene` from a normal buffer, a foreground mask and a light direction."""
    n = np.asarray(normals, dtype=float)
    m = np.asarray(mask, dtype=bool)
    if n.ndim != 3 or n.shape[-1] != 3 or m.shape != n.shape[:2]:
        raise DesignInputError("normals/mask", "(H, W, 3) normals and an (H, W) mask", (n.shape, m.shape))
    if not np.isfinite(irradiance) or irradiance <= 0:
        raise DesignInputError("irradiance", "finite > 0", irradiance)
    light = _unit(light_dir, "light_dir")
    theta, phi = aspecular_and_lambert(n, m, light)
    ldirs = np.where(m[..., None], _reflect(VIEW, n), 0.0)
    return Scene(name, n, m, light, theta, phi, ldirs, float(irradiance))


def scene_from_buffers(
    aspecular_deg: ArrayLike,
    mask: ArrayLike,
    *,
    lambert: ArrayLike | None = None,
    incidence_deg: ArrayLike | None = None,
    light_dirs: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    light_dir: ArrayLike = DEFAULT_LIGHT,
    irradiance: float = 1.0,
    name: str = "buffers",
) -> Scene:
    """Wrap buffers made elsewhere (e.g. ``station.render.buffers.angle_buffers`` on the GPU path) as a
    :class:`Scene`. Give the Lambert term either as ϕ = cos(incidence) (*lambert*) or as the incidence
    angle in degrees (*incidence_deg*, clipped at 90° → ϕ = 0). Missing light-direction or normal
    buffers are zero (the tools that need them then refuse with a typed error)."""
    theta = np.asarray(aspecular_deg, dtype=float)
    m = np.asarray(mask, dtype=bool)
    if theta.ndim != 2 or m.shape != theta.shape:
        raise DesignInputError(
            "aspecular_deg/mask", "two (H, W) buffers of one shape", (theta.shape, m.shape)
        )
    if (lambert is None) == (incidence_deg is None):
        raise DesignInputError("lambert", "exactly one of lambert or incidence_deg", None)
    if lambert is not None:
        phi = np.asarray(lambert, dtype=float)
    else:
        phi = np.maximum(np.cos(np.radians(np.asarray(incidence_deg, dtype=float))), 0.0)
    if phi.shape != theta.shape:
        raise DesignInputError("lambert", f"an (H, W) buffer of shape {theta.shape}", phi.shape)
    buffers = (theta, phi)
    if not all(np.all(np.isfinite(b[m])) for b in buffers):
        raise DesignInputError("aspecular_deg", "finite values on the foreground", "non-finite")
    zeros3 = np.zeros((*theta.shape, 3))
    ld = zeros3 if light_dirs is None else np.asarray(light_dirs, dtype=float)
    nm = zeros3 if normals is None else np.asarray(normals, dtype=float)
    if ld.shape != zeros3.shape or nm.shape != zeros3.shape:
        raise DesignInputError(
            "light_dirs/normals", f"(H, W, 3) buffers of shape {zeros3.shape}", (ld.shape, nm.shape)
        )
    if not np.isfinite(irradiance) or irradiance <= 0:
        raise DesignInputError("irradiance", "finite > 0", irradiance)
    return Scene(
        name,
        nm,
        m,
        _unit(light_dir, "light_dir"),
        np.where(m, theta, 0.0),
        np.where(m, phi, 0.0),
        ld,
        float(irradiance),
    )


def _grid(size: int) -> tuple[NDArray, NDArray]:
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)  # row 0 = top = +y
    return x, y


def sphere_scene(size: int = 96, light_dir: ArrayLike = DEFAULT_LIGHT, irradiance: float = 1.0) -> Scene:
    """A unit sphere filling the frame (orthographic view along −z), lit by a directional light.

    With the default light (45° off the view axis) θ spans 0° (highlight) to about 135° (terminator).
    """
    size = _check_size(size)
    x, y = _grid(size)
    r2 = x * x + y * y
    mask = r2 < 0.98
    z = np.sqrt(np.clip(1.0 - r2, 0.0, None))
    n = np.where(mask[..., None], np.stack([x, y, z], axis=-1), 0.0)
    return scene_from_normals("sphere-point", n, mask, light_dir, irradiance)


def panel_scene(
    size: int = 96, bend_radius: float = 1.2, light_dir: ArrayLike = DEFAULT_LIGHT, irradiance: float = 1.0
) -> Scene:
    """A panel bent about the vertical axis (a cylinder section of radius *bend_radius*) — a booklet page.

    The panel fills the middle 80 % of the frame; its normal turns from ``−asin(0.8/R)`` to ``+asin(0.8/R)``
    about the y axis across it, and it also tilts ±15° top to bottom, so θ covers a useful band.
    """
    size = _check_size(size)
    if not np.isfinite(bend_radius) or bend_radius <= 0.8:
        raise DesignInputError("bend_radius", "> 0.8 (panel half-width)", bend_radius)
    x, y = _grid(size)
    mask = (np.abs(x) < 0.8) & (np.abs(y) < 0.8)
    yaw = np.arcsin(np.clip(x / bend_radius, -1, 1))
    pitch = np.radians(15.0) * y / 0.8
    n = np.stack([np.sin(yaw) * np.cos(pitch), np.sin(pitch), np.cos(yaw) * np.cos(pitch)], axis=-1)
    n = np.where(mask[..., None], n, 0.0)
    return scene_from_normals("panel-point", n, mask, light_dir, irradiance)


BUILTIN_SCENES: dict[str, Callable[[int], Scene]] = {"sphere-point": sphere_scene, "panel-point": panel_scene}


def builtin_scene(name: str, size: int = 96) -> Scene:
    """Return the built-in scene *name* (``sphere-point`` or ``panel-point``) at *size* pixels."""
    if name not in BUILTIN_SCENES:
        raise DesignInputError("scene", " | ".join(BUILTIN_SCENES), name)
    return BUILTIN_SCENES[name](size)


# --------------------------------------------------------------------------------------------- shading


def shade(
    scene: Scene, design: FaceFlopTravelGloss, specular: bool = True, background: ArrayLike = (0.0, 0.0, 0.0)
) -> NDArray[np.float64]:
    """Render *design* in *scene*: ``(H, W, 3)`` linear sRGB (module docstring; eq 3.7.1 forwards).

    The pixel is :func:`station.model.shading.point_light_rgb`; only foreground pixels are evaluated
    (at 128² this is well under 10 ms).
    """
    out = np.empty((*scene.shape, 3))
    out[:] = np.asarray(background, dtype=float)
    m = scene.mask
    out[m] = point_light_rgb(
        design, scene.lambert[m], scene.aspecular_deg[m], irradiance=scene.irradiance, specular=specular
    )
    return out


# ------------------------------------------------------------------------------------------ transfer


# ---------------------------------------------------------------------------------- environment light


@dataclass(frozen=True, eq=False)
class EnvironmentScene:
    """A sphere lit by a small set of directional lights (a discretised environment map).

    ``aspecular_deg`` and ``lambert`` are ``(K, H, W)``: one layer per light ``k`` with direction
    ``light_dirs[k]`` and linear RGB radiance ``light_rgb[k]``. Image = Σ_k radiance_k × point-light image_k.
    """

    name: str
    mask: NDArray[np.bool_]
    light_dirs: NDArray[np.float64]
    light_rgb: NDArray[np.float64]
    aspecular_deg: NDArray[np.float64]
    lambert: NDArray[np.float64]
    normals: NDArray[np.float64] = field(repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        """Image size ``(H, W)`` in pixels."""
        return self.mask.shape


def studio_lights(count: int = 16) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A deterministic studio environment: one warm key light and *count − 1* dim bluish fills
    spread over the front hemisphere (Fibonacci spiral). Returns ``(directions (K,3), rgb (K,3))``."""
    if count < 1:
        raise DesignInputError("count", ">= 1 lights", count)
    dirs = [np.array(DEFAULT_LIGHT)]
    rgb = [np.array([0.80, 0.76, 0.70])]
    golden = np.pi * (3.0 - np.sqrt(5.0))
    for i in range(count - 1):
        z = 1.0 - (i + 0.5) / (count - 1)  # front hemisphere, z in (0, 1)
        r = np.sqrt(1.0 - z * z)
        dirs.append(np.array([r * np.cos(golden * i), r * np.sin(golden * i), z]))
        rgb.append(np.array([0.18, 0.21, 0.26]) * 2.0 / max(count - 1, 1))
    return np.array(dirs), np.array(rgb)


def environment_sphere_scene(size: int = 64, lights: int = 16) -> EnvironmentScene:
    """The unit sphere of :func:`sphere_scene` under :func:`studio_lights`."""
    base = sphere_scene(size)
    dirs, rgb = studio_lights(lights)
    thetas, phis = zip(*(aspecular_and_lambert(base.normals, base.mask, d) for d in dirs), strict=True)
    return EnvironmentScene(
        "sphere-environment", base.mask, dirs, rgb, np.stack(thetas), np.stack(phis), base.normals
    )


def shade_environment(
    scene: EnvironmentScene, design: FaceFlopTravelGloss, specular: bool = True
) -> NDArray[np.float64]:
    """Render *design* under the environment: Σ_k radiance_k · (ϕ_k rgb(θ_k) + specular_k), linear sRGB."""
    out = np.zeros((*scene.shape, 3))
    m = scene.mask
    acc = np.zeros((int(m.sum()), 3))
    for k in range(len(scene.light_dirs)):
        theta, phi = scene.aspecular_deg[k][m], scene.lambert[k][m]
        acc += scene.light_rgb[k] * point_light_rgb(design, phi, theta, specular=specular)
    out[m] = acc
    return out


@dataclass(frozen=True, eq=False)
class LobeBasis:
    """Per-lobe basis images of one fixed view: the image is linear in the lobe weights (DESIGN §4).

    ``images[j]`` (``(J, H, W, 3)``, linear RGB) is the image of lobe *j* with unit weight in every
    channel. ``exponents[j]`` is the lobe's exponent ``E_j`` in ``(R·V)^E_j``; ``None`` marks the
    Lambertian diffuse lobe ``K_D (L·N)``. Directional-diffuse lobes carry the Lambert factor
    (``(L·N)(R·V)^E``), as in eqs 2.3.1–2.3.3.
    """

    images: NDArray[np.float64]
    exponents: tuple[float | None, ...]
    mask: NDArray[np.bool_]
    scales: tuple[float, ...] | None = None

    def lobe_values(self, theta_deg: ArrayLike) -> NDArray[np.float64]:
        """Each lobe's reflectance factor at aspecular angles in the measurement geometry, ``(..., J)``:
        ``scale_j`` × (1 for the diffuse lobe, cos(θ)^E_j clipped at 90° otherwise). *scales* (default 1)
        lets a renderer whose lobes are normalised differently state its constants."""
        c = np.cos(np.radians(np.asarray(theta_deg, dtype=float)))[..., None]
        cols = [
            np.ones_like(c) if e is None else np.where(c > 0, np.abs(c) ** e, 0.0) for e in self.exponents
        ]
        out = np.concatenate(cols, axis=-1)
        return out if self.scales is None else out * np.asarray(self.scales, dtype=float)


DEFAULT_EXPONENTS: tuple[float | None, ...] = (None, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0)


def lobe_basis(scene: EnvironmentScene, exponents: tuple[float | None, ...] = DEFAULT_EXPONENTS) -> LobeBasis:
    """Compute the diffuse and directional-diffuse basis images of *scene* (the renderer's cache, in NumPy)."""
    if not exponents:
        raise DesignInputError("exponents", "at least one lobe", exponents)
    images = np.zeros((len(exponents), *scene.shape, 3))
    m = scene.mask
    probe = LobeBasis(images, tuple(exponents), m)
    for k in range(len(scene.light_dirs)):
        vals = probe.lobe_values(scene.aspecular_deg[k][m]) * scene.lambert[k][m][:, None]  # (n, J)
        images[:, m, :] += vals.T[:, :, None] * scene.light_rgb[k][None, None, :]
    return LobeBasis(images, tuple(exponents), m)
