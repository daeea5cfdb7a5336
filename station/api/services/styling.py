"""Styling tools over ``station.design``: variations, swatch PNGs, eyedroppers and the sketch fit.

Nothing here is stored: the results are proposals a stylist saves as a design version when wanted.
Uploaded images are decoded from the request bytes by ``station.design.images.decode_image`` (size cap
checked on the header before any pixel is decoded, decompression-bomb guard, colour profile honoured
or stated) as 8-bit sRGB, 3 bytes a pixel; the eyedroppers convert only the discs they read to float.
The routes bound how many uploads are decoded at once (``app.state.image_slots``).
"""

from __future__ import annotations

import io
import json
import math
from typing import Any

from station.api.errors import UnavailableError
from station.api.schemas.styling import RenderRequest, SwatchRequest, VariationsRequest
from station.api.services.designs import to_design
from station.errors import InputError

#: Mood-board uploads stay 8-bit (3 bytes a pixel, about 10 while Pillow decodes): at most 4 megapixels,
#: about 40 MB a request at the peak, whatever the compression ratio of the upload.
EYEDROP_MAX_PIXELS = 4_000_000
#: Sketch-fit art is a square image the size of the built-in scene; this bounds the CPU a request may take.
SKETCH_MAX_SIDE = 512


def variations(*, request: VariationsRequest) -> dict[str, Any]:
    """The ring of variations (``station.design.variations.variations``)."""
    from station.design.variations import variations as ring_of

    ring = ring_of(to_design(request.design), request.degree, request.category)
    return ring.to_dict()


