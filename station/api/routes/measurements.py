"""Measurements: ``/api/v1/measurements`` (create, corrections, query, CSV export)."""

from __future__ import annotations

import datetime as dt
from typing import Annotated

from fastapi import APIRouter, Depends, Query, Request, Response, status
from fastapi.responses import StreamingResponse
from pydantic import AwareDatetime
from sqlalchemy.orm import Session

from db.models import User
from station.api.deps import ReadSessionDep, SessionDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND
from station.api.json_guard import ParsedJsonRoute
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.schemas.measurements import CorrectionCreate, MeasurementPublic, MeasurementQuery
from station.api.schemas.panels import Job, Part
from station.api.security import Scope
from station.api.services import measurements as service
from station.ingest import Reading, StoreResult
from station.ingest.group import GroupCommit

router = APIRouter(
    prefix="/measurements", tags=["measurements"], responses=ERROR_RESPONSES, route_class=ParsedJsonRoute
)
Reader = Annotated[User, scoped(Scope.MEASUREMENTS_READ)]
Writer = Annotated[User, scoped(Scope.MEASUREMENTS_WRITE)]
Corrector = Annotated[User, scoped(Scope.MEASUREMENTS_CORRECT)]
Serial = Annotated[str, Query(min_length=1, max_length=64, description="instrument serial number")]


def _query(
    job: Annotated[Job | None, Query()] = None,
    part: Part | None = None,
    panel_id: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    instrument: Serial | None = None,
    since: Annotated[
        AwareDatetime | None, Query(description="measured at or after (ISO 8601 with zone)")
    ] = None,
    until: Annotated[AwareDatetime | None, Query(description="measured before (ISO 8601 with zone)")] = None,
    include_superseded: bool = False,
    illumination_deg: Annotated[
        float | None,
        Query(
            gt=0, lt=90, description="only this illumination block, degrees (e.g. 45; default: every block)"
        ),
    ] = None,
) -> MeasurementQuery:
    """The measurement filters of the query string (the list and the CSV export take the same)."""
    return MeasurementQuery(
        job=job,
        part=part,
        panel_id=panel_id,
        instrument=instrument,
        since=since,
        until=until,
        include_superseded=include_superseded,
        illumination_deg=illumination_deg,
    )


Filters = Annotated[MeasurementQuery, Depends(_query)]

#: The audit action of a reading stored through this route.
CREATE_ACTION = "measurement.create"


async def measurement_writes(request: Request) -> GroupCommit[MeasurementPublic]:
    """The app's group commit for this route (``app.state.measurement_writes``, made by ``create_app``)."""
    writes: GroupCommit[MeasurementPublic] = request.app.state.measurement_writes
    return writes


def _stored(session: Session, reading: Reading, result: StoreResult) -> MeasurementPublic:
    """The stored row as the route answers it: a new row from the values just inserted (what it
    reads back, with times in UTC), a row stored before read in the storing transaction."""
    row = result.row
    if not result.created or row is None:
        return service.get_measurement(session=session, measurement_id=result.measurement_id)
    data = {name: row[name] for name in MeasurementPublic.model_fields if name in row}
    for name in ("measured_at", "received_at"):
        data[name] = row[name].astimezone(dt.UTC)
    return MeasurementPublic(
        **data, id=result.measurement_id, instrument_serial=reading.instrument.serial, superseded_by_id=None
    )


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    response_model=MeasurementPublic,
    responses={
        200: {"model": MeasurementPublic, "description": "already stored (same client_id)"},
        **NOT_FOUND,
        **CONFLICT,
    },
)
async def create_measurement(
    request: Request,
    user: Writer,
    reading: Reading,
    response: Response,
    writes: Annotated[GroupCommit[MeasurementPublic], Depends(measurement_writes)],
) -> MeasurementPublic:
    """Store a reading once: re-sending the same ``client_id`` returns the stored row with 200.

    Readings posted at the same moment share one transaction (:class:`GroupCommit`); each answer
    comes once its reading is committed. The request waits on the event loop, without a thread of
    its own: a worker thread writes the groups, each on a session of the app's (``app.state.sessions``).
    """
    measurement, created = await writes.store_async(
        request.app.state.sessions, reading, actor_id=user.id, answer=_stored
    )
    if not created:
        response.status_code = status.HTTP_200_OK
    return measurement


@router.get("", response_model=Page[MeasurementPublic])
def list_measurements(
    session: ReadSessionDep, _user: Reader, q: Filters, limit: Limit = 100, offset: Offset = 0
) -> Page[MeasurementPublic]:
    """Query by job, part, panel, instrument, time and illumination block; newest first."""
    rows, total = service.query(session=session, q=q, limit=limit, offset=offset)
    return Page[MeasurementPublic](data=rows, count=total)


@router.get(
    "/export.csv",
    response_class=StreamingResponse,
    responses={
        200: {
            "content": {
                "text/csv": {
                    "schema": {"type": "string"},
                    "example": "measurement_id,client_id,...\n1,5b0c…,...\n",
                }
            },
            "description": "one line per measurement and geometry",
        }
    },
)
def export_csv(session: ReadSessionDep, _user: Reader, q: Filters) -> StreamingResponse:
    """The same filters as the list, as CSV (long format: one row per geometry)."""
    lines = list(service.export_csv(session=session, q=q))
    return StreamingResponse(
        iter(lines),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="measurements.csv"'},
    )


@router.get("/{measurement_id}", response_model=MeasurementPublic, responses=NOT_FOUND)
def get_measurement(session: ReadSessionDep, _user: Reader, measurement_id: Id) -> MeasurementPublic:
    """One measurement (with ``superseded_by_id`` when corrected)."""
    return service.get_measurement(session=session, measurement_id=measurement_id)


@router.post(
    "/{measurement_id}/corrections",
    status_code=status.HTTP_201_CREATED,
    response_model=MeasurementPublic,
    responses={**NOT_FOUND, **CONFLICT},
)
def correct_measurement(
    session: SessionDep, user: Corrector, measurement_id: Id, correction: CorrectionCreate
) -> MeasurementPublic:
    """Store a corrected reading that supersedes this one (the original is kept), with the reason."""
    return service.correct(session=session, actor=user, measurement_id=measurement_id, correction=correction)
