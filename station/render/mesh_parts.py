"""Parts of a single-material model by its palette texture: which faces are paint, tyre, glass or chrome.

Low-poly models (like the CC0 cars) often carry one material whose base colour comes from a small palette
texture: every face's UVs point at one palette swatch. :func:`palette_codes` reads the swatch under each
face (at the mean of its corners' UVs), converts it to CIELAB (colour-science, sRGB, D65) and assigns a
material code (PAINT ...):

* the swatch covering the largest area, and every swatch within ΔE*ab PAINT_DE of it: the paint;
* L* < TYRE_L: tyre; an achromatic swatch (C*ab < NEUTRAL_C) with L* < GLASS_L: glass; a lighter
  achromatic one: chrome;
* anything else (lamps, badges): a neutral grey.

A heuristic on the swatches' colours, not a segmentation: a model with named parts is better served by
``load_mesh(paint=…)``. :func:`base_color_image` finds the texture in a GLB (PNG, JPEG or WebP, through
Pillow).
"""

from __future__ import annotations

import io
import json
import struct
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: Material codes of :attr:`station.render.meshes.Mesh.painted` (per vertex; the shader reads them flat
#: per triangle): the paint, and the other parts drawn as a neutral grey, a matte tyre, glass or chrome
#: (render.frag.glsl's part_radiance).
NEUTRAL, PAINT, TYRE, GLASS, CHROME = 0.0, 1.0, 2.0, 3.0, 4.0
PAINT_DE = 10.0
TYRE_L = 15.0
GLASS_L = 35.0
NEUTRAL_C = 10.0


def base_color_image(glb: bytes) -> NDArray[np.float64] | None:
    """The first material's base-colour texture of a GLB as sRGB-encoded (H, W, 3) in [0, 1], or None
    (no texture, or an image Pillow cannot read)."""
    from PIL import Image

    if len(glb) < 20 or glb[:4] != b"glTF":
        return None
    json_len = struct.unpack_from("<I", glb, 12)[0]
    doc = json.loads(glb[20 : 20 + json_len])
    try:
        tex = doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"]
        texture = doc["textures"][tex]
        source = texture.get(
            "source", texture.get("extensions", {}).get("EXT_texture_webp", {}).get("source")
        )
        view = doc["bufferViews"][doc["images"][source]["bufferView"]]
    except (KeyError, IndexError, TypeError):
        return None
    off = 20 + json_len
    start = off + 8 + view.get("byteOffset", 0)
    try:
        img = Image.open(io.BytesIO(glb[start : start + view["byteLength"]])).convert("RGB")
    except (OSError, ValueError):
        return None
    return np.asarray(img, dtype=np.float64) / 255.0


def palette_codes(geom: Any, image: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """Material code per face (F,) of a trimesh geometry with UVs, from the swatches of *image* (module
    docstring); None without UVs."""
    import colour

    uv = getattr(getattr(geom, "visual", None), "uv", None)
    if uv is None or len(uv) != len(geom.vertices):
        return None
    faces = np.asarray(geom.faces, np.int64)
    fu = np.asarray(uv, float)[faces].mean(axis=1)
    h, w = image.shape[:2]
    col = np.clip(np.floor(np.mod(fu[:, 0], 1.0) * w), 0, w - 1).astype(int)
    row = np.clip(np.floor((1.0 - np.mod(fu[:, 1], 1.0)) * h), 0, h - 1).astype(int)
    swatch = image[row, col]
    lab = colour.XYZ_to_Lab(colour.sRGB_to_XYZ(swatch))
    keys, inverse = np.unique(np.round(swatch * 255).astype(int), axis=0, return_inverse=True)
    area = np.bincount(inverse.ravel(), weights=np.asarray(geom.area_faces, float), minlength=len(keys))
    paint_lab = lab[np.nonzero(inverse.ravel() == int(np.argmax(area)))[0][0]]
    chroma = np.hypot(lab[:, 1], lab[:, 2])
    codes = np.full(len(faces), NEUTRAL)
    codes[(chroma < NEUTRAL_C) & (lab[:, 0] >= GLASS_L)] = CHROME
    codes[(chroma < NEUTRAL_C) & (lab[:, 0] < GLASS_L)] = GLASS
    codes[lab[:, 0] < TYRE_L] = TYRE
    codes[np.linalg.norm(lab - paint_lab, axis=1) <= PAINT_DE] = PAINT
    return codes


def split_faces(
    positions: NDArray, normals: NDArray, faces: NDArray, codes: NDArray
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """One vertex per face corner (positions, normals, faces, per-vertex codes), so each face keeps its
    own material code; the normals stay the shared (smooth) ones."""
    f = np.asarray(faces, np.int64)
    corners = f.reshape(-1)
    return (
        np.asarray(positions)[corners],
        np.asarray(normals)[corners],
        np.arange(corners.size, dtype=np.int64).reshape(-1, 3),
        np.repeat(np.asarray(codes, float), 3),
    )
