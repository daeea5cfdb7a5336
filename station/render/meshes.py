"""Own meshes for the GL renderer: glTF/GLB, OBJ and STL through trimesh, plus a procedural car body.

:func:`load_mesh` reads a file with ``trimesh`` (scene graph transforms applied), picks the part to paint
by mesh (node or geometry) name or material name (case-insensitive substring; default: every part is
painted), draws the other parts as tyre, glass or chrome when their names say so (:func:`part_material`),
else as a neutral grey diffuse (``NEUTRAL_ALBEDO``); a GLB of one part with a palette texture and no
*paint* name has its faces coded by their swatches (:mod:`station.render.mesh_parts`). It shades every part smooth with its creases kept
(:func:`smooth_normals`), and places the
model on the renderer's stage: centred on the origin in x and z, its floor at MESH_FLOOR_Y, its longest
horizontal side MESH_LENGTH long. Paint halves follow the shapes' rule: paint 0 where x < 0, paint 1
where x ≥ 0 (design | match side by side), −1 on neutral parts.

glTF files compressed with ``EXT_meshopt_compression`` (and quantised with ``KHR_mesh_quantization``), as
glTF-Transform writes them, are first decoded with the ``meshoptimizer`` package (the reference codec's
Python binding) into a plain GLB of float attributes, which trimesh then reads; textures are dropped (the
paint comes from the design).

:func:`station.render.car.car_body` is the procedural car (body, glass, wheels), for stylists who have no
mesh at hand.

Contact shadow: :meth:`Mesh.occluders` gives MAX_OCCLUDERS sphere proxies along the model's length
(``station.render.stage.sphere_occlusion``).
"""

from __future__ import annotations

import io
import json
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.render.camera import Camera
from station.render.errors import RenderInputError
from station.render.mesh_parts import (
    CHROME,
    GLASS,
    NEUTRAL,
    PAINT,
    TYRE,
    base_color_image,
    palette_codes,
    split_faces,
)
from station.render.stage import MAX_OCCLUDERS

#: File types :func:`load_mesh` reads.
MESH_SUFFIXES = (".glb", ".gltf", ".obj", ".stl")
#: Longest horizontal side of a loaded model (scene units; the speed shape is 2.4 long).
MESH_LENGTH = 2.4
#: Floor height of a loaded model.
MESH_FLOOR_Y = -0.5
#: Reflectance of the neutral (unpainted) parts.
NEUTRAL_ALBEDO = 0.18
#: Default camera on a placed model (three-quarter front view, slightly above).
MESH_CAMERA = Camera((2.3, 1.1, 3.9), (0.0, -0.2, 0.0), fov_deg=34.0)
#: Name fragments (mesh, node or material; lower case) that make an unpainted part tyre, glass or chrome.
PART_WORDS: dict[float, tuple[str, ...]] = {
    TYRE: ("tyre", "tire", "wheel", "rubber"),
    GLASS: ("glass", "window", "windscreen", "windshield", "lamp", "light"),
    CHROME: ("chrome", "rim", "metal", "mirror", "grille", "grill", "exhaust"),
}
#: Faces meeting at a larger angle keep a sharp crease in :func:`smooth_normals`; smaller ones shade smooth.
SMOOTH_ANGLE_DEG = 40.0
_GLB_MAGIC = b"glTF"
_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_NORM = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh on the stage: positions (V, 3) float32, unit vertex normals (V, 3) float32, faces
    (F, 3) uint32 and per-vertex material code (V,) float32 (PAINT, NEUTRAL, TYRE, GLASS, CHROME);
    ``name`` for reports."""

    name: str
    positions: NDArray[np.float32] = field(repr=False)
    normals: NDArray[np.float32] = field(repr=False)
    faces: NDArray[np.uint32] = field(repr=False)
    painted: NDArray[np.float32] = field(repr=False)

    def __post_init__(self) -> None:
        v = self.positions.shape[0]
        if (
            self.positions.shape != (v, 3)
            or self.normals.shape != (v, 3)
            or self.painted.shape != (v,)
            or self.faces.ndim != 2
            or self.faces.shape[1] != 3
            or self.faces.shape[0] == 0
            or v < 3
        ):
            raise RenderInputError("mesh", "vertices (V, 3), normals (V, 3), faces (F, 3), F > 0", self.name)
        if self.faces.max() >= v or not np.all(np.isfinite(self.positions)):
            raise RenderInputError("mesh", "faces indexing its vertices, finite positions", self.name)

    @property
    def bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(min corner, max corner) of the positions."""
        return self.positions.min(axis=0).astype(float), self.positions.max(axis=0).astype(float)

    @property
    def floor_y(self) -> float:
        """Height of the model's lowest point (where the ground goes)."""
        return float(self.positions[:, 1].min())

    def occluders(self) -> NDArray[np.float64]:
        """(k, 4) sphere proxies (centre, radius) for the contact shadow: spheres along the longer horizontal
        axis, radius half the smaller horizontal extent (capped by the height), resting on the floor."""
        lo, hi = self.bounds
        ext = hi - lo
        long_axis = 0 if ext[0] >= ext[2] else 2
        short = ext[2 if long_axis == 0 else 0]
        r = 0.5 * min(short, ext[1] * 1.2)
        k = int(np.clip(np.ceil(ext[long_axis] / max(r, 1e-6)), 1, MAX_OCCLUDERS))
        out = np.zeros((k, 4))
        centre = 0.5 * (lo + hi)
        for i in range(k):
            c = centre.copy()
            c[long_axis] = lo[long_axis] + r + (ext[long_axis] - 2 * r) * (i / max(k - 1, 1))
            c[1] = lo[1] + r
            out[i] = (*c, r)
        return out


