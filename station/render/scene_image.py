"""A design (or two, side by side) rendered in an environment on its stage: the picture the service returns.

The environment is a built-in procedural one (``station.render.procedural``) or an uploaded HDR file
(:func:`environment_from_bytes`: Radiance .hdr or OpenEXR .exr, bytes and pixels capped before the
pixels are decoded where the format allows). The picture is the NumPy renderer's
(:mod:`station.render.numpy_renderer`: same equations as the GL one, no GL stack needed by the service)
with the environment box-filtered to ENV_WIDTH and prefiltered to PREFILTER_SIZE faces, cached on disk
by content (:class:`~station.render.envcache.PrefilterCache`).
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from station.model.gloss import ClearCoat
from station.render.environment import Environment
from station.render.errors import EnvironmentFileError, RenderInputError
from station.render.hdr_io import ACCEPTED, read_hdr_image
from station.render.shapes import Scene
from station.render.stage import Stage

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: Largest uploaded environment file (bytes): a 1k Radiance file with RLE is about 1.4 MB.
MAX_UPLOAD_BYTES = 4 * 1_048_576
#: Largest uploaded environment (pixels): 2048 × 1024.
MAX_UPLOAD_PIXELS = 2048 * 1024
#: Width the environment is box-filtered to before prefiltering (equirect, pixels).
ENV_WIDTH = 256
#: Cube face size of the prefiltered maps.
PREFILTER_SIZE = 32
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
    from station.render import lobe_fit, tonemap
    from station.render.envcache import PrefilterCache
    from station.render.numpy_renderer import render_linear
    from station.render.prefilter import prefilter_basis

    if not 1 <= len(designs) <= 2:
        raise RenderInputError("designs", "one or two designs", len(designs))
    paints = [lobe_fit.fit_design(d) for d in designs]
    env = environment.downsampled(ENV_WIDTH) if environment.equirect.shape[1] > ENV_WIDTH else environment
    basis = prefilter_basis(
        env, paints[0].exponents, engine="numpy", cache=PrefilterCache(), max_size=PREFILTER_SIZE
    )
    linear = render_linear(Scene(shape, stage=stage), basis, paints, size, size, coat=coat)
    return tonemap.to_display(linear, exposure_ev)
