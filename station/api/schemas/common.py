"""Pieces shared by the resource schemas."""

from __future__ import annotations

from typing import Annotated, Generic, TypeVar

from pydantic import BaseModel, Field

T = TypeVar("T")

#: Numbers of JSON bodies: no bool → number, no numeric string → number, no NaN/±inf (an int is a float).
StrictFloat = Annotated[float, Field(strict=True, allow_inf_nan=False)]
StrictInt = Annotated[int, Field(strict=True)]
StrictBool = Annotated[bool, Field(strict=True)]

#: Path and query parameters arrive as text: these stay lax (``"7"`` → 7).
Id = Annotated[int, Field(ge=1, le=2**31 - 1)]
Limit = Annotated[int, Field(ge=1, le=1000, description="page size")]
Offset = Annotated[int, Field(ge=0, le=10_000_000, description="rows to skip")]


class Page(BaseModel, Generic[T]):
    """A page of rows and the total count matching the query."""

    data: list[T]
    count: int


#: Signed polar angle of a light or viewer in degrees (station.analysis.geometry: |θ| <= 89).
Polar = Annotated[float, Field(strict=True, ge=-89.0, le=89.0, allow_inf_nan=False)]
