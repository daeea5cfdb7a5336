"""Procedural lighting environments, so the product renders with no HDR files.

All three are deterministic functions of their arguments, return an
:class:`~station.render.environment.Environment` in linear sRGB (D65 white = (1, 1, 1)), are
supersampled 2×2 per pixel, and are scaled so that an upward-facing white Lambertian surface
(albedo 1) has radiance 1: exposure 1 is a sensible default for every one of them.

* :func:`light_booth` — a D65 viewing booth as paint labs use (ASTM D1729 style): a room of neutral
  grey walls (reflectance ~N7) around the sample, two overhead diffuser panels 6× brighter than
  needed for a grey wall, and a darker grey floor. Radiances are stylised constants per surface
  (no light transport is simulated), chosen so the panels dominate the specular highlights.
* :func:`sunny_sky` — the Preetham, Shirley & Smits (1999) analytic daylight model (Perez
  distribution of luminance and chromaticity, Appendix A.2 coefficients) for a given turbidity and
  sun elevation, plus a sun disc and a grey ground (albedo 0.2) lit by sun and sky.
* :func:`overcast_sky` — the CIE standard overcast sky (Moon & Spencer 1942, CIE S 011 type 1):
  L(θ) = L_z (1 + 2 cos θ)/3 for zenith angle θ, neutral D65, over a grey ground (albedo 0.2).
"""

from __future__ import annotations

import numpy as np

from station.render.cubemap import equirect_directions, equirect_solid_angles
from station.render.environment import Environment
from station.render.errors import RenderInputError

GROUND_ALBEDO = 0.2
SUN_RADIUS_DEG = 1.5  # enlarged from the true 0.27° so a 512-pixel map resolves it
SUN_TO_SKY = 5.0  # horizontal illuminance of the sun / of the sky (clear day, mid elevation)
SUN_XY = (0.3324, 0.3474)  # CIE D55 chromaticity for the direct sun

_XYZ_TO_SRGB = np.array(
    [
        [3.2404542, -1.5371385, -0.4985314],
        [-0.9692660, 1.8760108, 0.0415560],
        [0.0556434, -0.2040259, 1.0572252],
    ]
)


def _check_width(width: int) -> None:
    if not (isinstance(width, int) and 16 <= width <= 8192 and width % 2 == 0):
        raise RenderInputError("width", "even integer 16..8192", width)


def _supersampled_dirs(width: int) -> np.ndarray:
    """Directions of a 2×-supersampled equirect grid, (H, 2, W, 2, 3) to average over axes 1, 3."""
    d = equirect_directions(width, 2 * width)  # height = width at 2× → final H = width/2
    h = width // 2
    return d.reshape(h, 2, width, 2, 3)


def _horizontal_irradiance(img: np.ndarray) -> np.ndarray:
    """Irradiance (3,) on an upward-facing plane: Σ L cos θ dω over the upper hemisphere."""
    h, w = img.shape[:2]
    dirs = equirect_directions(h, w)
    cos = np.clip(dirs[..., 1], 0.0, None)
    return (img * (cos * equirect_solid_angles(h, w))[..., None]).sum(axis=(0, 1))


def _xyY_to_srgb(x: np.ndarray, y: np.ndarray, big_y: np.ndarray) -> np.ndarray:
    y = np.maximum(y, 1e-6)
    xyz = np.stack([x * big_y / y, big_y, (1.0 - x - y) * big_y / y], axis=-1)
    return np.clip(xyz @ _XYZ_TO_SRGB.T, 0.0, None)


