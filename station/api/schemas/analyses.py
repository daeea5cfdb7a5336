"""Analyses: misalignment QA (thesis ch. 4): stored seam QA, goniogeometric index, trompe l'oeil, sweep."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator
from pydantic.config import JsonDict

from station.api.schemas.common import Polar, StrictBool, StrictFloat, StrictInt
from station.api.schemas.designs import DesignBody
from station.api.schemas.environment import (
    ENVIRONMENT_CHOICES,
    UPLOAD_DESCRIPTION,
    BuiltinEnvironment,
    EnvironmentTurn,
    UploadedEnvironment,
)
from station.model.domain import BETA_MAX_RANGE_DEG, JND_CIE76, DeltaEComputed, DeltaEEnvironment
from station.schema_config import strict_config

Method = DeltaEComputed
Hinge = Annotated[
    Literal["in-plane", "out-of-plane"]
    | Annotated[StrictFloat, Field(ge=-180.0, le=180.0, allow_inf_nan=False)],
    Field(description="in-plane | out-of-plane | hinge azimuth in degrees"),
]
Epsilon = Annotated[
    StrictFloat,
    Field(
        gt=0.0,
        le=50.0,
        allow_inf_nan=False,
        description="ΔE threshold ε in units of `method` (1 JND = 2.3 ΔE*ab)",
    ),
]
Beta = Annotated[
    StrictFloat,
    Field(
        ge=-45.0,
        le=45.0,
        allow_inf_nan=False,
        description="signed misalignment of panel B, degrees (0 < |β| <= 45)",
    ),
]
Lights = Annotated[list[Polar], Field(min_length=1, max_length=16, description="light polar angles, degrees")]
#: The index search's options shared by the point-lit and the environment-lit index.
Direction = Literal["+", "-", "either"]
BetaMax = Annotated[
    StrictFloat,
    Field(
        ge=BETA_MAX_RANGE_DEG[0],
        le=BETA_MAX_RANGE_DEG[1],
        description=f"largest β searched, degrees ({BETA_MAX_RANGE_DEG[0]:g} to {BETA_MAX_RANGE_DEG[1]:g})",
    ),
]
IncludeGloss = Annotated[StrictBool, Field(description="add the gloss lobe (excluded in the thesis)")]

_PAINT: JsonDict = {
    "face": [60.0, -4.0, -42.0],
    "flop": [18.0, 2.0, -22.0],
    "travel_deg": 55.0,
    "gloss_gu": 88.0,
}
_GREY: JsonDict = {"face": [50.0, 0.0, 0.0], "flop": [50.0, 0.0, 0.0], "travel_deg": None}


class SeamQaCreate(BaseModel):
    """Two panels (A: reference, B: misaligned by β), each a stored measurement or a design, the geometries
    and the judging tolerance."""

    model_config = strict_config(
        examples=[
            {
                "measurement_a": 1,
                "measurement_b": 2,
                "beta_deg": 5.0,
                "tolerance": 2.3,
                "method": "cie76",
            },
            {"design_a": _PAINT, "design_b": _PAINT, "beta_deg": 8.0, "lights_deg": [30.0, 45.0, 60.0]},
        ]
    )

    measurement_a: Annotated[StrictInt, Field(ge=1, le=2**31 - 1, description="e.g. the fender")] | None = (
        None
    )
    measurement_b: Annotated[StrictInt, Field(ge=1, le=2**31 - 1, description="e.g. the bumper")] | None = (
        None
    )
    design_a: (
        Annotated[DesignBody, Field(description="panel A as a design instead of a measurement")] | None
    ) = None
    design_b: (
        Annotated[DesignBody, Field(description="panel B as a design instead of a measurement")] | None
    ) = None
    beta_deg: Beta
    tolerance: Annotated[
        StrictFloat, Field(gt=0.0, le=50.0, description="seam ΔE accepted (1 JND = 2.3 ΔE*ab)")
    ] = JND_CIE76
    method: Method = "cie76"
    lights_deg: Lights = [30.0, 45.0, 60.0]
    aspecular_deg: Annotated[
        list[Annotated[StrictFloat, Field(ge=-89.0, le=179.0, allow_inf_nan=False)]],
        Field(min_length=1, max_length=16, description="aspecular angles on panel A"),
    ] = [15.0, 25.0, 45.0, 75.0]
    hinge: Hinge = "in-plane"
    objective: Literal["rms", "minimax"] = "minimax"
    illuminant: Annotated[
        str,
        Field(
            min_length=1,
            max_length=32,
            description="judge the seam under this illuminant (e.g. A, F11): the measurements' Lab is taken "
            "from their spectra under it; other than D65 both panels must be measurements with spectra",
        ),
    ] = "D65"

    @model_validator(mode="after")
    def _one_source_per_panel(self) -> SeamQaCreate:
        for side in ("a", "b"):
            if (getattr(self, f"measurement_{side}") is None) == (getattr(self, f"design_{side}") is None):
                raise ValueError(
                    f"panel {side.upper()}: give exactly one of measurement_{side} and design_{side}"
                )
        return self


class GgIndexRequest(BaseModel):
    """Goniogeometric index β_min (eq 4.3.1) of one paint on both panels, for point lights and views."""

    model_config = strict_config(
        examples=[
            {"paint": _GREY, "lights_deg": [30.0], "views_deg": [0.0], "epsilon": 2.3, "method": "cie76"},
            {"paint": _PAINT, "lights_deg": [45.0], "direction": "either", "per_geometry": True},
        ]
    )

    paint: DesignBody
    lights_deg: Lights
    views_deg: (
        Annotated[
            list[Polar],
            Field(min_length=1, max_length=64, description="view polar angles; null: aspecular 15–110° scan"),
        ]
        | None
    ) = None
    epsilon: Epsilon = JND_CIE76
    method: Method = "cie76"
    hinge: Hinge = "in-plane"
    direction: Direction = "either"
    beta_max_deg: BetaMax = 30.0
    include_gloss: IncludeGloss = False
    per_geometry: Annotated[StrictBool, Field(description="list β_min for every geometry")] = False


class GgIndexOut(BaseModel):
    """``IndexResult.to_dict()``: β_min in degrees (null when ε is never reached up to β_max) and where."""

    model_config = ConfigDict(extra="allow")

    beta_min_deg: float | None
    reached: bool
    direction: str | None
    geometry: dict[str, Any] | None
    epsilon: float
    method: str
    message: str


class GgIndexEnvironmentRequest(BaseModel):
    """Environment-lit goniogeometric index (eq 4.3.1, thesis §4.3): one paint on both panels lit by a
    built-in environment or an uploaded .hdr/.exr (the same inputs as ``/styling/render``)."""

    model_config = strict_config(
        examples=[{"paint": _PAINT, "environment": "sky", "views_deg": [0.0, 30.0], "panel": "up"}]
    )

    paint: DesignBody
    environment: BuiltinEnvironment = Field(
        None, description=f"built-in environment ({ENVIRONMENT_CHOICES}); or environment_hdr"
    )
    environment_hdr: UploadedEnvironment = Field(None, description=UPLOAD_DESCRIPTION + ")")
    rotation_deg: EnvironmentTurn = 0.0
    panel: Literal["up", "front"] = Field(
        "up", description="panel A's orientation: up (bonnet, roof) or front (a door facing +Z)"
    )
    views_deg: (
        Annotated[
            list[Polar],
            Field(min_length=1, max_length=64, description="view polar angles in the panel's x-z plane"),
        ]
        | None
    ) = None
    epsilon: Epsilon = JND_CIE76
    method: DeltaEEnvironment = "cie76"
    hinge: Hinge = "in-plane"
    direction: Direction = "either"
    beta_max_deg: BetaMax = 30.0
    include_gloss: IncludeGloss = False
    per_geometry: Annotated[StrictBool, Field(description="list β_min for every view")] = False


class TrompeRequest(BaseModel):
    """Inverse trompe l'oeil (§4.4): paint B for the panel misaligned by β."""

    model_config = strict_config(
        examples=[
            {
                "paint": _GREY,
                "lights_deg": [0.0, 15.5, 29.1, 39.8, 45.0, 52.0],
                "beta_deg": -3.0,
                "objective": "rms",
            },
        ]
    )

    paint: DesignBody
    lights_deg: Annotated[list[Polar], Field(min_length=1, max_length=32, description="light polar angles")]
    views_deg: (
        Annotated[
            list[Polar],
            Field(min_length=1, max_length=32, description="one view per light; null: the normal"),
        ]
        | None
    ) = None
    beta_deg: Beta
    objective: Literal["single", "rms", "minimax", "per_geometry"] = "rms"
    at: Annotated[StrictInt, Field(ge=0, le=31, description="geometry index for objective single")] = 0
    subset: (
        Annotated[
            str,
            Field(
                max_length=80,
                pattern=r"^[A-Za-z_+]+$",
                description="solid | face_L | face_L+travel | face | face+travel | full | "
                "parameter names joined by +",
            ),
        ]
        | None
    ) = None
    hinge: Hinge = "in-plane"
    method: Method = "cie76"
    epsilon: Epsilon = JND_CIE76
    allow_face_darker: bool = False


