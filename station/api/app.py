"""The application factory: everything (engine, sessions, instruments) is built here, nothing at import.

``create_app(settings)`` returns a FastAPI app whose lifespan migrates the database (when
``settings.auto_migrate``), loads the demo library (when asked and the table is empty), and attaches
the configured simulators. Tests build one app per database and override ``get_session`` as needed.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from fastapi import FastAPI

from db.engine import make_engine, make_sessionmaker
from station import __version__
from station.api.availability import PROBE_BUSY, DatabaseState, probe_database
from station.api.errors import install_error_handlers
from station.api.json_guard import StrictJsonBody
from station.api.middleware import BodySizeLimit, SecurityHeaders
from station.api.security import TokenCache
from station.api.settings import Settings
from station.errors import InputError
from station.ingest.group import GroupCommit

log = logging.getLogger(__name__)

API_PREFIX = "/api/v1"

DESCRIPTION = """
CACAD Station workstation service: instruments, panels and measurements, versioned designs, the paint
library. Every route but `/health` needs `Authorization: Bearer <token>`; the first token is printed
once by `station serve` on first start. Angles are in degrees; Lab is CIE L*a*b* (D65, CIE 1964 10°)
unless a field says otherwise; gloss is in gloss units (60° unless stated).
"""

TAGS = [
    {"name": "health", "description": "liveness (no token)"},
    {"name": "instruments", "description": "attached instruments: connect, calibrate, measure"},
    {"name": "panels", "description": "painted samples (job, part, substrate)"},
    {"name": "measurements", "description": "immutable readings; corrections supersede; CSV export"},
    {
        "name": "analyses",
        "description": "misalignment QA (thesis ch. 4): seam QA of measured panels or designs, "
        "goniogeometric index, inverse trompe l'oeil, seam sweep",
    },
    {"name": "designs", "description": "versioned cacad.design/1 designs"},
    {
        "name": "styling",
        "description": "colour styling tools (thesis §3.4–§3.7): variations, eyedroppers, "
        "palette swatch, sketch fit (stylist)",
    },
    {"name": "library", "description": "library paints; CSV import (chemist) and export"},
    {"name": "recipes", "description": "formulation jobs: ColorSnap a design to the library (chemist)"},
    {
        "name": "formulation",
        "description": "ColorSnap top-k, recipe formulation (SYNTHETIC colorants), XML / "
        "CxF3 export (chemist, thesis §5.3)",
    },
    {"name": "users", "description": "users and tokens (admin)"},
    {"name": "audit", "description": "who wrote what, when"},
    {
        "name": "qc",
        "description": "colour QC against standards: measurements with gloss, sample-versus-standard "
        "verdicts, job summaries, reports (QA)",
    },
    {
        "name": "booth",
        "description": "virtual light booth: standard against sample under D65, A, F11, TL84, LED and "
        "a lab's own lamps, with the CIE special metamerism index",
    },
]


def _startup(app: FastAPI, settings: Settings) -> None:
    from db.files import private_dir
    from db.migrate import ensure_at_head
    from station.api.instruments import InstrumentHub
    from station.api.services.library import load_demo_library

    private_dir(settings.data_dir)  # 0700: the database, the outbox and the bootstrap token live here
    url = settings.effective_database_url
    if settings.auto_migrate:
        ensure_at_head(url)
    engine = make_engine(url)
    app.state.engine = engine
    app.state.sessions = make_sessionmaker(engine)
    app.state.read_sessions = make_sessionmaker(engine, read_only=True)  # GET routes, token checks
    if settings.load_demo_library:
        with app.state.sessions() as session:
            try:
                load_demo_library(session=session)
            except Exception:  # the service still runs; the library routes then list nothing
                session.rollback()
                log.exception("demo library not loaded")
    hub = InstrumentHub(
        settings=settings, engine=engine, sessions=app.state.sessions, database=app.state.database
    )
    app.state.instruments = hub
    hub.attach_simulators(settings.simulators)


def _start_watch_folder(app: FastAPI, settings: Settings) -> tuple[threading.Event, threading.Thread] | None:
    """Start the watch-folder thread when ``settings.watch_dir`` is set: files go through the service's ingestor."""
    if settings.watch_dir is None:
        return None
    from station.ingest.formats.records import ImportOptions
    from station.ingest.formats.watch import watch_folder

    folder = Path(settings.watch_dir)
    folder.mkdir(parents=True, exist_ok=True)
    stop = threading.Event()
    hub = app.state.instruments
    options = ImportOptions("service", job=settings.watch_job, part=settings.watch_part)

    def run() -> None:
        while not stop.is_set():
            try:
                watch_folder(folder, hub.ingestor(), options, interval_s=settings.watch_interval_s, stop=stop)
            except InputError as exc:  # a linked or foreign done/ or rejected/: never used, not retried
                log.error("watch folder %s refused: %s", folder, exc)
                return
            except Exception:  # the service keeps running; the next scan tries again
                log.exception("watch folder %s", folder)
                stop.wait(settings.watch_interval_s)

    thread = threading.Thread(target=run, name="watch-folder", daemon=True)
    thread.start()
    log.info("watching %s for measurement files", folder)
    return stop, thread


