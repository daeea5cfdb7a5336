"""Service errors and the one place where domain errors become HTTP responses.

``InputError`` → 422 in FastAPI's validation-error shape (with ``accepted``), not found → 404,
conflicts (and an instrument needing calibration) → 409, an instrument that cannot be reached → 503, other ``StationError`` → 500.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from sqlalchemy.exc import DBAPIError, InterfaceError, OperationalError

from db.errors import DatabaseUnavailableError, ImmutableRowError
from station.analysis.errors import AnalysisError
from station.design.errors import DesignError
from station.drivers.errors import CalibrationNeeded, DriverError
from station.errors import InputError, StationError
from station.formulate.errors import FormulateError
from station.ingest import ClientIdConflictError, ReferenceNotFoundError
from station.model.errors import ModelError

log = logging.getLogger(__name__)


class ApiError(StationError):
    """Base of errors raised by the service layer."""

    status_code = 500


class NotFoundError(ApiError, LookupError):
    """The named resource does not exist."""

    status_code = 404


class ConflictError(ApiError):
    """The request contradicts stored state (already superseded, name taken …)."""

    status_code = 409


class UnavailableError(ApiError):
    """A dependency (instrument, database) cannot be reached now; retry later."""

    status_code = 503


class ErrorOut(BaseModel):
    """Body of every non-validation error."""

    detail: str


_STATUS: list[tuple[type[BaseException], int]] = [
    (AnalysisError, 422),  # the panels cannot be analysed as given (e.g. a fit the model refuses)
    (ModelError, 422),
    (DesignError, 422),  # e.g. a sketch the fit cannot use
    (FormulateError, 422),  # e.g. a library without recipes
    (ReferenceNotFoundError, 404),
    (ClientIdConflictError, 409),
    (ImmutableRowError, 409),
    (DatabaseUnavailableError, 503),
]


def status_for(exc: StationError) -> int:
    """HTTP status for a domain error."""
    if isinstance(exc, ApiError):
        return exc.status_code
    for cls, status in _STATUS:
        if isinstance(exc, cls):
            return status
    if isinstance(exc, CalibrationNeeded):
        return 409
    if isinstance(exc, DriverError):
        return 503
    return 500


def _input_error_body(exc: InputError) -> dict[str, Any]:
    return {
        "detail": [
            {
                "loc": ["body", *exc.field.split(".")],
                "msg": str(exc),
                "type": "value_error",
                "ctx": {"accepted": exc.accepted},
            }
        ]
    }


def install_error_handlers(app: FastAPI) -> None:
    """Map the domain hierarchy to HTTP once for the whole app."""

    @app.exception_handler(InputError)
    async def _input(_req: Request, exc: InputError) -> JSONResponse:
        return JSONResponse(_input_error_body(exc), status_code=422)

    @app.exception_handler(OperationalError)
    @app.exception_handler(InterfaceError)
    async def _db_away(_req: Request, exc: DBAPIError) -> JSONResponse:
        log.error("database unavailable: %s", exc.orig)
        return JSONResponse({"detail": "database unavailable; retry later"}, status_code=503)

    @app.exception_handler(StationError)
    async def _station(_req: Request, exc: StationError) -> JSONResponse:
        status = status_for(exc)
        if status == 422:  # same shape as request validation errors
            return JSONResponse({"detail": [{"loc": ["body"], "msg": str(exc), "type": "value_error"}]}, 422)
        if status >= 500:
            log.error("%s: %s", type(exc).__name__, exc)
        return JSONResponse({"detail": str(exc)}, status_code=status)


#: OpenAPI entries for the error statuses a protected route can return.
ERROR_RESPONSES: dict[int | str, dict[str, Any]] = {
    401: {"model": ErrorOut, "description": "missing, unknown or revoked bearer token"},
    403: {"model": ErrorOut, "description": "the token's role lacks the scope this route needs"},
}
NOT_FOUND: dict[int | str, dict[str, Any]] = {404: {"model": ErrorOut, "description": "no such resource"}}
CONFLICT: dict[int | str, dict[str, Any]] = {
    409: {"model": ErrorOut, "description": "conflicts with stored state"}
}
UNAVAILABLE: dict[int | str, dict[str, Any]] = {
    503: {"model": ErrorOut, "description": "instrument or database unreachable"},
}
