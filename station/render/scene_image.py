"""A design (or two, side by side) rendered in an environment on its stage: the picture the service returns.

The environment is a built-in procedural one (``station.render.procedural``) or an uploaded HDR file
(:func:`environment_from_bytes`: Radiance .hdr or OpenEXR .exr, bytes and pixels capped before the
pixels are decoded where the format allows). The picture is the NumPy renderer's
(:mod:`station.render.numpy_renderer`: same equations as the GL one, no GL stack needed by the service)
with the environment box-filtered to ENV_WIDTH and prefiltered to PREFILTER_SIZE faces, cached on disk
by content (:class:`~station.render.envcache.PrefilterCache`). Flakes are drawn as the GL renderer draws
them; a built-in mesh (:data:`BUILTIN_MESHES`) is rasterised by the GL renderer (the NumPy one ray-casts
the analytic shapes only); :func:`scene_lod` is the level of detail shared with ``station render --lod``.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render.environment import Environment
from station.render.errors import EnvironmentFileError, RenderInputError
from station.render.flakes import FlakeChoice
from station.render.hdr_io import ACCEPTED, read_hdr_image
from station.render.shapes import Scene
from station.render.stage import Stage

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss
    from station.render.meshes import Mesh
    from station.render.weights import LobeWeights

#: Largest uploaded environment file (bytes): a 1k Radiance file with RLE is about 1.4 MB.
MAX_UPLOAD_BYTES = 4 * 1_048_576
#: Longest base64 text of such a file in a JSON body (4 characters per 3 bytes, plus padding).
MAX_UPLOAD_BASE64_CHARS = (MAX_UPLOAD_BYTES * 4) // 3 + 4
#: Largest uploaded environment (pixels): 2048 × 1024.
MAX_UPLOAD_PIXELS = 2048 * 1024
#: Width the environment is box-filtered to before prefiltering (equirect, pixels).
ENV_WIDTH = 256
#: Cube face size of the prefiltered maps.
PREFILTER_SIZE = 32
#: Largest ΔE tolerance the service accepts for the level of detail (CIEDE2000).
LOD_MAX_DE = 10.0
_RADIANCE_SIZE = re.compile(rb"\n[-+]Y (\d+) [-+]X (\d+)\n")


def environment_from_bytes(data: bytes, field: str = "environment_hdr") -> Environment:
    """The environment in an uploaded .hdr/.exr file's bytes; RenderInputError naming *field* when it is
    empty, over MAX_UPLOAD_BYTES or MAX_UPLOAD_PIXELS, or not a usable HDR image."""
    if not data:
        raise RenderInputError(field, ACCEPTED, None, "an empty file")
    if len(data) > MAX_UPLOAD_BYTES:
        raise RenderInputError(
            field, f"a file of at most {MAX_UPLOAD_BYTES} bytes", None, f"{len(data)} bytes"
        )
    if data.startswith((b"#?RADIANCE", b"#?RGBE")):
        m = _RADIANCE_SIZE.search(data[:4096])
        if m is None:
            raise RenderInputError(field, ACCEPTED, None, "no resolution line in the Radiance header")
        h, w = int(m.group(1)), int(m.group(2))
        if h * w > MAX_UPLOAD_PIXELS:
            raise RenderInputError(field, f"at most {MAX_UPLOAD_PIXELS} pixels", None, f"{w}x{h}")
    suffix = ".exr" if data.startswith(b"\x76\x2f\x31\x01") else ".hdr"
    with tempfile.TemporaryDirectory(prefix="cacad-env-") as tmp:
        path = Path(tmp) / f"upload{suffix}"
        path.write_bytes(data)
        try:
            image = read_hdr_image(path)
        except EnvironmentFileError as exc:
            raise RenderInputError(field, ACCEPTED, None, exc.detail) from None
    if image.shape[0] * image.shape[1] > MAX_UPLOAD_PIXELS:
        raise RenderInputError(
            field, f"at most {MAX_UPLOAD_PIXELS} pixels", None, f"{image.shape[1]}x{image.shape[0]}"
        )
    if image.shape[1] != 2 * image.shape[0]:
        raise RenderInputError(
            field, "an equirectangular map (width = 2 × height)", None, f"{image.shape[1]}x{image.shape[0]}"
        )
    return Environment("upload", image)


#: Built-in meshes a request may name (no files: generated on demand).
BUILTIN_MESHES = ("car",)


@dataclass(frozen=True)
class SceneImage:
    """A rendered picture and what the level of detail chose: ``flakes`` (the flake layer's
    :class:`~station.render.flakes.FlakeChoice`, None without one), ``lod`` (lobes and environment width
    for a ΔE tolerance, :func:`scene_lod`, None without a tolerance) and the ``engine`` (numpy | gl)."""

    image: np.ndarray
    flakes: FlakeChoice | None
    lod: dict[str, Any] | None
    engine: str


def builtin_mesh(name: str) -> Mesh:
    """The built-in mesh *name* (BUILTIN_MESHES: ``car``, the procedural car body)."""
    from station.render.car import car_body

    if name not in BUILTIN_MESHES:
        raise RenderInputError("mesh", " | ".join(BUILTIN_MESHES), name)
    return car_body()


def scene_lod(
    designs: Sequence[FaceFlopTravelGloss], environment: Environment, scene: Scene, tolerance_de: float
) -> tuple[list[LobeWeights], Environment, dict[str, Any]]:
    """Level of detail for a ΔE tolerance (:func:`station.render.lod.choose_lod` against the ground truth
    on a 16 × 16 sample of the view): the paints fitted with the chosen lobe count, the environment at the
    chosen width, and the report (lobes, environment width, met, errors, the description)."""
    from station.render import lobe_fit
    from station.render.lobes import basis_for_count
    from station.render.lod import choose_lod
    from station.render.numpy_renderer import gbuffer

    g16 = gbuffer(scene, 16, 16)
    sel = g16.mask & (g16.n_dot_v > 0.05)
    if not sel.any():
        raise RenderInputError("lod", "a view that shows the shape", tolerance_de)
    choice = choose_lod(
        designs,
        environment,
        g16.normal[sel],
        g16.view[sel],
        tolerance_de,
        mode="prefiltered-lut",
        samples=64,
        quadrature_width=64,
    )
    paints = [lobe_fit.fit_design(d, basis_for_count(choice.lobes)) for d in designs]
    env = environment
    if choice.environment_width < env.equirect.shape[1]:
        env = env.downsampled(choice.environment_width)
    report = {
        "lobes": choice.lobes,
        "environment_width": int(env.equirect.shape[1]),
        "met": choice.met,
        "errors": {k: round(float(v), 3) for k, v in choice.errors.items()},
        "describe": choice.describe(),
    }
    return paints, env, report


def render_scene_image(
    designs: Sequence[FaceFlopTravelGloss],
    environment: Environment,
    *,
    shape: str = "speedshape",
    stage: Stage | None = None,
    coat: ClearCoat | None = None,
    exposure_ev: float = 0.0,
    size: int = 256,
    flakes: FlakeLayer | None = None,
    mesh: str | None = None,
    lod_de: float | None = None,
) -> SceneImage:
    """8-bit sRGB picture (size, size, 3) of one design (both halves) or two (left | right) in
    *environment* on *stage* with the clear coat *coat* (None: the thesis's model), the flake layer
    *flakes* (drawn where the level of detail keeps it), on *shape* or a built-in *mesh* (GL: needs an
    OpenGL stack, GLUnavailableError otherwise), with the lobes and environment width chosen for the
    CIEDE2000 tolerance *lod_de* (None: the default basis at ENV_WIDTH)."""
    from station.render import lobe_fit, tonemap
    from station.render.envcache import PrefilterCache
    from station.render.flakes import flake_lod
    from station.render.numpy_renderer import render_linear
    from station.render.prefilter import prefilter_basis

    if not 1 <= len(designs) <= 2:
        raise RenderInputError("designs", "one or two designs", len(designs))
    scene = Scene(shape, stage=stage)
    env = environment.downsampled(ENV_WIDTH) if environment.equirect.shape[1] > ENV_WIDTH else environment
    lod = None
    if lod_de is not None:
        paints, env, lod = scene_lod(designs, env, scene, lod_de)
    else:
        paints = [lobe_fit.fit_design(d) for d in designs]
    basis = prefilter_basis(
        env, paints[0].exponents, engine="numpy", cache=PrefilterCache(), max_size=PREFILTER_SIZE
    )
    if mesh is not None:
        from station.render.gl_renderer import GLRenderer

        model = builtin_mesh(mesh)
        with GLRenderer(basis, size, size) as gl:
            linear = gl.render_mesh(model, paints, stage=stage, coat=coat, linear=True, flakes=flakes)
            return SceneImage(tonemap.to_display(linear, exposure_ev), gl.last_flakes, lod, "gl")
    linear = render_linear(scene, basis, paints, size, size, coat=coat, flakes=flakes)
    choice = None if flakes is None else flake_lod(flakes, scene.view_camera, size)
    return SceneImage(tonemap.to_display(linear, exposure_ev), choice, lod, "numpy")


def render_design_image(
    designs: Sequence[FaceFlopTravelGloss],
    environment: Environment,
    *,
    shape: str = "speedshape",
    stage: Stage | None = None,
    coat: ClearCoat | None = None,
    exposure_ev: float = 0.0,
    size: int = 256,
) -> np.ndarray:
    """8-bit sRGB picture (size, size, 3) of one design (both halves) or two (left | right) in
    *environment* on *stage* with the clear coat *coat* (None: the thesis's model)."""
    return render_scene_image(
        designs, environment, shape=shape, stage=stage, coat=coat, exposure_ev=exposure_ev, size=size
    ).image
