"""Pinhole camera: primary rays for the NumPy renderer and the same numbers as GL uniforms.

Right-handed, +Y up. Image row 0 is the top row; pixel (row j, column i) looks through
x = (2(i + ½)/W − 1)·tan(fov/2)·W/H, y = (1 − 2(j + ½)/H)·tan(fov/2) on the image plane one unit in
front of the eye. ``fov_deg`` is the vertical field of view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.render.errors import RenderInputError


def cross3(a: np.ndarray | tuple[float, ...], b: np.ndarray | tuple[float, ...]) -> np.ndarray:
    """a × b of two 3-vectors, float64: the products and differences of ``np.cross`` (the same bits)
    without its per-call overhead, which dominates for single vectors (about 20 µs against 2)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]], np.float64
    )


@dataclass(frozen=True)
class Camera:
    """Eye position, look-at target, up hint and vertical field of view (degrees)."""

    eye: tuple[float, float, float] = (0.0, 0.8, 4.5)
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov_deg: float = 30.0

    def __post_init__(self) -> None:
        if not 1.0 <= self.fov_deg <= 120.0:
            raise RenderInputError("fov_deg", "1 <= fov_deg <= 120", self.fov_deg)
        if np.linalg.norm(np.subtract(self.target, self.eye)) < 1e-9:
            raise RenderInputError("camera.target", "a point different from the eye", self.target)

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(forward, right, up) unit vectors."""
        f = np.subtract(self.target, self.eye).astype(np.float64)
        f /= np.linalg.norm(f)
        r = cross3(f, np.asarray(self.up, np.float64))
        if np.linalg.norm(r) < 1e-9:
            raise RenderInputError("camera.up", "not parallel to the view direction", self.up)
        r /= np.linalg.norm(r)
        return f, r, cross3(r, f)

    def rays(self, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Ray origin (3,) and unit directions (H, W, 3) float64, row 0 at the top."""
        f, r, u = self.basis()
        t = np.tan(np.radians(self.fov_deg) / 2.0)
        x = (2.0 * (np.arange(width) + 0.5) / width - 1.0) * t * width / height
        y = (1.0 - 2.0 * (np.arange(height) + 0.5) / height) * t
        d = f + x[None, :, None] * r + y[:, None, None] * u
        return np.asarray(self.eye, dtype=np.float64), d / np.linalg.norm(d, axis=-1, keepdims=True)

    def uniforms(self, width: int, height: int) -> dict[str, object]:
        """The GLSL uniforms of the ray generator (see shaders/render.frag.glsl)."""
        f, r, u = self.basis()
        return {
            "u_eye": tuple(map(float, self.eye)),
            "u_forward": tuple(map(float, f)),
            "u_right": tuple(map(float, r)),
            "u_up": tuple(map(float, u)),
            "u_tan_half_fov": float(np.tan(np.radians(self.fov_deg) / 2.0)),
            "u_aspect": width / height,
        }


#: Accepted ranges of :func:`orbit_camera`: pitch (degrees) and distance (scene units).
PITCH_RANGE = (-89.0, 89.0)
DISTANCE_RANGE = (0.05, 50.0)


def orbit_camera(
    target: tuple[float, float, float] | np.ndarray,
    yaw_deg: float,
    pitch_deg: float,
    distance: float,
    fov_deg: float = 30.0,
) -> Camera:
    """A camera looking at *target* from yaw *yaw_deg* (about +Y, 0 from +Z, 90 from +X) and pitch
    *pitch_deg* (above the horizon) at *distance* scene units: eye = target + d (cos p sin y, sin p,
    cos p cos y). RenderInputError names ``view.pitch`` / ``view.distance`` out of range."""
    if not PITCH_RANGE[0] <= pitch_deg <= PITCH_RANGE[1]:
        raise RenderInputError(
            "view.pitch", f"{PITCH_RANGE[0]:g} <= pitch <= {PITCH_RANGE[1]:g} degrees", pitch_deg
        )
    if not DISTANCE_RANGE[0] <= distance <= DISTANCE_RANGE[1]:
        raise RenderInputError(
            "view.distance", f"{DISTANCE_RANGE[0]:g} <= distance <= {DISTANCE_RANGE[1]:g}", distance
        )
    y, p = np.radians(yaw_deg), np.radians(pitch_deg)
    t = np.asarray(target, dtype=np.float64)
    eye = t + distance * np.array([np.cos(p) * np.sin(y), np.sin(p), np.cos(p) * np.cos(y)])
    return Camera(
        (float(eye[0]), float(eye[1]), float(eye[2])),
        (float(t[0]), float(t[1]), float(t[2])),
        fov_deg=fov_deg,
    )
