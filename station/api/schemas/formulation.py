"""Formulation (thesis §5.3): ColorSnap top-k, recipe formulation, XML / CxF3 export, library import."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator
from pydantic.config import JsonDict, JsonValue

from station.api.schemas.common import StrictBool, StrictFloat, StrictInt
from station.api.schemas.designs import DesignBody, Lab
from station.model.domain import (
    DEFAULT_MAX_COLORANTS,
    DEFAULT_SCALE_RESOLUTION_G,
    FORMULATION_TOLERANCE_DE00,
    GLOSS_MAX_GU,
    GLOSS_MIN_GU,
    MAX_COLORANTS_RANGE,
    SCALE_RESOLUTION_RANGE_G,
    TONER_LINES,
    PaintType,
    SnapMetric,
)
from station.schema_config import strict_config

#: A paint-type filter of one to three types (ColorSnap and formulation).
PaintTypes = Annotated[list[PaintType], Field(min_length=1, max_length=3)]
#: The name of one stored library (``extra.library`` of its paints, as GET /library/libraries lists).
LibraryName = Annotated[str, Field(min_length=1, max_length=64)]
_DESIGN: JsonDict = {
    "name": "Blue metallic",
    "face": [62.0, -4.0, -38.0],
    "flop": [24.0, 1.0, -20.0],
    "travel_deg": 70.0,
    "gloss_gu": 88.0,
}
_LAB: JsonValue = [[62.0, -4.0, -38.0], [40.0, -1.5, -29.0], [24.0, 1.0, -20.0]]


class DesignSource(BaseModel):
    """The target: exactly one of ``lab`` (at 15°/45°/110°), an inline ``design``, or a stored ``design_id``
    (``version``: default the latest)."""

    lab: (
        Annotated[list[Lab], Field(min_length=3, max_length=3, description="Lab at 15°, 45°, 110°")] | None
    ) = None
    design: DesignBody | None = None
    design_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    version: Annotated[StrictInt, Field(ge=1, le=1_000_000, description="default: the latest")] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> DesignSource:
        given = [n for n in ("lab", "design", "design_id") if getattr(self, n) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of lab, design, design_id (got {', '.join(given) or 'none'})")
        return self


class SnapRequest(DesignSource):
    """ColorSnap: the k nearest library paints by ΔE summed over 15°/45°/110°."""

    model_config = strict_config(
        examples=[
            {"lab": _LAB, "k": 5, "metric": "cie76"},
            {"design_id": 1, "k": 3, "metric": "cie2000"},
        ]
    )

    k: Annotated[StrictInt, Field(ge=1, le=50, description="matches returned, best first")] = 5
    metric: Annotated[
        SnapMetric, Field(description="ΔE summed over the angles (cie76 = ΔE*ab, the thesis's)")
    ] = "cie76"
    types: PaintTypes | None = Field(None, description="search only paints of these types; default all")
    library: LibraryName | None = Field(
        None,
        description="search one stored library (its name, as GET /library/libraries lists); "
        "default every stored paint",
    )


class SnapMatchOut(BaseModel):
    """One library paint: summed ΔE, ΔE per angle, its recipe when the library has one."""

    code: str
    library_paint_id: int
    type: PaintType
    library: str
    synthetic: bool
    sum_de: float
    de_per_angle: list[float]
    recipe: dict[str, float] | None


class SnapOut(BaseModel):
    """Matches (best first) and the Fig. 5.10 warnings (far from the library, travel not captured)."""

    matches: list[SnapMatchOut]
    warnings: list[str]
    method: str
    angles_deg: list[float]
    design_lab: list[list[float]]
    library_paints: int
    libraries: list[str]
    types: list[PaintType]
    synthetic: bool = Field(description="true when any match is a synthetic (generated) paint")


class FormulateRequest(DesignSource):
    """Formulate a recipe from the ColorSnap (CIEDE2000) matches' recipes (SYNTHETIC colorants)."""

    model_config = strict_config(
        examples=[{"lab": _LAB, "gloss_gu": 88.0, "tolerance": 1.0}, {"design": _DESIGN}]
    )

    gloss_gu: (
        Annotated[
            StrictFloat,
            Field(ge=GLOSS_MIN_GU, le=GLOSS_MAX_GU, description="60° gloss target; default the design's"),
        ]
        | None
    ) = None
    tolerance: Annotated[StrictFloat, Field(gt=0.0, le=20.0, description="mean ΔE00 for 'formulable'")] = (
        FORMULATION_TOLERANCE_DE00
    )
    k: Annotated[StrictInt, Field(ge=1, le=10, description="library matches tried as starting recipes")] = 3
    types: PaintTypes | None = Field(
        None, description="start only from matches of these paint types; default all"
    )
    library: LibraryName | None = Field(
        None,
        description="start only from one stored library's paints (GET /library/libraries); "
        "default every stored paint with a recipe",
    )
    illuminants: (
        Annotated[
            list[Annotated[str, Field(min_length=1, max_length=32)]],
            Field(
                min_length=1,
                max_length=8,
                description="rank the candidate recipes by metamerism index (reference D65) under these "
                'test illuminants, e.g. ["A", "F11"]',
            ),
        ]
        | None
    ) = None
    candidates: Annotated[
        StrictInt, Field(ge=1, le=12, description="with illuminants: starts tried to convergence at least")
    ] = 4
    line: Annotated[str, Field(min_length=1, max_length=32)] | None = Field(
        None,
        description="the toner line to formulate from (one of "
        + ", ".join(TONER_LINES)
        + "); default the line(s) the design's type calls for",
    )
    max_colorants: Annotated[
        StrictInt,
        Field(
            ge=MAX_COLORANTS_RANGE[0],
            le=MAX_COLORANTS_RANGE[1],
            description="most colorants in a recipe besides the binder (and matting agent)",
        ),
    ] = DEFAULT_MAX_COLORANTS
    scale_resolution_g: Annotated[
        StrictFloat,
        Field(
            ge=SCALE_RESOLUTION_RANGE_G[0],
            le=SCALE_RESOLUTION_RANGE_G[1],
            description="the scale's resolution in g: every amount is rounded to it for the 1000 g batch",
        ),
    ] = DEFAULT_SCALE_RESOLUTION_G


