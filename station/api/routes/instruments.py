"""Instruments: ``/api/v1/instruments`` (list, connect, detach, calibrate in one call or step by step,
measure); driver calls off the event loop."""

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
    CalibrationSessionOut,
    CalibrationStart,
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


def client_id_of(body_id: uuid.UUID | None, key: str | None, user_id: int) -> uuid.UUID | None:
    """The request's client id: ``client_id``, else one derived from the ``Idempotency-Key`` and the user.

    A key is the client's name for one attempt, chosen per user ("scan-1"): the stored id is
    ``uuid5(namespace, "<user id>:<key>")`` for every key, a UUID key included, so two users' equal
    keys name two readings, while the same user's retry (any of its tokens, after a restart, while the
    reading waits in the outbox) derives the same id and gets its first answer. With both, the header
    must repeat the body's ``client_id`` (the client then named the reading's id itself; it is used as is).
    """
    if key is None:
        return body_id
    if body_id is not None:
        try:
            same = uuid.UUID(key) == body_id
        except ValueError:
            same = False
        if not same:
            raise InputError("Idempotency-Key", f"the body's client_id {body_id} or no header", key)
        return body_id
    return uuid.uuid5(_KEY_NAMESPACE, f"{user_id}:{key}")


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
    """Open the instrument at a driver address and attach it (a `sim:` address: at most max_simulators, 409 beyond)."""
    return await asyncio.to_thread(_hub(request).connect, address=body.address, actor=user)


@router.delete(
    "/{instrument_id}", status_code=status.HTTP_204_NO_CONTENT, response_class=Response, responses=NOT_FOUND
)
async def detach(request: Request, user: Operator, instrument_id: InstrumentId) -> Response:
    """Detach an instrument: close it and, for a simulator, end its process (frees a simulator slot)."""
    await asyncio.to_thread(_hub(request).detach, instrument_id=instrument_id, actor=user)
    return Response(status_code=status.HTTP_204_NO_CONTENT)


@router.post(
    "/{instrument_id}/calibrate", response_model=CalibrationPublic, responses={**NOT_FOUND, **CONFLICT}
)
async def calibrate(
    request: Request, user: Operator, instrument_id: InstrumentId, body: CalibrateRequest
) -> CalibrationPublic:
    """Run every calibration step (zero, white, verification; a gloss meter: its standard) without pausing,
    as `station calibrate --yes`, and store the record."""
    return await asyncio.to_thread(
        _hub(request).calibrate, instrument_id=instrument_id, reference=body.reference, actor=user
    )


CalibrationId = Annotated[uuid.UUID, Path(description="the session's id from POST /instruments/calibrations")]


@router.post(
    "/calibrations",
    status_code=status.HTTP_201_CREATED,
    response_model=CalibrationSessionOut,
    responses={**NOT_FOUND, **CONFLICT},
)
async def start_calibration(
    request: Request, _user: Operator, body: CalibrationStart
) -> CalibrationSessionOut:
    """Start a step-wise calibration (a spectrophotometer, then its gloss meter): every step with the prompt
    to show before it, nothing read yet."""
    return await asyncio.to_thread(
        _hub(request).start_calibration,
        instrument_id=body.instrument_id,
        gloss_instrument_id=body.gloss_instrument_id,
        reference=body.reference,
    )


@router.get("/calibrations/{session_id}", response_model=CalibrationSessionOut, responses=NOT_FOUND)
async def read_calibration(
    request: Request, _user: Operator, session_id: CalibrationId
) -> CalibrationSessionOut:
    """A calibration session's state between steps: the step to prompt for next, every step's status."""
    return _hub(request).calibrations.read(session_id)


@router.post(
    "/calibrations/{session_id}/step",
    response_model=CalibrationSessionOut,
    responses={**NOT_FOUND, **CONFLICT},
)
async def calibration_step(
    request: Request, user: Operator, session_id: CalibrationId
) -> CalibrationSessionOut:
    """Read the next reference (the operator has placed the instrument as its prompt said); after the last
    step the records are stored (``calibrated``); a failed step ends the session (``failed``, named)."""
    return await asyncio.to_thread(_hub(request).calibration_step, session_id=session_id, actor=user)


@router.post(
    "/calibrations/{session_id}/cancel",
    response_model=CalibrationSessionOut,
    responses={**NOT_FOUND, **CONFLICT},
)
async def cancel_calibration(
    request: Request, _user: Operator, session_id: CalibrationId
) -> CalibrationSessionOut:
    """End a calibration session between steps, not calibrated."""
    return _hub(request).calibrations.cancel(session_id)


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
            description="client-chosen key making a retry store no second reading (alternative to client_id); "
            "scoped to the user: another user's equal key names another reading",
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
        client_id=client_id_of(body.client_id, idempotency_key, user.id),
    )
    if result.status == "duplicate":
        response.status_code = status.HTTP_200_OK
    return result