def _part_matches(query: str | None, *names: str | None) -> bool:
    if query is None:
        return True
    q = query.lower()
    return any(n is not None and q in n.lower() for n in names)


def smooth_normals(geom: Any, keep_vertices: bool = False) -> tuple[NDArray, NDArray, NDArray]:
    """(vertices, faces, unit vertex normals) of a trimesh geometry shaded smooth. A geometry whose faces
    share vertices and whose file gives normals keeps them. Any other (one vertex per face corner: a
    flat-shaded export, an STL; or shared vertices with no normals in the file, whose area-weighted
    normals would round a box's edges off) has its coincident vertices merged, then split again only along
    edges whose faces meet at more than SMOOTH_ANGLE_DEG (``trimesh.graph.smooth_shade``), so curved
    panels shade smooth and creases stay sharp. *keep_vertices*: a geometry with shared vertices keeps them
    whatever its normals (a palette-textured part is split by its own faces, :func:`_palette_split`)."""
    import trimesh

    faces = np.asarray(geom.faces, np.int64)
    if np.unique(faces).size < faces.size and (keep_vertices or _file_normals(geom)):
        return np.asarray(geom.vertices, float), faces, np.asarray(geom.vertex_normals, float)
    merged = trimesh.Trimesh(np.asarray(geom.vertices, float), faces, process=False)
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    smooth = trimesh.graph.smooth_shade(merged, angle=np.radians(SMOOTH_ANGLE_DEG), facet_minarea=None)
    return (
        np.asarray(smooth.vertices, float),
        np.asarray(smooth.faces, np.int64),
        np.asarray(smooth.vertex_normals, float),
    )


def _file_normals(geom: Any) -> bool:
    """Whether trimesh read vertex normals from the file: a loader puts them in the geometry's cache, where
    computed ones appear only once ``vertex_normals`` is first read (nothing reads it before this check)."""
    cache = getattr(geom, "_cache", None)
    return cache is not None and "vertex_normals" in cache


def part_material(*names: str | None) -> float:
    """The material code of an unpainted part from its mesh, node or material names (PART_WORDS; tyre
    first, then glass, then chrome), NEUTRAL when none matches."""
    text = " ".join(n.lower() for n in names if n)
    for code, words in PART_WORDS.items():
        if any(w in text for w in words):
            return code
    return NEUTRAL


