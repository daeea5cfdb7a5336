"""Recipes: formulation jobs that snap a design to its nearest library paints (thesis §5.3.5)."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any

from pydantic import BaseModel, Field

from station.api.schemas.common import StrictInt
from station.model.domain import SnapMetric
from station.schema_config import strict_config

Metric = SnapMetric


class RecipeCreate(BaseModel):
    """Which design version to formulate, how many candidates, which colour difference."""

    model_config = strict_config(examples=[{"design_id": 1, "version": None, "k": 5, "metric": "cie2000"}])

    design_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)]
    version: Annotated[StrictInt, Field(ge=1, le=1_000_000, description="default: the latest")] | None = None
    k: Annotated[StrictInt, Field(ge=1, le=20, description="candidates returned, best first")] = 5
    metric: Metric = "cie2000"


class SnapCandidate(BaseModel):
    """One library paint: summed ΔE over 15°/45°/110° and ΔE per angle."""

    code: str
    library_paint_id: int
    sum_de: float
    de_per_angle: list[float]
    recipe: dict[str, float] | None


class RecipePublic(BaseModel):
    """A stored formulation job: the target Lab, the candidates, the recipe of the best one."""

    id: int
    state: str
    design_id: int
    design_version: int
    metric: str
    angles_deg: list[float]
    target_lab: list[list[float]]
    candidates: list[SnapCandidate]
    recipe: dict[str, float] | None
    warnings: list[str]
    created_at: dt.datetime
    created_by_id: int | None

    @classmethod
    def from_job(cls, job: Any, design_id: int, version: int) -> RecipePublic:
        result = job.recipe or {}
        return cls(
            id=job.id,
            state=job.state,
            design_id=design_id,
            design_version=version,
            metric=job.target.get("metric", ""),
            angles_deg=job.target.get("angles_deg", []),
            target_lab=job.target.get("lab", []),
            candidates=result.get("candidates", []),
            recipe=result.get("recipe"),
            warnings=result.get("warnings", []),
            created_at=job.created_at,
            created_by_id=job.created_by_id,
        )
