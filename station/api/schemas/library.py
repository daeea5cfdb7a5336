"""Library paints."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict


class LibraryPaintPublic(BaseModel):
    """A library paint: Lab per aspecular angle (degrees), gloss (GU), place in the hierarchy."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    code: str
    name: str
    category: str
    family: str
    angles_deg: list[float]
    lab: list[list[float]]
    gloss_gu: float | None
    extra: dict[str, Any]