async def _replay_outbox_periodically(app: FastAPI, period_s: float) -> None:
    """Every *period_s* seconds: probe the database, mark it away or back, and drain the outbox when it answers.

    The readings queued while the database was away land here without a new measure, in the order
    they were taken, each exactly once (by client id).
    """
    import asyncio

    database: DatabaseState = app.state.database
    while True:
        await asyncio.sleep(period_s)
        try:
            answer = await asyncio.wait_for(asyncio.to_thread(probe_database, app.state.engine), timeout=10.0)
        except Exception as exc:
            if not database.away:
                log.warning("database unreachable (%s); readings go to the outbox", type(exc).__name__)
            database.mark_away(exc)
            continue
        if database.away and answer == PROBE_BUSY:
            continue  # readable, but a write just gave up on its lock: drain once the lock is free
        if database.away:
            log.info("database reachable again")
        database.mark_back()
        try:
            done = await asyncio.to_thread(app.state.instruments.replay_outbox)
            if done:
                log.info("outbox: %d queued readings replayed", done)
        except Exception:
            log.exception("outbox replay failed; will retry")


def _shutdown(app: FastAPI) -> None:
    hub = getattr(app.state, "instruments", None)
    if hub is not None:
        hub.close()
    engine = getattr(app.state, "engine", None)
    if engine is not None:
        engine.dispose()


def _roles_markdown() -> str:
    from station.api.security import ROLE_SCOPES

    rows = "\n".join(
        f"| {role.value} | {', '.join(sorted(s.value for s in scopes))} |"
        for role, scopes in ROLE_SCOPES.items()
    )
    return (
        "\nEach operation lists the scope it needs under its security requirement. Roles hold these "
        f"scopes:\n\n| role | scopes |\n|---|---|\n{rows}\n"
    )


DOCS_ASSETS = "/docs-assets"
"""Where the service serves the docs pages' scripts, style and icon (bundled: no CDN)."""
DOCS_FILES = {
    "swagger-ui-bundle.js": "text/javascript",
    "swagger-ui.css": "text/css",
    "redoc.standalone.js": "text/javascript",
    "favicon.png": "image/png",
}
"""The files of ``fastapi-offline``'s bundle the pages use: Swagger UI 5 (it reads OpenAPI 3.1, the
version FastAPI writes; Swagger UI 3 and 4 cannot) and ReDoc 2."""


