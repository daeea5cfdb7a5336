"""Cube maps in the OpenGL face convention, and equirectangular ↔ direction mapping.

Directions are right-handed with +Y up. A cube map is a float array (6, S, S, 3) with faces in
OpenGL order +X, −X, +Y, −Y, +Z, −Z; texel (row j, column i) of a face sits at face coordinates
a = 2(i + ½)/S − 1, b = 2(j + ½)/S − 1 and points along (OpenGL 4.5 spec, table 8.19):

    +X (1, −b, −a)   −X (−1, −b, a)   +Y (a, 1, b)   −Y (a, −1, −b)   +Z (a, −b, 1)   −Z (−a, −b, −1)

so uploading face f row by row to ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + f`` gives the same lookups in
GLSL ``texture(samplerCube, d)`` as :func:`sample_cube` here.

Equirectangular images have polar angle θ from +Y down the rows (row centre v = (j + ½)/H, θ = πv)
and azimuth φ = 2π(u − ½) across the columns, direction (sin θ sin φ, cos θ, −sin θ cos φ): the image
centre looks along −Z, the direction a default camera looks.
"""

from __future__ import annotations

import numpy as np

FACE_NAMES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")


def _normalize(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def face_coords(size: int) -> np.ndarray:
    """Texel-centre face coordinates, (size,) in (−1, 1)."""
    return (2.0 * (np.arange(size) + 0.5) / size - 1.0).astype(np.float64)


def face_directions(size: int) -> np.ndarray:
    """Unit direction of every texel centre, (6, size, size, 3) float64."""
    c = face_coords(size)
    a, b = np.meshgrid(c, c)  # a along columns, b along rows
    one = np.ones_like(a)
    dirs = np.stack(
        [
            np.stack([one, -b, -a], -1),
            np.stack([-one, -b, a], -1),
            np.stack([a, one, b], -1),
            np.stack([a, -one, -b], -1),
            np.stack([a, -b, one], -1),
            np.stack([-a, -b, -one], -1),
        ]
    )
    return _normalize(dirs)


def texel_solid_angles(size: int) -> np.ndarray:
    """Exact solid angle (sr) of each face texel, (size, size); the six faces sum to 4π."""
    edges = np.linspace(-1.0, 1.0, size + 1)
    x, y = np.meshgrid(edges, edges)
    area = np.arctan2(x * y, np.sqrt(x * x + y * y + 1.0))
    return area[1:, 1:] - area[:-1, 1:] - area[1:, :-1] + area[:-1, :-1]


def direction_to_face(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Map directions (..., 3) to (face index, a, b) with a, b in [−1, 1] (inverse of face_directions)."""
    x, y, z = dirs[..., 0], dirs[..., 1], dirs[..., 2]
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    face = np.where(
        (ax >= ay) & (ax >= az),
        np.where(x > 0, 0, 1),
        np.where(ay >= az, np.where(y > 0, 2, 3), np.where(z > 0, 4, 5)),
    )
    # (sc, tc, ma) per face, OpenGL table 8.19
    sc = np.choose(face, [-z, z, x, x, x, -x])
    tc = np.choose(face, [-y, -y, z, -z, -y, -y])
    ma = np.choose(face, [ax, ax, ay, ay, az, az])
    ma = np.maximum(ma, 1e-30)
    return face, sc / ma, tc / ma


def sample_cube(cube: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Bilinearly sample a cube map (6, S, S, C) along directions (..., 3); edges clamp within a face."""
    size = cube.shape[1]
    face, a, b = direction_to_face(dirs)
    fx = np.clip((a + 1.0) * 0.5 * size - 0.5, 0.0, size - 1.0)
    fy = np.clip((b + 1.0) * 0.5 * size - 0.5, 0.0, size - 1.0)
    x0 = np.minimum(fx.astype(np.int64), size - 2) if size > 1 else np.zeros_like(fx, dtype=np.int64)
    y0 = np.minimum(fy.astype(np.int64), size - 2) if size > 1 else np.zeros_like(fy, dtype=np.int64)
    wx = (fx - x0)[..., None]
    wy = (fy - y0)[..., None]
    x1 = np.minimum(x0 + 1, size - 1)
    y1 = np.minimum(y0 + 1, size - 1)
    c00 = cube[face, y0, x0]
    c01 = cube[face, y0, x1]
    c10 = cube[face, y1, x0]
    c11 = cube[face, y1, x1]
    return (c00 * (1 - wx) + c01 * wx) * (1 - wy) + (c10 * (1 - wx) + c11 * wx) * wy


def equirect_directions(height: int, width: int) -> np.ndarray:
    """Unit direction of every equirectangular pixel centre, (H, W, 3) float64."""
    theta = np.pi * (np.arange(height) + 0.5) / height
    phi = 2.0 * np.pi * ((np.arange(width) + 0.5) / width - 0.5)
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    return np.stack(np.broadcast_arrays(st * np.sin(phi), ct, -st * np.cos(phi)), axis=-1)


def equirect_solid_angles(height: int, width: int) -> np.ndarray:
    """Exact solid angle (sr) of each equirectangular pixel row, (H, 1); rows × W sum to 4π."""
    edges = np.cos(np.pi * np.arange(height + 1) / height)
    return ((edges[:-1] - edges[1:]) * 2.0 * np.pi / width)[:, None]


def direction_to_equirect(dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Map directions (..., 3) to equirectangular (u, v) in [0, 1] (u across, v down)."""
    d = _normalize(np.asarray(dirs, dtype=np.float64))
    u = np.arctan2(d[..., 0], -d[..., 2]) / (2.0 * np.pi) + 0.5
    v = np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi
    return u, v


def sample_equirect(image: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Bilinearly sample an equirectangular image (H, W, C) along directions (..., 3), wrapping in φ."""
    h, w = image.shape[:2]
    u, v = direction_to_equirect(dirs)
    fx = u * w - 0.5
    fy = np.clip(v * h - 0.5, 0.0, h - 1.0)
    x0 = np.floor(fx).astype(np.int64)
    y0 = np.minimum(np.floor(fy).astype(np.int64), max(h - 2, 0))
    wx = (fx - x0)[..., None]
    wy = (fy - y0)[..., None]
    x0m, x1m = x0 % w, (x0 + 1) % w
    y1 = np.minimum(y0 + 1, h - 1)
    top = image[y0, x0m] * (1 - wx) + image[y0, x1m] * wx
    bot = image[y1, x0m] * (1 - wx) + image[y1, x1m] * wx
    return top * (1 - wy) + bot * wy


def downsample_equirect(image: np.ndarray, width: int) -> np.ndarray:
    """Box-filter an equirectangular image by powers of two until its width is ≤ max(width, 8)."""
    img = image
    while img.shape[1] > max(width, 8) and img.shape[0] % 2 == 0 and img.shape[1] % 2 == 0:
        h, w = img.shape[:2]
        img = img.reshape(h // 2, 2, w // 2, 2, -1).mean(axis=(1, 3))
    return img


def equirect_to_cube(image: np.ndarray, size: int) -> np.ndarray:
    """Resample an equirectangular image (H, W, 3) to a cube map (6, size, size, 3) float32.

    The source is first box-filtered to about 8·size pixels across, sampled bilinearly at 2×2
    sub-texel positions (half-pixel spacing, so every source pixel gets its share: small bright
    sources such as the sun keep their energy), and the sub-texels are averaged.
    """
    src = downsample_equirect(np.asarray(image, dtype=np.float32), 8 * size)
    fine = sample_equirect(src, face_directions(2 * size)).astype(np.float32)
    return downsample_cube(fine)


def downsample_cube(cube: np.ndarray) -> np.ndarray:
    """Halve a cube map's face size by 2×2 box filtering (a mip level)."""
    n, s = cube.shape[0], cube.shape[1]
    return cube.reshape(n, s // 2, 2, s // 2, 2, -1).mean(axis=(2, 4))
