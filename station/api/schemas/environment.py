"""The environment inputs of the styling and analysis requests: a built-in environment by name or an
uploaded equirectangular map (size-capped), and its turn about the vertical."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, Field

from station.api.schemas.common import StrictFloat
from station.render.procedural import NAMES
from station.render.scene_image import MAX_UPLOAD_BASE64_CHARS, MAX_UPLOAD_BYTES

#: Routes whose JSON body may carry an uploaded map (``environment_hdr``), under the API prefix, and their
#: body cap: the base64 of a MAX_UPLOAD_BYTES file plus 64 KiB for the rest of the request (the service's
#: general cap, ``max_body_bytes``, applies instead when larger).
ENVIRONMENT_UPLOAD_PATHS = ("/styling/render", "/analyses/gg-index/environment")
ENVIRONMENT_BODY_BYTES = MAX_UPLOAD_BASE64_CHARS + 65_536
#: The multipart route that takes the map as a file part ``environment_hdr`` (under the API prefix), and its
#: body cap: a MAX_UPLOAD_BYTES file plus 64 KiB for the part headers and the ``request`` part; a larger
#: body is a 413 naming ``environment_hdr`` (``station.api.middleware.BodySizeLimit``).
ENVIRONMENT_MULTIPART_PATH = "/styling/render/upload"
ENVIRONMENT_MULTIPART_BYTES = MAX_UPLOAD_BYTES + 65_536
ENVIRONMENT_FILE_FIELD = "environment_hdr"
#: "booth | sky | ..." for descriptions and error messages.
ENVIRONMENT_CHOICES = " | ".join(NAMES)
#: Description of an uploaded map's field (the byte and pixel caps of ``station.render.scene_image``).
UPLOAD_DESCRIPTION = (
    f"base64 of an equirectangular .hdr/.exr file (at most {MAX_UPLOAD_BYTES} bytes, 2048 x 1024 pixels"
)


def known_environment(v: str | None) -> str | None:
    """*v* when it names a built-in environment (or is None); ValueError naming the choices otherwise."""
    if v is not None and v not in NAMES:
        raise ValueError("expected " + ENVIRONMENT_CHOICES)
    return v


#: A built-in environment's name, or None.
BuiltinEnvironment = Annotated[
    str | None, AfterValidator(known_environment), Field(json_schema_extra={"enum": list(NAMES)})
]
#: The base64 text of an uploaded .hdr/.exr, capped before decoding, or None.
UploadedEnvironment = Annotated[str | None, Field(max_length=MAX_UPLOAD_BASE64_CHARS)]
#: The environment's turn about the vertical, degrees.
EnvironmentTurn = Annotated[
    StrictFloat, Field(ge=-360.0, le=360.0, description="environment turn about the vertical, degrees")
]
