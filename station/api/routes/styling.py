"""Styling tools: ``/api/v1/styling`` (stylists; nothing stored, results are proposals to save as designs).

Image uploads are the raw PNG/JPEG request body (capped by the service's body limit); the CPU work runs
off the event loop (``asyncio.to_thread``; the JSON routes are plain ``def``, run in the thread pool), at
most ``CACAD_IMAGE_DECODE_CONCURRENCY`` uploads at once (the others wait, holding only their body).
"""

from __future__ import annotations

import asyncio
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, Query, Request, Response
from fastapi.responses import JSONResponse

from db.models import User
from station.api.deps import SettingsDep, get_settings, scoped
from station.api.errors import ERROR_RESPONSES
from station.api.schemas.environment import ENVIRONMENT_FILE_FIELD, ENVIRONMENT_MULTIPART_PATH
from station.api.schemas.styling import (
    IMAGE_BODY,
    PNG_RESPONSE,
    EyedropOut,
    RenderRequest,
    SketchFitOut,
    SwatchRequest,
    VariationsOut,
    VariationsRequest,
)
from station.api.security import Scope
from station.api.services import styling as service
from station.render.scene_image import MAX_UPLOAD_BYTES


def image_slots(request: Request) -> asyncio.Semaphore:
    """The app's bound on uploads decoded at once (``settings.image_decode_concurrency``), made in the
    lifespan; an app driven without its lifespan gets one on first use."""
    slots: asyncio.Semaphore | None = getattr(request.app.state, "image_slots", None)
    if slots is None:
        slots = asyncio.Semaphore(get_settings(request).image_decode_concurrency)
        request.app.state.image_slots = slots
    return slots


ImageSlotsDep = Annotated[asyncio.Semaphore, Depends(image_slots)]
router = APIRouter(prefix="/styling", tags=["styling"], responses=ERROR_RESPONSES)
Stylist = Annotated[User, scoped(Scope.STYLING_USE)]
Pixel = Annotated[float, Query(ge=0.0, le=100_000.0, allow_inf_nan=False)]
_TOO_LARGE: dict[int | str, dict[str, Any]] = {413: {"description": "request body over the service's limit"}}


@router.post("/variations", response_model=VariationsOut)
def variations(_user: Stylist, request: VariationsRequest) -> dict[str, Any]:
    """The ring of variations of a design (lighter/darker, more/less chroma, hue ±; or travel and gloss),
    deterministic (thesis §3.4.4)."""
    return service.variations(request=request)


@router.post("/swatch", response_class=Response, responses=PNG_RESPONSE)
def swatch(_user: Stylist, request: SwatchRequest) -> Response:
    """The palette swatch PNG (gradient bar across aspecular angles 15°→110°, gloss shown by the border's
    brightness) or the shaded booklet thumbnail (thesis §3.4.6). Header ``X-Out-Of-Gamut-Columns``."""
    png, out_of_gamut = service.swatch_png(request=request)
    return Response(png, media_type="image/png", headers={"X-Out-Of-Gamut-Columns": str(out_of_gamut)})


@router.post("/render", response_class=Response, responses=PNG_RESPONSE)
def render(_user: Stylist, request: RenderRequest) -> Response:
    """A design (default silver) as PNG: in a built-in point-light scene (the picture an artist paints over
    before the sketch fit, thesis §3.7.1), or lit by an environment, built-in (``environment``) or an
    uploaded .hdr/.exr (``environment_hdr``, base64, size-capped), on a shape or the built-in car mesh
    with backdrop, rotation, ground with contact and sun shadows, exposure, the clear coat's Fresnel,
    metallic flakes and a level-of-detail tolerance (``design2``: a second design on the right half).
    Headers ``X-Flakes`` and ``X-Lod`` say what the level of detail chose, ``X-Render-Engine`` the engine."""
    png, headers = service.render_png(request=request)
    return Response(png, media_type="image/png", headers=headers)


#: OpenAPI body of the multipart render: the map as a file part, the render options as a JSON part.
ENVIRONMENT_FORM: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "description": "the environment map as a file part and the render options as a JSON part",
        "content": {
            "multipart/form-data": {
                "schema": {
                    "type": "object",
                    "required": [ENVIRONMENT_FILE_FIELD],
                    "properties": {
                        ENVIRONMENT_FILE_FIELD: {
                            "type": "string",
                            "format": "binary",
                            "description": f"an equirectangular .hdr/.exr file, at most {MAX_UPLOAD_BYTES} bytes",
                        },
                        "request": {
                            "type": "string",
                            "description": "JSON of the /styling/render request without environment and "
                            "environment_hdr (default {})",
                        },
                    },
                }
            }
        },
    }
}
_FILE_TOO_LARGE: dict[int | str, dict[str, Any]] = {
    413: {"description": f"body over the route's limit: detail[0].loc names {ENVIRONMENT_FILE_FIELD}"},
    422: {
        "description": "not multipart/form-data, no usable HDR file, or a bad option; detail[0].loc names it"
    },
}


