"""Panels: physical painted samples (job, part, substrate, notes)."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from station.schema_config import strict_config

Part = Literal[
    "bumper", "fender", "door", "hood", "trunk", "mirror", "roof", "quarter_panel", "test_panel", "other"
]
Job = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[^\x00-\x1f]+$", examples=["J-2026-0113"])]


class PanelCreate(BaseModel):
    """Properties to receive on creation."""

    model_config = strict_config(
        examples=[
            {
                "job": "J-2026-0113",
                "part": "bumper",
                "substrate": "PP/EPDM",
                "notes": "rear bumper, left of the plate",
            }
        ]
    )

    job: Job
    part: Part
    substrate: Annotated[str, Field(max_length=64)] = ""
    notes: Annotated[str, Field(max_length=4000)] = ""


class PanelPublic(PanelCreate):
    """A stored panel."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    created_at: dt.datetime
    created_by_id: int | None