def _ray_box(d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Hit points of rays from the origin (inside the box) along d with the box walls, (..., 3)."""
    with np.errstate(divide="ignore"):
        t = np.where(d > 0, hi / d, np.where(d < 0, lo / d, np.inf))
    return d * t.min(axis=-1, keepdims=True)


def light_booth(width: int = 512) -> Environment:
    """D65 viewing booth: grey walls, grey floor, two overhead diffuser panels (see module doc)."""
    _check_width(width)
    d = _supersampled_dirs(width)
    lo, hi = np.array([-1.2, -0.5, -1.0]), np.array([1.2, 1.0, 1.0])
    p = _ray_box(d, lo, hi)
    wall, floor, back = 0.45, 0.25, 0.35
    rad = np.full(p.shape[:-1], wall)
    rad = np.where(p[..., 1] <= lo[1] + 1e-9, floor, rad)
    rad = np.where(p[..., 2] <= lo[2] + 1e-9, back, rad)
    on_ceiling = p[..., 1] >= hi[1] - 1e-9
    panel = (
        on_ceiling
        & (np.abs(p[..., 2] + 0.2) <= 0.45)
        & ((np.abs(p[..., 0] - 0.5) <= 0.3) | (np.abs(p[..., 0] + 0.5) <= 0.3))
    )
    rad = np.where(on_ceiling & ~panel, 0.3, rad)
    rad = np.where(panel, 1.0, rad)  # scaled below
    img = np.repeat(rad.mean(axis=(1, 3))[..., None], 3, axis=-1)
    panel_frac = np.repeat(panel.mean(axis=(1, 3))[..., None], 3, axis=-1)
    # Choose the panel radiance so the horizontal irradiance/π is 1 (see module doc).
    base = np.where(panel_frac > 0, img - panel_frac, img)
    e_base = _horizontal_irradiance(base)
    e_panel = _horizontal_irradiance(panel_frac)
    scale = (np.pi - e_base) / e_panel
    return Environment(f"booth{width}", (base + panel_frac * scale).astype(np.float32))


def preetham_coefficients(turbidity: float) -> dict[str, np.ndarray]:
    """Perez coefficients A..E for Y, x, y (Preetham et al. 1999, Appendix A.2), each shape (5,)."""
    t = turbidity
    return {
        "Y": np.array(
            [
                0.1787 * t - 1.4630,
                -0.3554 * t + 0.4275,
                -0.0227 * t + 5.3251,
                0.1206 * t - 2.5771,
                -0.0670 * t + 0.3703,
            ]
        ),
        "x": np.array(
            [
                -0.0193 * t - 0.2592,
                -0.0665 * t + 0.0008,
                -0.0004 * t + 0.2125,
                -0.0641 * t - 0.8989,
                -0.0033 * t + 0.0452,
            ]
        ),
        "y": np.array(
            [
                -0.0167 * t - 0.2608,
                -0.0950 * t + 0.0092,
                -0.0079 * t + 0.2102,
                -0.0441 * t - 1.6537,
                -0.0109 * t + 0.0529,
            ]
        ),
    }


def preetham_zenith(turbidity: float, sun_zenith: float) -> tuple[float, float, float]:
    """Zenith (Y in kcd/m², x, y) of the Preetham model for turbidity T and sun zenith angle θs (rad)."""
    t, ts = turbidity, sun_zenith
    chi = (4.0 / 9.0 - t / 120.0) * (np.pi - 2.0 * ts)
    big_y = (4.0453 * t - 4.9710) * np.tan(chi) - 0.2155 * t + 2.4192
    tv = np.array([t * t, t, 1.0])
    sv = np.array([ts**3, ts**2, ts, 1.0])
    mx = np.array(
        [
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ]
    )
    my = np.array(
        [
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ]
    )
    return float(big_y), float(tv @ mx @ sv), float(tv @ my @ sv)


def perez(theta: np.ndarray, gamma: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Perez distribution F(θ, γ) = (1 + A e^{B/cos θ})(1 + C e^{Dγ} + E cos²γ)."""
    cos_t = np.maximum(np.cos(theta), 0.01)
    return (1.0 + c[0] * np.exp(c[1] / cos_t)) * (
        1.0 + c[2] * np.exp(c[3] * gamma) + c[4] * np.cos(gamma) ** 2
    )


def sun_direction(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector towards the sun; azimuth 0 = −Z (in front of the default camera), 90 = +X."""
    el, az = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.array([np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)])


def sunny_sky(
    width: int = 512, turbidity: float = 3.0, sun_elevation_deg: float = 35.0, sun_azimuth_deg: float = 150.0
) -> Environment:
    """Clear sky from the Preetham model with a sun disc and a grey ground (see module doc).

    The default sun stands behind the camera's right shoulder at 35° elevation, so a sphere in front
    of the camera shows its highlight.
    """
    _check_width(width)
    if not 1.7 <= turbidity <= 10.0:
        raise RenderInputError("turbidity", "1.7 <= turbidity <= 10 (Preetham model range)", turbidity)
    if not 2.0 <= sun_elevation_deg <= 90.0:
        raise RenderInputError("sun_elevation_deg", "2 <= elevation <= 90 degrees", sun_elevation_deg)
    sun = sun_direction(sun_elevation_deg, sun_azimuth_deg)
    ts = np.pi / 2 - np.radians(sun_elevation_deg)
    coef = preetham_coefficients(turbidity)
    yz, xz, yzc = preetham_zenith(turbidity, ts)
    d = _supersampled_dirs(width)
    theta = np.arccos(np.clip(d[..., 1], -1.0, 1.0))
    gamma = np.arccos(np.clip(d @ sun, -1.0, 1.0))
    lum = yz * perez(theta, gamma, coef["Y"]) / perez(np.zeros(1), np.array([ts]), coef["Y"])
    cx = xz * perez(theta, gamma, coef["x"]) / perez(np.zeros(1), np.array([ts]), coef["x"])
    cy = yzc * perez(theta, gamma, coef["y"]) / perez(np.zeros(1), np.array([ts]), coef["y"])
    sky = _xyY_to_srgb(cx, cy, lum)
    above = (d[..., 1] > 0)[..., None]
    sky = np.where(above, sky, 0.0).mean(axis=(1, 3))
    e_sky = _horizontal_irradiance(sky)
    sky = sky * (np.pi / e_sky[1]) / (1.0 + SUN_TO_SKY)  # sky alone: horizontal irradiance/π = 1/(1+k)
    # Sun disc: uniform radiance whose horizontal illuminance is SUN_TO_SKY × the sky's.
    cos_r = np.cos(np.radians(SUN_RADIUS_DEG))
    disc = ((d @ sun) >= cos_r).mean(axis=(1, 3))
    sun_rgb = _xyY_to_srgb(np.array(SUN_XY[0]), np.array(SUN_XY[1]), np.array(1.0))
    h = width // 2
    e_disc = (
        disc * np.clip(equirect_directions(h, width)[..., 1], 0, None) * equirect_solid_angles(h, width)
    ).sum()
    sun_lum = SUN_TO_SKY * np.pi / (1.0 + SUN_TO_SKY) / e_disc
    img = sky + disc[..., None] * sun_lum * sun_rgb / sun_rgb[1]
    e_total = _horizontal_irradiance(img)
    below = (equirect_directions(h, width)[..., 1] < 0)[..., None]
    ground_frac = (_supersampled_dirs(width)[..., 1] < 0).mean(axis=(1, 3))[..., None]
    img = np.where(below | (ground_frac > 0), img + ground_frac * GROUND_ALBEDO * e_total / np.pi, img)
    return Environment(f"sky{width}_T{turbidity:g}_el{sun_elevation_deg:g}", img.astype(np.float32))


def overcast_sky(width: int = 512) -> Environment:
    """CIE standard overcast sky over a grey ground; zenith 3× the horizon (see module doc)."""
    _check_width(width)
    d = _supersampled_dirs(width)
    up = d[..., 1]
    lz = 9.0 / 7.0  # horizontal illuminance π·L_z·7/9 → irradiance/π = 1
    sky = np.where(up > 0, lz * (1.0 + 2.0 * up) / 3.0, GROUND_ALBEDO * 1.0).mean(axis=(1, 3))
    return Environment(f"overcast{width}", np.repeat(sky[..., None], 3, axis=-1).astype(np.float32))


#: Names of the built-in procedural environments (:func:`procedural_environment`).
NAMES = ("booth", "sky", "overcast")


def procedural_environment(name: str, width: int = 512) -> Environment:
    """Environment by name: ``booth``, ``sky`` or ``overcast`` (defaults of each generator)."""
    makers = {"booth": light_booth, "sky": sunny_sky, "overcast": overcast_sky}
    if name not in makers:
        raise RenderInputError("env", "booth | sky | overcast | PATH to .hdr/.exr", name)
    return makers[name](width)
