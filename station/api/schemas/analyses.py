"""Analyses: stored misalignment QA of two measured panels (thesis ch. 4)."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field


class SeamQaCreate(BaseModel):
    """Two measurements (panel A: reference, panel B: misaligned by β) and the judging tolerance."""

    model_config = ConfigDict(extra="forbid", json_schema_extra={
        "examples": [{"measurement_a": 1, "measurement_b": 2, "beta_deg": 5.0, "tolerance": 2.3, "method": "cie76"}]})

    measurement_a: Annotated[int, Field(ge=1, le=2**31 - 1, description="e.g. the fender")]
    measurement_b: Annotated[int, Field(ge=1, le=2**31 - 1, description="e.g. the bumper")]
    beta_deg: Annotated[float, Field(ge=-45.0, le=45.0, description="signed misalignment of panel B, degrees")]
    tolerance: Annotated[float, Field(gt=0.0, le=50.0, description="seam ΔE accepted (1 JND = 2.3 ΔE*ab)")] = 2.3
    method: Literal["cie76", "cie94", "cie2000", "din6175"] = "cie76"


class AnalysisPublic(BaseModel):
    """A stored analysis: kind, inputs, the JSON result, who ran it and when."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    kind: str
    inputs: dict[str, Any]
    result: dict[str, Any]
    created_at: dt.datetime
    created_by_id: int | None