class TrompeOut(BaseModel):
    """``TrompeResult.to_dict()``: the paint for panel B and the seam ΔE before and after."""

    model_config = ConfigDict(extra="allow")

    objective: str
    subset: str
    paint: dict[str, Any]
    seam_de_before: list[float]
    seam_de_after: list[float]
    meets_epsilon: bool
    message: str


class SweepRequest(BaseModel):
    """Seam ΔE of one paint over β × light × view (thesis Fig. 4.3)."""

    model_config = strict_config(
        examples=[
            {
                "paint": _PAINT,
                "betas_deg": [1.0, 3.0, 8.0],
                "lights_deg": [15.0, 45.0],
                "views_deg": [-30.0, 0.0, 30.0],
            },
        ]
    )

    paint: DesignBody
    betas_deg: Annotated[list[Beta], Field(min_length=1, max_length=16)] = [0.5, 1.0, 2.0, 3.0, 5.0, 8.0]
    lights_deg: Annotated[list[Polar], Field(min_length=1, max_length=8)] = [15.0, 30.0, 45.0, 60.0]
    views_deg: (
        Annotated[
            list[Polar],
            Field(min_length=1, max_length=91, description="view polar angles; null: −80…80 step 2"),
        ]
        | None
    ) = None
    hinge: Hinge = "in-plane"
    method: Method = "cie76"
    epsilon: Epsilon = JND_CIE76


class SweepOut(BaseModel):
    """``SweepResult.to_dict()``: ``delta_e[β][light][view]`` (−1 where panel B faces away)."""

    model_config = ConfigDict(extra="allow")

    betas_deg: list[float]
    lights_deg: list[float]
    views_deg: list[float]
    delta_e: list[list[list[float]]]
    index_estimate_deg: float | None


class AnalysisPublic(BaseModel):
    """A stored analysis: kind, inputs, the JSON result, who ran it and when."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    kind: str
    inputs: dict[str, Any]
    result: dict[str, Any]
    created_at: dt.datetime
    created_by_id: int | None
