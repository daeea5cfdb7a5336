"""Formulation: ``/api/v1/formulation``: ColorSnap, recipe formulation, XML / CxF3 export (chemists and QA:
computed, nothing stored), and the closed loop (chemists: it stores a formulation job).

The library is the one in the database; its ColorSnap index is built once per app and library
(``app.state.library_cache``). CPU work runs in the thread pool (plain ``def`` routes).
"""

from __future__ import annotations

from typing import Annotated, Any
from urllib.parse import quote

from fastapi import APIRouter, Request, Response, status

from db.models import User
from station.api.deps import SessionDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.formulation import (
    ClosedLoopOut,
    ClosedLoopRequest,
    ExportRequest,
    FormulateOut,
    FormulateRequest,
    SnapOut,
    SnapRequest,
)
from station.api.security import Scope
from station.api.services import formulation as service

router = APIRouter(
    prefix="/formulation", tags=["formulation"], responses={**ERROR_RESPONSES, **NOT_FOUND, **CONFLICT}
)
Chemist = Annotated[User, scoped(Scope.RECIPES_WRITE)]
#: ColorSnap, formulate and export compute and store nothing: QA may judge a corrected paint with them.
Formulator = Annotated[User, scoped(Scope.FORMULATION_USE)]
_FILE: dict[int | str, dict[str, Any]] = {
    200: {
        "description": "the thesis's XML (§5.3.1) or CxF3 (ISO 17972) file; header X-Match-Code",
        "content": {"application/xml": {"schema": {"type": "string"}}},
    }
}


_HEADER_SAFE = "".join(chr(c) for c in range(0x20, 0x7F) if chr(c) != "%")


def header_safe(text: str) -> str:
    """*text* as an HTTP header value: printable ASCII kept, anything else (CR, LF, NUL, non-ASCII)
    percent-encoded as UTF-8 (RFC 3986), so a stored code can never split or break the response."""
    return quote(text, safe=_HEADER_SAFE, errors="backslashreplace")


@router.post("/snap", response_model=SnapOut)
def snap(request: Request, session: SessionDep, _user: Formulator, body: SnapRequest) -> dict[str, Any]:
    """ColorSnap: the k library paints nearest to the target by ΔE summed over 15°/45°/110° (cie76 = ΔE*ab as
    in the thesis, cie2000, din6175), exact, with the Fig. 5.10 warnings. Nothing is stored (a stored
    formulation job is ``POST /recipes``)."""
    return service.snap(session=session, cache=service.app_cache(request.app.state), request=body)


@router.post("/formulate", response_model=FormulateOut)
def formulate(
    request: Request, session: SessionDep, _user: Formulator, body: FormulateRequest
) -> dict[str, Any]:
    """A recipe for the target from the SYNTHETIC colorant database, started from the ColorSnap matches'
    recipes: predicted Lab and CIEDE2000 per angle, and whether it is formulable within the tolerance."""
    return service.formulate(session=session, cache=service.app_cache(request.app.state), request=body)


@router.post("/closed-loop", status_code=status.HTTP_201_CREATED, response_model=ClosedLoopOut)
def closed_loop(
    request: Request, session: SessionDep, user: Chemist, body: ClosedLoopRequest
) -> dict[str, Any]:
    """Closed-loop prototyping (beyond the thesis): recipe → simulated spray-out panel → simulated
    spectrophotometer and gloss meter → ΔE00 to the design → correction, as labs iterate; stored as one
    formulation job with every step (readable at ``GET /recipes/{id}``) and audited. SYNTHETIC."""
    return service.closed_loop(
        session=session, actor=user, cache=service.app_cache(request.app.state), request=body
    )


@router.post("/export", response_class=Response, responses=_FILE)
def export(request: Request, session: SessionDep, _user: Formulator, body: ExportRequest) -> Response:
    """The design at both 3-angle sets (15/45/110 and 25/45/75; 5 angles on request) and its ColorSnap
    match, as the thesis's XML or CxF3, as a file. ``X-Match-Code`` is the match's code, percent-encoded
    where it is not printable ASCII."""
    data, filename, code = service.export(
        session=session, cache=service.app_cache(request.app.state), request=body
    )
    headers = {"Content-Disposition": f'attachment; filename="{filename}"'}
    if code is not None:
        headers["X-Match-Code"] = header_safe(code)
    return Response(data, media_type="application/xml", headers=headers)