def png_bytes(pixels: Any) -> bytes:
    """Encode an ``(H, W, 3)`` uint8 array as PNG."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, format="PNG")
    return buf.getvalue()


def swatch_png(*, request: SwatchRequest) -> tuple[bytes, int]:
    """The swatch (or booklet thumbnail) as PNG bytes and the number of out-of-gamut swatch columns."""
    from station.design.palette import booklet, swatch

    design = to_design(request.design)
    if request.kind == "booklet":
        return png_bytes(booklet(design, request.size)), 0
    sw = swatch(design, request.width, request.height, request.border)
    return png_bytes(sw.pixels), int(sw.out_of_gamut_columns)


def _silver() -> Any:
    from station.model import FaceFlopTravelGloss

    return FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 50.0, "silver")  # thesis §3.7.1


def render_png(*, request: RenderRequest, upload: bytes | None = None) -> tuple[bytes, dict[str, str]]:
    """The design (default silver) shaded in the built-in scene, or lit by the requested environment on
    its stage (``station.render.scene_image``), sRGB-encoded PNG, and the headers that report the level of
    detail's choices (``X-Flakes``, the flakes' reason; ``X-Lod``, the choice as ASCII JSON) and the engine (``X-Render-Engine``).
    *upload*: the bytes of an .hdr/.exr file sent as a multipart part ``environment_hdr``, which lights the
    scene (the request then names no other environment; InputError naming the field)."""
    design = to_design(request.design) if request.design is not None else _silver()
    if upload is not None:
        for name in ("environment", "environment_hdr"):
            if getattr(request, name) is not None:
                raise InputError(f"request.{name}", "none: the uploaded environment_hdr file lights it", None)
    if request.environment is None and request.environment_hdr is None and upload is None:
        from station.design.scene import builtin_scene, shade, srgb_encode, to_uint8

        for name in ("flakes", "mesh", "lod_de"):
            if getattr(request, name) not in (None, False):
                raise InputError(name, "an environment render (environment or environment_hdr)", None)
        png = png_bytes(to_uint8(srgb_encode(shade(builtin_scene(request.scene, request.size), design))))
        return png, {}
    from station.model.design_io import default_flakes
    from station.model.flakes import FlakeLayer
    from station.model.gloss import ClearCoat
    from station.render.errors import GLUnavailableError
    from station.render.stage import Stage

    designs = [design] + ([to_design(request.design2)] if request.design2 is not None else [])
    stage = Stage(
        backdrop=request.backdrop,
        backdrop_blur_deg=request.backdrop_blur_deg,
        rotation_deg=request.rotation_deg,
        ground=request.ground,
    )
    coat = ClearCoat(request.coat_index) if request.coat_index is not None else None
    if request.flake_layer is not None and not request.flakes:
        raise InputError("flake_layer", "flakes: true with a flake layer", None)
    flakes = None
    if request.flakes:
        if request.flake_layer is not None:
            given = {k: v for k, v in request.flake_layer.model_dump().items() if v is not None}
            flakes = FlakeLayer(**{**(default_flakes(design) or FlakeLayer()).to_dict(), **given})
        else:
            flakes = default_flakes(design)
    from station.render.scene_image import environment_from_bytes, render_scene_image

    environment = (
        request_environment(request.environment, request.environment_hdr)
        if upload is None
        else environment_from_bytes(upload, "environment_hdr")
    )
    try:
        result = render_scene_image(
            designs,
            environment,
            shape=request.shape,
            stage=stage,
            coat=coat,
            exposure_ev=request.exposure_ev,
            size=request.size,
            flakes=flakes,
            mesh=request.mesh,
            lod_de=request.lod_de,
        )
    except GLUnavailableError as exc:
        raise UnavailableError(f"mesh renders need an OpenGL stack on the service: {exc}") from None
    headers = {"X-Render-Engine": result.engine}
    if request.flakes:
        headers["X-Flakes"] = "no flake layer" if result.flakes is None else result.flakes.reason
    if result.lod is not None:  # JSON with non-ASCII escaped: header values are Latin-1
        headers["X-Lod"] = json.dumps(result.lod, ensure_ascii=True, separators=(",", ":"))
    return png_bytes(result.image), headers


def request_environment(environment: str | None, environment_hdr: str | None) -> Any:
    """The ``station.render`` environment of a request: the built-in *environment* at ENV_WIDTH or the
    base64 .hdr/.exr upload *environment_hdr* (InputError naming the field; not both)."""
    import base64
    import binascii

    from station.render.procedural import procedural_environment
    from station.render.scene_image import ENV_WIDTH, environment_from_bytes

    if environment is not None and environment_hdr is not None:
        raise InputError("environment_hdr", "either environment or environment_hdr, not both", None)
    if environment_hdr is not None:
        try:
            data = base64.b64decode(environment_hdr, validate=True)
        except (binascii.Error, ValueError):
            raise InputError("environment_hdr", "base64 of an .hdr/.exr file", None, "not base64") from None
        return environment_from_bytes(data, "environment_hdr")
    if environment is None:
        raise InputError("environment", "a built-in environment or environment_hdr", None)
    return procedural_environment(str(environment), ENV_WIDTH)


def load_upload(data: bytes, *, max_bytes: int, max_pixels: int) -> Any:
    """``decode_image`` on uploaded bytes: an :class:`~station.design.images.EncodedImage` (8-bit)."""
    from station.design.images import decode_image

    if not data:
        raise InputError("image", "a PNG or JPEG file as the request body", "an empty body")
    return decode_image(data, max_pixels=max_pixels, max_bytes=max_bytes)


def _finite(x: Any) -> float | None:
    return float(x) if x is not None and math.isfinite(float(x)) else None


def eyedrop(
    *,
    data: bytes,
    max_bytes: int,
    face: tuple[float, float],
    flop: tuple[float, float],
    gloss: tuple[float, float] | None,
    gloss_gu: float,
    travel_deg: float,
    radius: int,
    auto_swap: bool,
) -> dict[str, Any]:
    """Face/flop(/gloss) eyedroppers on an uploaded image → a design (thesis §3.5)."""
    from station.design.moodboard import eyedrop_design

    img = load_upload(data, max_bytes=max_bytes, max_pixels=EYEDROP_MAX_PIXELS)
    h, w = img.pixels.shape[:2]
    for name, (x, y) in (("face", face), ("flop", flop), *((("gloss", gloss),) if gloss else ())):
        if not (0 <= x < w and 0 <= y < h):
            raise InputError(f"{name}_x", f"a pixel inside the {w}x{h} image", (x, y))
    r = eyedrop_design(
        img.pixels,
        face,
        flop,
        travel_deg=travel_deg,
        gloss_gu=gloss_gu,
        radius=radius,
        auto_swap=auto_swap,
        gloss_xy=gloss,
    )
    return r.to_dict(colour=img.colour_note)


def sketch_fit(*, data: bytes, max_bytes: int, scene_name: str, gloss_mode: str) -> dict[str, Any]:
    """Point-light sketch fit of uploaded art over a built-in scene, started from the scene in silver (§3.7)."""
    from station.design.scene import builtin_scene, shade, srgb_encode
    from station.design.sketch import fit_point_light

    art = load_upload(data, max_bytes=max_bytes, max_pixels=SKETCH_MAX_SIDE**2).to_float().pixels
    h, w = art.shape[:2]
    if h != w or not 16 <= h <= SKETCH_MAX_SIDE:
        raise InputError(
            "art", f"a square image of 16..{SKETCH_MAX_SIDE} pixels, the scene's size", f"{w}x{h}"
        )
    scene = builtin_scene(scene_name, h)
    fit = fit_point_light(scene, art, srgb_encode(shade(scene, _silver())), gloss=gloss_mode)
    out = fit.to_dict()
    for key in ("rms_de", "shading_de", "theta_clamp_deg"):  # JSON has no NaN: a failed fit reads null
        out[key] = _finite(out[key])
    return out
