"""Service errors and the one place where domain errors become HTTP responses.

``InputError`` → 422 in FastAPI's validation-error shape (with ``accepted``), not found → 404,
conflicts (and an instrument needing calibration) → 409, an instrument that cannot be reached → 503, other ``StationError`` → 500.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from sqlalchemy.exc import DBAPIError, InterfaceError, OperationalError

from db.errors import DatabaseUnavailableError, ImmutableRowError
from station.analysis.errors import AnalysisError
from station.api.json_guard import safe_text
from station.design.errors import DesignError
from station.drivers.errors import CalibrationNeeded, DriverError
from station.errors import InputError, StationError
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


def _statuses() -> tuple[tuple[type[BaseException], int], ...]:
    """(error class, HTTP status) in the order :func:`status_for` tries them. Built when an error is
    answered, not at import: the package :mod:`station.formulate` pulls in colour-science (a second or
    more of start-up), which a command that only reaches the user service (``station users``) never
    needs."""
    from station.formulate.errors import FormulateError

    return (
        (AnalysisError, 422),  # the panels cannot be analysed as given (e.g. a fit the model refuses)
        (ModelError, 422),
        (DesignError, 422),  # e.g. a sketch the fit cannot use
        (FormulateError, 422),  # e.g. a library without recipes
        (ReferenceNotFoundError, 404),
        (ClientIdConflictError, 409),
        (ImmutableRowError, 409),
        (DatabaseUnavailableError, 503),
    )


def status_for(exc: StationError) -> int:
    """HTTP status for a domain error."""
    if isinstance(exc, ApiError):
        return exc.status_code
    for cls, status in _statuses():
        if isinstance(exc, cls):
            return status
    if isinstance(exc, CalibrationNeeded):
        return 409
    if isinstance(exc, DriverError):
        return 503
    return 500


MAX_MSG = 1000


def _input_error_body(exc: InputError) -> dict[str, Any]:
    return {
        "detail": [
            {
                "loc": ["body", *(safe_text(p) for p in exc.field.split("."))],
                "msg": safe_text(str(exc), MAX_MSG),
                "type": "value_error",
                "ctx": {"accepted": exc.accepted},
            }
        ]
    }


def _safe_ctx_value(value: object) -> object:
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, int):
        return value if abs(value) < 2**63 else safe_text(value, MAX_MSG)
    if isinstance(value, float):
        return value if math.isfinite(value) else safe_text(value)
    return safe_text(value, MAX_MSG)


def validation_error_body(errors: Sequence[Any]) -> dict[str, Any]:
    """FastAPI's 422 body (``loc``, ``msg``, ``type``, ``ctx``) without the rejected ``input``.

    The bad value is never written back: it may be NaN or ±Infinity (not JSON), a lone surrogate (not
    encodable), raw bytes or megabytes of text. Member names in ``loc`` and the message are escaped and
    bounded, so the response always serialises and the connection stays open.
    """
    detail = []
    for err in errors:
        item: dict[str, Any] = {
            "loc": [p if isinstance(p, int) else safe_text(p) for p in err.get("loc", ())],
            "msg": safe_text(err.get("msg", ""), MAX_MSG),
            "type": safe_text(err.get("type", "value_error")),
        }
        ctx = err.get("ctx")
        if isinstance(ctx, dict) and ctx:
            item["ctx"] = {safe_text(k): _safe_ctx_value(v) for k, v in ctx.items()}
        detail.append(item)
    return {"detail": detail}


def install_error_handlers(app: FastAPI) -> None:
    """Map the domain hierarchy to HTTP once for the whole app."""

    @app.exception_handler(RequestValidationError)
    async def _invalid(_req: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse(validation_error_body(exc.errors()), status_code=422)

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
            body = {"detail": [{"loc": ["body"], "msg": safe_text(str(exc), MAX_MSG), "type": "value_error"}]}
            return JSONResponse(body, 422)
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