class FormulateOut(BaseModel):
    """``FormulationResult.to_dict()``: recipe, predicted Lab and ΔE00 per angle, formulable flag, plus the
    ColorSnap matches it started from."""

    model_config = ConfigDict(extra="allow")

    recipe: dict[str, float]
    angles_deg: list[float]
    design_lab: list[list[float]]
    predicted_lab: list[list[float]]
    de_per_angle: list[float]
    mean_de: float
    max_de: float
    formulable: bool
    message: str
    synthetic_colorants: bool
    matches: list[dict[str, Any]]
    snap_warnings: list[str]
    batch: dict[str, Any] = Field(
        description="the recipe weighed out as a 1000 g batch: colorants_g, binder_g, total_g"
    )
    nearest_achievable_lab: list[list[float]] | None = Field(
        default=None,
        description="when not formulable: Lab per angle of the best recipe (the nearest achievable paint)",
    )
    gamut: dict[str, Any] | None = Field(
        default=None,
        description="when not formulable: the N-colorant gamut verdict (station.formulate.gamut.recipe_gamut: "
        "inside, line_inside, mean_de, line_mean_de, max_colorants, line, recipe, needed_colorants, message); "
        "its message ends the result's message",
    )
    metamerism_ranking: dict[str, Any] | None = Field(
        default=None,
        description="with illuminants: the candidate recipes best first by metamerism index "
        "(station.formulate.metamerism: rule, illuminants, per candidate the index per illuminant and geometry)",
    )


class ExportRequest(BaseModel):
    """A design (inline or stored) exported with its ColorSnap match as the thesis's XML or CxF3."""

    model_config = strict_config(
        examples=[
            {"design": _DESIGN, "format": "xml", "match": True},
            {"design_id": 1, "format": "cxf", "five_angles": True},
        ]
    )

    design: DesignBody | None = None
    design_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    version: Annotated[StrictInt, Field(ge=1, le=1_000_000)] | None = None
    format: Literal["xml", "cxf"] = "xml"
    five_angles: Annotated[StrictBool, Field(description="also export 15/25/45/75/110")] = False
    match: Annotated[StrictBool, Field(description="add the ColorSnap match (needs a loaded library)")] = True
    metric: SnapMetric = "cie76"

    @model_validator(mode="after")
    def _one_source(self) -> ExportRequest:
        if (self.design is None) == (self.design_id is None):
            raise ValueError("give exactly one of design, design_id")
        return self


class LibraryImportOut(BaseModel):
    """What an import stored."""

    library: str
    paints: int
    angles_deg: list[float]
    types: dict[str, int]


class BrowsePaint(BaseModel):
    """A library paint in the browser: type, gloss, place in the hierarchy, Lab at 15/45/110 and the indices
    (eqs 5.3.1–5.3.3; null where undefined: a dark colour's Flop Index, an achromatic face's Hue Shift)."""

    code: str
    library_paint_id: int
    type: str
    gloss_gu: float | None
    group: list[str]
    lab_15_45_110: list[list[float]]
    indices: dict[str, float | None]


class BrowseOut(BaseModel):
    """The paints the filter keeps (a page of them), how many matched, and the hierarchy of the library."""

    library: str
    synthetic: bool
    matched: int
    paints: list[BrowsePaint]
    hierarchy: dict[str, dict[str, dict[str, int]]]


class ClosedLoopRequest(BaseModel):
    """Closed-loop prototyping of a stored design version: formulate, spray a simulated panel, measure it
    with the simulated spectrophotometer and gloss meter, correct; every step stored (SYNTHETIC)."""

    model_config = strict_config(examples=[{"design_id": 1, "corrections": 3, "tolerance": 1.0, "seed": 7}])

    design_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)]
    version: Annotated[StrictInt, Field(ge=1, le=1_000_000, description="default: the latest")] | None = None
    gloss_gu: (
        Annotated[
            StrictFloat,
            Field(ge=GLOSS_MIN_GU, le=GLOSS_MAX_GU, description="60° gloss target; default the design's"),
        ]
        | None
    ) = None
    tolerance: Annotated[StrictFloat, Field(gt=0.0, le=20.0, description="mean ΔE00 accepted")] = (
        FORMULATION_TOLERANCE_DE00
    )
    corrections: Annotated[
        StrictInt, Field(ge=0, le=5, description="correction steps after the first spray")
    ] = 3
    seed: Annotated[
        StrictInt, Field(ge=0, le=2**31 - 1, description="seed of the simulated spray-out panel")
    ] = 7


class ClosedLoopOut(BaseModel):
    """The stored job (``recipe_id`` reads back at ``GET /recipes/{id}``) and ``FormulationJob.to_dict()``."""

    model_config = ConfigDict(extra="allow")

    recipe_id: int
    status: str
    message: str
    corrections: int
    final_recipe: dict[str, float] | None
    steps: list[dict[str, Any]]
    measurement: str


class StoredLibraryOut(BaseModel):
    """One stored library: its name, paints per type, and whether its paints are synthetic."""

    name: str
    paints: int
    types: dict[str, int]
    synthetic: bool
