"""Colour styling tools (thesis §3.4–§3.7): variations, palette swatch, eyedroppers, sketch fit."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator
from pydantic.config import JsonDict

from station.api.schemas.common import StrictBool, StrictFloat, StrictInt
from station.api.schemas.designs import DesignBody
from station.api.schemas.environment import (
    ENVIRONMENT_CHOICES,
    UPLOAD_DESCRIPTION,
    BuiltinEnvironment,
    EnvironmentTurn,
    UploadedEnvironment,
)
from station.model.flakes import FLAKE_RANGES
from station.render.scene_image import BUILTIN_MESHES, LOD_MAX_DE
from station.render.shapes import SHAPES
from station.schema_config import strict_config

_EXAMPLE: JsonDict = {
    "name": "Blue metallic",
    "face": [62.0, -4.0, -38.0],
    "flop": [24.0, 1.0, -20.0],
    "travel_deg": 70.0,
    "gloss_gu": 88.0,
}

#: Image uploads (eyedropper, sketch fit) are the raw PNG/JPEG request body, capped by the service's body
#: limit (``CACAD_MAX_BODY_BYTES``) and by ``station.design.images.load_image``'s guards.
IMAGE_BODY: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "description": "the image file (PNG or JPEG)",
        "content": {
            "image/png": {"schema": {"type": "string", "format": "binary"}},
            "image/jpeg": {"schema": {"type": "string", "format": "binary"}},
        },
    }
}
PNG_RESPONSE: dict[int | str, dict[str, Any]] = {
    200: {
        "content": {"image/png": {"schema": {"type": "string", "format": "binary"}}},
        "description": "a PNG image",
    }
}


class VariationsRequest(BaseModel):
    """The centre design, a step and a category (thesis §3.4.4)."""

    model_config = strict_config(examples=[{"design": _EXAMPLE, "degree": 5.0, "category": "face"}])

    design: DesignBody
    degree: Annotated[
        StrictFloat,
        Field(
            gt=0.0,
            le=50.0,
            allow_inf_nan=False,
            description="step: ΔE*ab for colours, degrees for travel, GU for gloss",
        ),
    ] = 5.0
    category: Literal["face", "flop", "travel-gloss"] = "face"


class Variation(BaseModel):
    """One variation: its label, the design (null when it would leave the model's range) and why."""

    label: str
    design: dict[str, Any] | None
    reason: str


class VariationsOut(BaseModel):
    """The ring of variations around the centre, deterministic."""

    centre: dict[str, Any]
    category: str
    degree: float
    variations: list[Variation]


class SwatchRequest(BaseModel):
    """A palette swatch (gradient bar 15°→110°, gloss as the border's brightness) or a booklet thumbnail."""

    model_config = strict_config(
        examples=[{"design": _EXAMPLE, "kind": "swatch", "width": 160, "height": 32, "border": 4}]
    )

    design: DesignBody
    kind: Literal["swatch", "booklet"] = "swatch"
    width: Annotated[StrictInt, Field(ge=8, le=1024, description="swatch width, pixels")] = 160
    height: Annotated[StrictInt, Field(ge=4, le=256, description="swatch height, pixels")] = 32
    border: Annotated[
        StrictInt, Field(ge=1, le=32, description="swatch border, pixels (< half the smaller side)")
    ] = 4
    size: Annotated[StrictInt, Field(ge=16, le=512, description="booklet thumbnail size, pixels")] = 96


class GlossOut(BaseModel):
    """The gloss eyedropper's contrast gloss (§3.5.3)."""

    gloss_gu: float
    contrast: float
    clipped: bool


class EyedropOut(BaseModel):
    """A design seeded by the eyedroppers, the sampled Labs, whether face and flop were swapped, and how the
    image's colour was interpreted."""

    design: dict[str, Any]
    face_lab: list[float]
    flop_lab: list[float]
    swapped: bool
    colour: str
    gloss: GlossOut | None = None


class LabStandard(BaseModel):
    """Lab of the fitted curve at the standard angles."""

    angles_deg: list[float]
    lab: list[list[float]]


class SketchFitOut(BaseModel):
    """The point-light sketch fit (§3.7): design, RMS ΔE*ab, failure flag and reason, wall time."""

    design: dict[str, Any]
    rms_de: float | None
    failed: bool
    seconds: float
    reason: str
    shading_de: float | None
    lab_standard: LabStandard
    theta_clamp_deg: float | None
    pixels: int
    gloss_source: str


def _flake_field(name: str, description: str) -> Any:
    lo, hi = FLAKE_RANGES[name]
    return Field(None, ge=lo, le=hi, allow_inf_nan=False, description=f"{description} ({lo} to {hi})")


class FlakeLayerBody(BaseModel):
    """A flake layer's physical parameters (``station.model.flakes.FlakeLayer``); missing fields take the
    defaults of the paint type (metallic)."""

    model_config = ConfigDict(extra="forbid")

    size_um: StrictFloat | None = _flake_field("size_um", "mean flake diameter, µm")
    density_per_mm2: StrictFloat | None = _flake_field("density_per_mm2", "flakes per mm² seen from above")
    spread_deg: StrictFloat | None = _flake_field("spread_deg", "flake-normal spread per axis, degrees")
    reflectance: StrictFloat | None = _flake_field("reflectance", "share of the reflection the flakes carry")


class RenderRequest(BaseModel):
    """A design (default: the thesis's silver) in a built-in point-light scene: the picture an artist paints
    over before ``/styling/sketch-fit`` (§3.7.1); or, with ``environment`` or ``environment_hdr``, lit by
    that environment on a shape with the stage options (backdrop, rotation, ground, exposure, clear coat).
    """

    model_config = strict_config(
        examples=[
            {"design": _EXAMPLE, "scene": "sphere-point", "size": 128},
            {"scene": "panel-point", "size": 96},
            {"design": _EXAMPLE, "environment": "sky", "shape": "speedshape", "size": 256},
        ]
    )

    design: DesignBody | None = None
    scene: Literal["sphere-point", "panel-point"] = "sphere-point"
    size: Annotated[StrictInt, Field(ge=16, le=512, description="square image side, pixels")] = 128
    environment: BuiltinEnvironment = Field(
        None,
        description=f"built-in environment ({ENVIRONMENT_CHOICES}); the render is then "
        "environment-lit instead of the point-light scene",
    )
    environment_hdr: UploadedEnvironment = Field(
        None,
        description=UPLOAD_DESCRIPTION
        + "; the service's body cap applies first), instead of a built-in environment",
    )
    design2: DesignBody | None = Field(
        None, description="environment renders: a second design on the right half"
    )
    shape: str = Field(
        "speedshape", description="environment renders: the shape", json_schema_extra={"enum": list(SHAPES)}
    )
    backdrop: StrictBool = Field(True, description="show the environment behind the shape")
    backdrop_blur_deg: Annotated[
        StrictFloat, Field(ge=0.0, le=90.0, description="backdrop blur, degrees")
    ] = 0.0
    rotation_deg: EnvironmentTurn = 0.0
    ground: StrictBool = Field(True, description="ground disc with contact shadow")
    exposure_ev: Annotated[StrictFloat, Field(ge=-10.0, le=10.0, description="exposure, EV")] = 0.0
    coat_index: Annotated[
        StrictFloat | None,
        Field(
            gt=1.0,
            le=3.0,
            description="clear coat's refractive index (Schlick Fresnel on the gloss); "
            "null: no Fresnel, the thesis's model",
        ),
    ] = 1.5
    flakes: StrictBool = Field(
        False,
        description="environment renders: draw the design's flake layer (the paint type's default, or "
        "flake_layer); the level of detail switches it off where flakes are far below a pixel and says so "
        "in the X-Flakes header",
    )
    flake_layer: FlakeLayerBody | None = Field(None, description="with flakes: the layer's parameters")
    mesh: Literal[BUILTIN_MESHES] | None = Field(  # type: ignore[valid-type]
        None, description="environment renders: a built-in mesh instead of the shape (car: procedural body)"
    )
    lod_de: Annotated[
        StrictFloat | None,
        Field(
            gt=0.0,
            le=LOD_MAX_DE,
            allow_inf_nan=False,
            description="CIEDE2000 tolerance: the level of detail picks lobes and environment resolution "
            "(X-Lod header); null: the default basis",
        ),
    ] = None

    @field_validator("shape")
    @classmethod
    def _known_shape(cls, v: str) -> str:
        if v not in SHAPES:
            raise ValueError("expected " + " | ".join(SHAPES))
        return v
