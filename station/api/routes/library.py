"""Library paints: ``/api/v1/library`` (browse; CSV export for readers, CSV import for chemists)."""

from __future__ import annotations

import asyncio
import codecs
from typing import Annotated, Literal

from fastapi import APIRouter, Path, Query, Request, Response, status

from db.models import User
from station.api.deps import ReadSessionDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.common import Limit, Offset, Page
from station.api.schemas.formulation import BrowseOut, LibraryImportOut, StoredLibraryOut
from station.api.schemas.library import LibraryPaintPublic
from station.api.security import Scope
from station.api.services import formulation
from station.api.services import library as service
from station.errors import InputError
from station.model.domain import PaintType

router = APIRouter(prefix="/library", tags=["library"], responses=ERROR_RESPONSES)
#: Path of the CSV upload under the API prefix; its body cap is ``Settings.library_upload_max_bytes``.
IMPORT_PATH = "/library/import"
Reader = Annotated[User, scoped(Scope.LIBRARY_READ)]
Importer = Annotated[User, scoped(Scope.LIBRARY_WRITE)]


@router.get("", response_model=Page[LibraryPaintPublic])
def list_paints(
    session: ReadSessionDep,
    _user: Reader,
    category: PaintType | None = None,
    code_prefix: Annotated[str | None, Query(max_length=64)] = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[LibraryPaintPublic]:
    """Library paints by category and code prefix, in code order."""
    rows, total = service.list_paints(
        session=session, category=category, code_prefix=code_prefix, limit=limit, offset=offset
    )
    return Page[LibraryPaintPublic](data=[LibraryPaintPublic.model_validate(r) for r in rows], count=total)


IndexBound = Annotated[float | None, Query(ge=-1000.0, le=1000.0, allow_inf_nan=False)]


@router.get("/browse", response_model=BrowseOut, responses=CONFLICT)
def browse(
    request: Request,
    session: ReadSessionDep,
    _user: Reader,
    types: Annotated[
        list[PaintType] | None,
        Query(max_length=3, description="type check boxes (repeat the parameter); default all"),
    ] = None,
    flop_min: IndexBound = None,
    flop_max: IndexBound = None,
    chroma_min: IndexBound = None,
    chroma_max: IndexBound = None,
    hue_shift_min: IndexBound = None,
    hue_shift_max: IndexBound = None,
    set_name: Annotated[Literal["solids", "metallics+pearls"] | None, Query(alias="set")] = None,
    kind: Literal["chromatic", "neutral"] | None = None,
    group: Literal["blue", "green", "yellow", "red", "light", "medium", "dark"] | None = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> dict[str, object]:
    """The thesis's library browser (§5.3.3): type check boxes, lower/upper bounds on the Flop, Chroma and Hue
    Shift Index (eqs 5.3.1–5.3.3) and the hierarchy solids | metallics+pearls → chromatic (blue, green,
    yellow, red) | neutral (light, medium, dark)."""
    from station.formulate.library import PAINT_TYPES, LibraryFilter

    flt = LibraryFilter(
        types=frozenset(types or PAINT_TYPES),
        flop=(flop_min, flop_max),
        chroma=(chroma_min, chroma_max),
        hue_shift=(hue_shift_min, hue_shift_max),
        set_name=set_name,
        kind=kind,
        group=group,
    )
    return formulation.browse(
        session=session, cache=formulation.app_cache(request.app.state), flt=flt, limit=limit, offset=offset
    )


@router.get(
    "/export.csv",
    response_class=Response,
    responses={
        **CONFLICT,
        200: {
            "description": "library CSV: code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110[,more angles]",
            "content": {"text/csv": {"schema": {"type": "string"}}},
        },
    },
)
def export_csv(
    request: Request,
    session: ReadSessionDep,
    _user: Reader,
    category: PaintType | None = None,
) -> Response:
    """The library (or one category) as library CSV (Lab and gloss to 4 decimals)."""
    text = formulation.export_csv(
        session=session, cache=formulation.app_cache(request.app.state), category=category
    )
    return Response(
        text, media_type="text/csv", headers={"Content-Disposition": 'attachment; filename="library.csv"'}
    )


@router.post(
    IMPORT_PATH.removeprefix("/library"),
    status_code=status.HTTP_201_CREATED,
    response_model=LibraryImportOut,
    responses={**CONFLICT, 413: {"description": "request body over the library upload limit"}},
    openapi_extra={
        "requestBody": {
            "required": True,
            "description": "library CSV (UTF-8)",
            "content": {
                "text/csv": {
                    "schema": {"type": "string"},
                    "example": "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\n"
                    "R-1,solid,90,40,50,30,40,50,30,40,50,30\n",
                }
            },
        }
    },
)
async def import_csv(
    request: Request,
    user: Importer,
    name: Annotated[
        str,
        Query(
            min_length=1,
            max_length=64,
            pattern=r"^[^\x00-\x1f]+$",
            description="library name stored with each paint",
        ),
    ] = "imported",
    allow_formulas: Annotated[
        bool,
        Query(
            description="accept codes starting with = + - @ (spreadsheet formulas; the export escapes "
            "them with a leading single quote); default: such a row is a 422"
        ),
    ] = False,
) -> LibraryImportOut:
    """Validate a library CSV (header ``code,type,gloss_gu,L15,a15,b15,…[,synthetic][,recipe]``; faults
    name row and column) and add its paints in one transaction: a code already stored is a 409 and
    nothing is added. Audited. Codes are printable text; one starting with = + - @ is refused unless
    ``allow_formulas``. The body is read as a stream, decoded chunk by chunk, under its own cap
    (``library_upload_max_bytes``, 64 MiB by default: a 50 000-paint library fits)."""
    decoder = codecs.getincrementaldecoder("utf-8-sig")()
    parts: list[str] = []
    try:
        async for chunk in request.stream():
            parts.append(decoder.decode(chunk))
        parts.append(decoder.decode(b"", final=True))
    except UnicodeDecodeError as exc:
        raise InputError("body", "UTF-8 CSV text") from exc
    text = "".join(parts)

    def run() -> dict[str, object]:
        with request.app.state.sessions() as session:
            return formulation.import_csv(
                session=session, actor=user, text=text, name=name, allow_formulas=allow_formulas
            )

    return LibraryImportOut.model_validate(await asyncio.to_thread(run))


@router.get("/libraries", response_model=list[StoredLibraryOut], responses=CONFLICT)
def libraries(request: Request, session: ReadSessionDep, _user: Reader) -> list[dict[str, object]]:
    """The libraries stored (each import is one, the demo library another): name, paints per type and
    whether they are synthetic. ``POST /formulation/snap`` searches one of them with ``library``."""
    return formulation.stored_libraries(session=session, cache=formulation.app_cache(request.app.state))


@router.get("/{code}", response_model=LibraryPaintPublic, responses=NOT_FOUND)
def get_paint(
    session: ReadSessionDep, _user: Reader, code: Annotated[str, Path(min_length=1, max_length=64)]
) -> LibraryPaintPublic:
    """One library paint."""
    return LibraryPaintPublic.model_validate(service.get_paint(session=session, code=code))