def _read_parts(p: Path, keep_palette: bool) -> tuple[list[tuple], NDArray | None]:
    """The parts of the model file *p*, (node, geometry name, material name, trimesh geometry, 4 × 4
    transform) each, and its palette texture when *keep_palette* (:func:`_palette`; else None);
    RenderInputError (field ``mesh``, naming the file) for a file that cannot be used."""
    import trimesh

    if p.suffix.lower() not in MESH_SUFFIXES:
        raise RenderInputError("mesh", " | ".join(MESH_SUFFIXES) + " file", str(p.name))
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise RenderInputError("mesh", "a readable mesh file", str(p.name), exc.strerror or "") from None
    file_type = p.suffix.lower().lstrip(".")
    palette = _palette(data, file_type) if keep_palette else None  # before decoding drops the textures
    if file_type == "glb" and data[:4] == _GLB_MAGIC:
        data = decode_meshopt_glb(data)
    try:
        scene: Any = trimesh.load(io.BytesIO(data), file_type=file_type, force="scene", process=False)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise RenderInputError("mesh", "a valid mesh file", str(p.name), str(exc)[:200]) from None
    parts = []
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not hasattr(geom, "faces") or len(geom.faces) == 0:
            continue
        material = getattr(getattr(geom, "visual", None), "material", None)
        parts.append((node, geom_name, getattr(material, "name", None), geom, transform))
    if not parts:
        raise RenderInputError("mesh", "a file with triangles", str(p.name))
    return parts, palette


def _names(parts: list[tuple]) -> tuple[str, ...]:
    return tuple(sorted({str(x) for n, g, m, _, _ in parts for x in (n, g, m) if x}))


def mesh_part_names(path: str | Path) -> tuple[str, ...]:
    """The names a part of the model file *path* can be picked by as the paint (``load_mesh(paint=…)``):
    its mesh (node and geometry) and material names, sorted, each once. RenderInputError as
    :func:`load_mesh`."""
    parts, _ = _read_parts(Path(path), keep_palette=False)
    return _names(parts)


def load_mesh(path: str | Path, paint: str | None = None) -> Mesh:
    """Read a .glb/.gltf/.obj/.stl file and place it on the stage (module docstring).

    *paint*: the part to paint, by mesh/node or material name (case-insensitive substring,
    :func:`mesh_part_names` lists them); None paints every part. RenderInputError (field ``mesh``) for an
    unknown suffix, an unreadable file, a file with no triangles, or (field ``paint``) a *paint* that
    matches no part (the message lists the parts).
    """
    p = Path(path)
    parts, palette = _read_parts(p, keep_palette=paint is None)
    chosen = [_part_matches(paint, n, g, m) for n, g, m, _, _ in parts]
    if not any(chosen):
        raise RenderInputError("paint", "a part name: " + ", ".join(_names(parts)), paint)
    pos, nrm, faces, painted = [], [], [], []
    base = 0
    for (node, geom_name, material, geom, transform), is_paint in zip(parts, chosen, strict=True):
        v, f, n = smooth_normals(geom, keep_vertices=palette is not None and len(parts) == 1)
        code = np.full(len(v), PAINT if is_paint else part_material(node, geom_name, material))
        if palette is not None and len(parts) == 1:
            v, f, n, code = _palette_split(geom, palette, v, f, n, code)
        v = v @ transform[:3, :3].T + transform[:3, 3]
        n = n @ np.linalg.inv(transform[:3, :3])
        pos.append(v)
        nrm.append(n)
        faces.append(f + base)
        painted.append(code)
        base += len(v)
    return place_on_stage(
        p.stem, np.concatenate(pos), np.concatenate(nrm), np.concatenate(faces), np.concatenate(painted)
    )


def _palette(data: bytes, file_type: str) -> NDArray | None:
    """The base-colour palette of a GLB (:func:`station.render.mesh_parts.base_color_image`), or None."""
    if file_type != "glb":
        return None
    return base_color_image(data)


