"""Instruments: ``/api/v1/instruments`` (list, connect, calibrate, measure); driver calls off the event loop."""

from __future__ import annotations

import asyncio
import uuid
from typing import Annotated

from fastapi import APIRouter, Header, Path, Query, Request, Response, status

from db.models import User
from station.api.deps import scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND, UNAVAILABLE
from station.api.instruments import InstrumentHub
from station.api.schemas.instruments import (
    CalibrateRequest,
    CalibrationPublic,
    ConnectRequest,
    InstrumentPublic,
    MeasureRequest,
    MeasureResult,
)
from station.api.security import Scope
from station.errors import InputError

router = APIRouter(prefix="/instruments", tags=["instruments"], responses={**ERROR_RESPONSES, **UNAVAILABLE})
Reader = Annotated[User, scoped(Scope.INSTRUMENTS_READ)]
Operator = Annotated[User, scoped(Scope.INSTRUMENTS_OPERATE)]
InstrumentId = Annotated[
    str,
    Path(
        min_length=1,
        max_length=80,
        pattern=r"^[a-z0-9_.-]+$",
        description="handle from the instrument list, e.g. ma6-sim00001",
    ),
]


_KEY_NAMESPACE = uuid.UUID("9d3f6b2a-4c1e-4f8a-b7d5-6e2a1c9f0b34")


def _hub(request: Request) -> InstrumentHub:
    return request.app.state.instruments


def client_id_of(body_id: uuid.UUID | None, key: str | None) -> uuid.UUID | None:
    """The request's client id: ``client_id``, else the ``Idempotency-Key`` (a UUID as it is, any other key hashed)."""
    if key is None:
        return body_id
    try:
        from_key = uuid.UUID(key)
    except ValueError:
        from_key = uuid.uuid5(_KEY_NAMESPACE, key)
    if body_id is not None and body_id != from_key:
        raise InputError("Idempotency-Key", f"the body's client_id {body_id} or no header", key)
    return from_key


@router.get("", response_model=list[InstrumentPublic])
async def list_instruments(request: Request, _user: Reader) -> list[InstrumentPublic]:
    """Attached instruments (simulators included) with their calibration state."""
    return await asyncio.to_thread(_hub(request).list)


@router.post(
    "/connect",
    status_code=status.HTTP_201_CREATED,
    response_model=InstrumentPublic,
    responses={**NOT_FOUND, **CONFLICT},
)
async def connect(request: Request, user: Operator, body: ConnectRequest) -> InstrumentPublic:
    """Open the instrument at a driver address and attach it."""
    return await asyncio.to_thread(_hub(request).connect, address=body.address, actor=user)


@router.post(
    "/{instrument_id}/calibrate", response_model=CalibrationPublic, responses={**NOT_FOUND, **CONFLICT}
)
async def calibrate(
    request: Request, user: Operator, instrument_id: InstrumentId, body: CalibrateRequest
) -> CalibrationPublic:
    """Run the calibration sequence (zero, white, verification) and store the record."""
    return await asyncio.to_thread(
        _hub(request).calibrate, instrument_id=instrument_id, reference=body.reference, actor=user
    )


@router.post(
    "/{instrument_id}/measure",
    status_code=status.HTTP_201_CREATED,
    response_model=MeasureResult,
    responses={**NOT_FOUND, **CONFLICT},
)
async def measure(
    request: Request,
    response: Response,
    user: Operator,
    instrument_id: InstrumentId,
    body: MeasureRequest,
    idempotency_key: Annotated[
        str | None,
        Header(
            min_length=1,
            max_length=255,
            pattern=r"^[\x21-\x7e]+$",
            description="client-chosen key making a retry store no second reading (alternative to client_id)",
        ),
    ] = None,
    gloss_instrument_id: Annotated[
        str | None,
        Query(
            min_length=1,
            max_length=80,
            pattern=r"^[a-z0-9_.-]+$",
            description="gloss meter to read 60° gloss from",
        ),
    ] = None,
) -> MeasureResult:
    """Measure the panel once and store the reading (Lab computed from the spectra, D65/10°).

    201 ``stored`` or ``queued`` (database away: kept in the outbox); 200 ``duplicate`` when a retry
    names a client id already stored (nothing is measured again).
    """
    result = await asyncio.to_thread(
        _hub(request).measure,
        instrument_id=instrument_id,
        req=body,
        gloss_instrument_id=gloss_instrument_id,
        actor=user,
        client_id=client_id_of(body.client_id, idempotency_key),
    )
    if result.status == "duplicate":
        response.status_code = status.HTTP_200_OK
    return result