@router.post(
    ENVIRONMENT_MULTIPART_PATH.removeprefix("/styling"),
    response_class=Response,
    responses={**PNG_RESPONSE, **_FILE_TOO_LARGE},
    openapi_extra=ENVIRONMENT_FORM,
)
async def render_upload(request: Request, slots: ImageSlotsDep, _user: Stylist) -> Response:
    """``/styling/render`` lit by an uploaded .hdr/.exr sent as a file (multipart/form-data: part
    ``environment_hdr``, at most 4 MiB, and an optional part ``request``, the JSON render options): no base64,
    so the documented 4 MiB file fits whatever the service's general body cap. Over 4 MiB: 413 naming
    ``environment_hdr``; a file that is no usable HDR image: 422 naming it."""
    from pydantic import ValidationError

    from station.api.errors import validation_error_body
    from station.api.multipart import form_parts
    from station.errors import InputError

    body = await request.body()
    parts = form_parts(request.headers.get("content-type"), body, (ENVIRONMENT_FILE_FIELD, "request"))
    data = parts.get(ENVIRONMENT_FILE_FIELD)
    if data is None:
        raise InputError(ENVIRONMENT_FILE_FIELD, "a file part named environment_hdr", None, "missing")
    if len(data) > MAX_UPLOAD_BYTES:
        detail = [
            {
                "loc": ["body", ENVIRONMENT_FILE_FIELD],
                "msg": f"{ENVIRONMENT_FILE_FIELD}: a file of {len(data)} bytes, over the {MAX_UPLOAD_BYTES}-byte limit",
                "type": "too_large",
                "ctx": {"accepted": f"a file of at most {MAX_UPLOAD_BYTES} bytes"},
            }
        ]
        return JSONResponse({"detail": detail}, status_code=413)
    try:
        options = RenderRequest.model_validate_json(parts.get("request") or b"{}")
    except ValidationError as exc:
        errors = [{**e, "loc": ("request", *e.get("loc", ()))} for e in exc.errors()]
        return JSONResponse(validation_error_body(errors), status_code=422)
    async with slots:
        png, headers = await asyncio.to_thread(service.render_png, request=options, upload=data)
    return Response(png, media_type="image/png", headers=headers)


@router.post("/eyedrop", response_model=EyedropOut, openapi_extra=IMAGE_BODY, responses=_TOO_LARGE)
async def eyedrop(
    request: Request,
    settings: SettingsDep,
    slots: ImageSlotsDep,
    _user: Stylist,
    face_x: Pixel,
    face_y: Pixel,
    flop_x: Pixel,
    flop_y: Pixel,
    gloss_x: Pixel | None = None,
    gloss_y: Pixel | None = None,
    gloss_gu: Annotated[
        float, Query(ge=0.0, le=100.0, description="gloss without the gloss eyedropper")
    ] = 50.0,
    travel_deg: Annotated[float, Query(gt=15.0, le=180.0, description="travel slider, degrees")] = 75.0,
    radius: Annotated[int, Query(ge=0, le=64, description="eyedropper radius, pixels")] = 3,
    auto_swap: Annotated[bool, Query(description="swap when the face is darker than the flop")] = True,
) -> dict[str, Any]:
    """Face and flop eyedroppers (robust average over a small region → Lab) and, with ``gloss_x``/``gloss_y``,
    the contrast-gloss eyedropper on an uploaded mood-board image (thesis §3.5). Pixel = (column, row)."""
    data = await request.body()
    gloss = (gloss_x, gloss_y) if gloss_x is not None and gloss_y is not None else None
    async with slots:
        return await asyncio.to_thread(
            service.eyedrop,
            data=data,
            max_bytes=settings.max_body_bytes,
            face=(face_x, face_y),
            flop=(flop_x, flop_y),
            gloss=gloss,
            gloss_gu=gloss_gu,
            travel_deg=travel_deg,
            radius=radius,
            auto_swap=auto_swap,
        )


@router.post("/sketch-fit", response_model=SketchFitOut, openapi_extra=IMAGE_BODY, responses=_TOO_LARGE)
async def sketch_fit(
    request: Request,
    settings: SettingsDep,
    slots: ImageSlotsDep,
    _user: Stylist,
    scene: Annotated[
        Literal["sphere-point", "panel-point"], Query(description="built-in point-light scene")
    ] = "sphere-point",
    gloss_mode: Annotated[Literal["highlight", "contrast", "default", "fit"], Query()] = "highlight",
) -> dict[str, Any]:
    """Fit a design to concept art painted over a built-in point-light scene (thesis §3.7, eq 3.7.2): the
    art is the upload, a square image the scene's size, painted over the scene rendered in silver."""
    data = await request.body()
    async with slots:
        return await asyncio.to_thread(
            service.sketch_fit,
            data=data,
            max_bytes=settings.max_body_bytes,
            scene_name=scene,
            gloss_mode=gloss_mode,
        )