def _palette_split(geom: Any, palette: NDArray, v: NDArray, f: NDArray, n: NDArray, code: NDArray) -> tuple:
    """A one-material model's faces coded by their palette swatch (station.render.mesh_parts), when the
    geometry's faces are the file's (smooth_normals kept them); else the part as it was."""
    if len(f) != len(geom.faces) or len(v) != len(geom.vertices):
        return v, f, n, code
    codes = palette_codes(geom, palette)
    if codes is None:
        return v, f, n, code
    sv, sn, sf, sc = split_faces(v, n, f, codes)
    return sv, sf, sn, sc


def place_on_stage(
    name: str, positions: NDArray, normals: NDArray, faces: NDArray, painted: NDArray | None = None
) -> Mesh:
    """Centre in x/z, floor at MESH_FLOOR_Y, longest horizontal side MESH_LENGTH along x (turned 90° about
    +Y when it lies along z); normals unit length."""
    v = np.asarray(positions, float)
    n = np.asarray(normals, float)
    lo, hi = v.min(axis=0), v.max(axis=0)
    if hi[2] - lo[2] > hi[0] - lo[0]:
        turn = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # (x, y, z) -> (z, y, -x)
        v, n = v @ turn.T, n @ turn.T
        lo, hi = v.min(axis=0), v.max(axis=0)
    size = max(hi[0] - lo[0], hi[2] - lo[2])
    if not size > 0:
        raise RenderInputError("mesh", "a model with a horizontal extent", name)
    s = MESH_LENGTH / size
    centre = np.array([0.5 * (lo[0] + hi[0]), lo[1], 0.5 * (lo[2] + hi[2])])
    v = (v - centre) * s + np.array([0.0, MESH_FLOOR_Y, 0.0])
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    f = np.asarray(faces, np.int64)
    paint = np.ones(len(v)) if painted is None else np.asarray(painted, float)
    return Mesh(
        name, v.astype(np.float32), n.astype(np.float32), f.astype(np.uint32), paint.astype(np.float32)
    )


# -- glTF with EXT_meshopt_compression --------------------------------------------------------------------


def _meshopt_view(doc: dict, bin_chunk: bytes, i: int) -> bytes:
    """The bytes of buffer view *i*, decoded with meshoptimizer when it is EXT_meshopt_compression'ed."""
    import meshoptimizer

    bv = doc["bufferViews"][i]
    ext = bv.get("extensions", {}).get("EXT_meshopt_compression")
    if ext is None:
        start = bv.get("byteOffset", 0)
        return bin_chunk[start : start + bv["byteLength"]]
    start = ext.get("byteOffset", 0)
    src = np.frombuffer(bin_chunk[start : start + ext["byteLength"]], np.uint8)
    count, stride, mode = ext["count"], ext["byteStride"], ext["mode"]
    if mode == "ATTRIBUTES":
        raw = meshoptimizer.decode_vertex_buffer(count, stride, src, dtype=np.dtype(f"V{stride}"))
        filt = ext.get("filter", "NONE")
        if filt == "OCTAHEDRAL":
            raw = meshoptimizer.decode_filter_oct(raw, count, stride)
        elif filt == "QUATERNION":
            raw = meshoptimizer.decode_filter_quat(raw, count, stride)
        elif filt == "EXPONENTIAL":
            raw = meshoptimizer.decode_filter_exp(raw, count, stride)
    elif mode == "TRIANGLES":
        raw = meshoptimizer.decode_index_buffer(count, stride, src)
    else:
        raw = meshoptimizer.decode_index_sequence(count, stride, src)
    return np.ascontiguousarray(raw).tobytes()[: count * stride]


