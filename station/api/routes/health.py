"""``GET /health``: liveness, database reachability and the outbox backlog (no token).

Always 200 while the service runs: ``status`` is ``ok``, or ``degraded`` while the database is away
(readings are then kept in the outbox, ``queued`` of them so far, and replayed when it is back).
``database`` tells the three cases apart: ``ok``; ``busy``, a healthy database whose write lock
another connection holds right now (readers and the probe do not wait for it, writers queue; the
status stays ``ok`` and readings are stored, not queued); ``unreachable``, the database cannot be
opened or read, or a write gave up on it. A monitor that wants a failing status code checks
``status``. The probe only reads (see :func:`~station.api.availability.probe_database`) and is
bounded (any backend: 2 s in all); while the service already knows the database is away it is not
probed here at all.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Request
from pydantic import BaseModel, Field

from station import __version__
from station.api.availability import PROBE_OK, DatabaseState, probe_database

router = APIRouter(tags=["health"])

PROBE_TIMEOUT_S = 2.0


class Health(BaseModel):
    """Service status."""

    status: str = Field(description="ok, or degraded while the database is away")
    version: str
    database: str = Field(
        description="ok; busy (answers, its write lock held by another connection: writers queue); "
        "or unreachable (cannot be opened or read: readings go to the outbox)"
    )
    queued: int = Field(0, description="readings waiting in the outbox for the database")


def _queued(request: Request) -> int:
    hub = getattr(request.app.state, "instruments", None)
    settings = request.app.state.settings
    if hub is None or not settings.outbox_path.exists():
        return 0
    return len(hub.outbox())


@router.get("/health", response_model=Health)
async def health(request: Request) -> Health:
    """Whether the service runs, reaches its database, and how many readings wait in the outbox."""
    database: DatabaseState = request.app.state.database
    engine = getattr(request.app.state, "engine", None)
    answer = PROBE_OK
    if engine is not None and not database.away:
        try:
            answer = await asyncio.wait_for(
                asyncio.to_thread(probe_database, engine), timeout=PROBE_TIMEOUT_S
            )
        except Exception as exc:
            database.mark_away(exc)
    queued = await asyncio.to_thread(_queued, request)
    if database.away:
        return Health(status="degraded", version=__version__, database="unreachable", queued=queued)
    return Health(status="ok", version=__version__, database=answer, queued=queued)
