"""``GET /health``: liveness and database reachability (no token)."""

from __future__ import annotations

from fastapi import APIRouter, Request
from pydantic import BaseModel
from sqlalchemy import text

from station import __version__

router = APIRouter(tags=["health"])


class Health(BaseModel):
    """Service status."""

    status: str
    version: str
    database: str


@router.get("/health", response_model=Health)
def health(request: Request) -> Health:
    """Whether the service runs and reaches its database."""
    try:
        with request.app.state.engine.connect() as conn:
            conn.execute(text("SELECT 1"))
        database = "ok"
    except Exception:
        database = "unreachable"
    return Health(status="ok", version=__version__, database=database)