def _plain_accessor(acc: dict, bv: dict, raw: bytes) -> tuple[np.ndarray, int]:
    """An accessor's values from its view's decoded bytes, as float32 (dequantised) or uint32 indices,
    and the new component type."""
    ct, k = acc["componentType"], _COMPONENTS[acc["type"]]
    dt = np.dtype(_DTYPES[ct])
    stride = bv.get("byteStride") or bv.get("extensions", {}).get("EXT_meshopt_compression", {}).get(
        "byteStride", dt.itemsize * k
    )
    n = acc["count"]
    base = acc.get("byteOffset", 0)
    rows = np.frombuffer(raw, np.uint8)[base : base + n * stride]
    rows = np.pad(rows, (0, max(0, n * stride - rows.size))).reshape(n, stride)
    vals = rows[:, : dt.itemsize * k].copy().view(dt).reshape(n, k)
    if acc.get("normalized") and ct in _NORM:
        return np.maximum(vals.astype(np.float32) / _NORM[ct], -1.0), 5126
    if ct == 5126:
        return vals.astype(np.float32), 5126
    if acc["type"] == "SCALAR":  # indices
        return vals.astype(np.uint32), 5125
    return vals.astype(np.float32), 5126


def _strip_textures(doc: dict) -> None:
    """Drop the images, textures and the compression extensions from a glTF document (in place)."""
    for key in ("images", "textures", "samplers"):
        doc.pop(key, None)
    for m in doc.get("materials", []):
        m.get("pbrMetallicRoughness", {}).pop("baseColorTexture", None)
        m.get("pbrMetallicRoughness", {}).pop("metallicRoughnessTexture", None)
        for t in ("normalTexture", "occlusionTexture", "emissiveTexture"):
            m.pop(t, None)
    for key in ("extensionsUsed", "extensionsRequired"):
        doc[key] = [
            e
            for e in doc.get(key, [])
            if e not in ("EXT_meshopt_compression", "KHR_mesh_quantization", "EXT_texture_webp")
        ]
        if not doc[key]:
            del doc[key]


def decode_meshopt_glb(data: bytes) -> bytes:
    """A GLB whose buffer views use EXT_meshopt_compression rewritten as a plain GLB of float32 attributes
    and uint32 indices (quantised attributes dequantised, textures dropped); other GLBs come back as they are.
    """
    if len(data) < 20 or data[:4] != _GLB_MAGIC:
        return data
    json_len, _ = struct.unpack_from("<II", data, 12)
    doc = json.loads(data[20 : 20 + json_len])
    if "EXT_meshopt_compression" not in doc.get("extensionsUsed", []):
        return data
    off = 20 + json_len
    bin_chunk = b""
    if off + 8 <= len(data):
        bin_len, _ = struct.unpack_from("<II", data, off)
        bin_chunk = data[off + 8 : off + 8 + bin_len]
    cache: dict[int, bytes] = {}
    out = bytearray()
    views, accessors = [], []
    for acc in doc["accessors"]:
        i = acc["bufferView"]
        if i not in cache:
            cache[i] = _meshopt_view(doc, bin_chunk, i)
        arr, new_ct = _plain_accessor(acc, doc["bufferViews"][i], cache[i])
        blob = arr.tobytes()
        views.append({"buffer": 0, "byteOffset": len(out), "byteLength": len(blob)})
        out += blob + b"\0" * (-len(blob) % 4)
        new = {key: acc[key] for key in ("type", "count", "name") if key in acc}
        new.update({"bufferView": len(views) - 1, "componentType": new_ct, "byteOffset": 0})
        if "min" in acc and new_ct == 5126 and acc.get("normalized"):
            new["min"] = list(map(float, arr.min(axis=0)))
            new["max"] = list(map(float, arr.max(axis=0)))
        elif "min" in acc and not acc.get("normalized"):
            new["min"], new["max"] = acc["min"], acc["max"]
        accessors.append(new)
    doc["accessors"], doc["bufferViews"] = accessors, views
    doc["buffers"] = [{"byteLength": len(out)}]
    _strip_textures(doc)
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(out)
    return (
        struct.pack("<4sII", _GLB_MAGIC, 2, total)
        + struct.pack("<II", len(js), 0x4E4F534A)
        + js
        + struct.pack("<II", len(out), 0x004E4942)
        + bytes(out)
    )