def _docs(app: FastAPI, protected: bool) -> None:
    """``/openapi.json``, ``/docs``, ``/redoc`` and ``/`` (a link to them); *protected*: behind the
    bearer token (any role), as every route but ``/health`` (issue 5) — the HTML pages need the token
    too; fetch the schema with it (``curl -H``). Their scripts are served by the service itself
    (:data:`DOCS_ASSETS`), so the pages work without the internet."""
    from fastapi import Depends
    from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
    from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, RedirectResponse, Response

    from station.api.deps import authorize

    guard = [Depends(authorize)] if protected else []

    @app.get("/", include_in_schema=False)
    def root() -> RedirectResponse:
        """The service's front door: the API documentation (``/docs``)."""
        return RedirectResponse("/docs", status_code=307)

    @app.get("/openapi.json", include_in_schema=False, dependencies=guard)
    def openapi() -> JSONResponse:
        """The OpenAPI schema of the service."""
        return JSONResponse(app.openapi())

    @app.get("/docs", include_in_schema=False, dependencies=guard)
    def docs() -> HTMLResponse:
        """The Swagger UI page (fetches the schema with the token; its script and style come from this
        service, so the page works without the internet)."""
        return get_swagger_ui_html(
            openapi_url="/openapi.json",
            title=f"{app.title} - docs",
            swagger_js_url=f"{DOCS_ASSETS}/swagger-ui-bundle.js",
            swagger_css_url=f"{DOCS_ASSETS}/swagger-ui.css",
            swagger_favicon_url=f"{DOCS_ASSETS}/favicon.png",
        )

    @app.get(DOCS_ASSETS + "/{name}", include_in_schema=False)
    def docs_asset(name: str) -> Response:
        """The docs pages' bundled files (``fastapi-offline``; public, like any static file)."""
        import fastapi_offline

        if name not in DOCS_FILES:
            return JSONResponse({"detail": f"no such file: {name}"}, status_code=404)
        return FileResponse(
            Path(fastapi_offline.__file__).parent / "static" / name, media_type=DOCS_FILES[name]
        )

    @app.get("/redoc", include_in_schema=False, dependencies=guard)
    def redoc() -> HTMLResponse:
        """The ReDoc page (fetches the schema with the token; its script comes from this service)."""
        return get_redoc_html(
            openapi_url="/openapi.json",
            title=f"{app.title} - ReDoc",
            redoc_js_url=f"{DOCS_ASSETS}/redoc.standalone.js",
            redoc_favicon_url=f"{DOCS_ASSETS}/favicon.png",
            with_google_fonts=False,
        )


def create_app(settings: Settings) -> FastAPI:
    """Build the service for *settings*."""
    from station.api.routes import ROUTERS, health
    from station.api.routes.library import IMPORT_PATH as LIBRARY_IMPORT_PATH
    from station.api.routes.measurements import CREATE_ACTION
    from station.api.schemas.environment import (
        ENVIRONMENT_BODY_BYTES,
        ENVIRONMENT_FILE_FIELD,
        ENVIRONMENT_MULTIPART_BYTES,
        ENVIRONMENT_MULTIPART_PATH,
        ENVIRONMENT_UPLOAD_PATHS,
    )

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        import asyncio

        app.state.image_slots = asyncio.Semaphore(settings.image_decode_concurrency)  # this loop's
        await asyncio.to_thread(_startup, app, settings)
        replayer = asyncio.create_task(_replay_outbox_periodically(app, settings.outbox_replay_s))
        watcher = _start_watch_folder(app, settings)
        try:
            yield
        finally:
            replayer.cancel()
            if watcher is not None:
                stop, thread = watcher
                stop.set()
                await asyncio.to_thread(thread.join, 30)
            await asyncio.to_thread(_shutdown, app)

    public = settings.public_docs  # otherwise the docs are served behind authentication
    app = FastAPI(
        title="CACAD Station",
        version=__version__,
        description=DESCRIPTION + _roles_markdown(),
        openapi_tags=TAGS,
        lifespan=lifespan,
        docs_url=None,  # served by _docs, with bundled Swagger UI files
        redoc_url=None,
        openapi_url=None,
    )
    app.state.settings = settings
    app.state.tokens = TokenCache(settings.token_offline_s)
    app.state.database = DatabaseState()
    app.state.measurement_writes = GroupCommit(CREATE_ACTION)  # POST /measurements: group commit
    install_error_handlers(app)
    app.include_router(health.router)
    _docs(app, protected=not public)
    for router in ROUTERS:
        app.include_router(router, prefix=API_PREFIX)
    app.add_middleware(StrictJsonBody)  # inside the size cap: parses bodies already bounded
    app.add_middleware(
        BodySizeLimit,
        max_bytes=settings.max_body_bytes,
        per_path={
            f"{API_PREFIX}{LIBRARY_IMPORT_PATH}": settings.library_upload_max_bytes,
            **{
                f"{API_PREFIX}{path}": max(settings.max_body_bytes, ENVIRONMENT_BODY_BYTES)
                for path in ENVIRONMENT_UPLOAD_PATHS
            },
            f"{API_PREFIX}{ENVIRONMENT_MULTIPART_PATH}": (
                max(settings.max_body_bytes, ENVIRONMENT_MULTIPART_BYTES),
                ENVIRONMENT_FILE_FIELD,
            ),
        },
    )
    app.add_middleware(SecurityHeaders)  # outermost: the 413 above gets the headers too
    return app
