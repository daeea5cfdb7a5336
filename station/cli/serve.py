"""``station serve``, ``station db …`` and ``station users …``: the workstation service and its admin commands.

``station serve`` applies migrations, loads the demo library on first start, attaches the simulated
instruments, hands out the bootstrap admin token once (first start only: printed on a terminal, else
written to ``bootstrap-token`` (0600) in the data folder and the path printed) and serves on loopback
(``--host``/``--port``, else ``$CACAD_HOST``/``$CACAD_PORT``). uvicorn runs with the keep-alive
timeout and header size of the settings, its h11 protocol under the header deadline and the connection
caps of ``station.api.connections``, the app behind a request-body deadline and a bound on requests
handled at once (idle connections do not count against it).

A database that cannot be reached or a revision that does not exist is one line on stderr and exit
status 2 for every command here (no traceback). ``station db verify`` recomputes the hash chains of
measurements, audit events and record events, the sealed records and the signed checkpoints of the
data folder (``db.chain_audit.audit_database``): exit 0 intact, 1 with every finding listed (``--json``: the
report with its ``findings``). ``station db checkpoint`` verifies, then appends a signed checkpoint.
"""

from __future__ import annotations

import argparse
import contextlib
import ipaddress
import logging
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from station.cli._common import add_json_flag
from station.errors import InputError


class DatabaseUnreachable(InputError):
    """The database named by ``--database`` / the settings cannot be opened (exit status 2)."""

    def __init__(self, url: str, reason: str) -> None:
        super().__init__("database", "a reachable database", None, f"{url}: {reason}")


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    text = text.split(" (Background on this error", 1)[0]
    return f"{type(exc).__name__}: {text}"[:300]


def _shown(url: str) -> str:
    from sqlalchemy.engine import make_url

    try:
        return make_url(url).render_as_string(hide_password=True)
    except Exception:
        return "<unparsable URL>"


@contextlib.contextmanager
def _database_errors(url: str, revision: str | None = None) -> Iterator[None]:
    """Turn a database that cannot be reached or an unknown revision into one :class:`InputError` line."""
    from alembic.util.exc import CommandError
    from sqlalchemy.exc import SQLAlchemyError

    from db.errors import DatabaseError, MigrationError, TamperedError

    try:
        yield
    except (InputError, TamperedError):
        raise
    except CommandError as exc:
        from db.migrate import head_revision

        if revision is not None and revision in str(exc):
            raise InputError(
                "revision", f"a revision this code knows (head {head_revision()}, base, +N or -N)", revision
            ) from None
        raise InputError(
            "database",
            f"a database at a revision this code knows (head {head_revision()})",
            None,
            _one_line(exc),
        ) from None
    except MigrationError as exc:
        raise InputError("database", "a database at the revision this code expects", None, str(exc)) from None
    except (SQLAlchemyError, DatabaseError, OSError) as exc:
        raise DatabaseUnreachable(_shown(url), _one_line(exc)) from None


def _settings(args: argparse.Namespace, **extra: Any) -> Any:
    import pydantic

    from station.api.settings import Settings

    opts: dict[str, Any] = {}
    if getattr(args, "database", None):
        opts["database_url"] = args.database
    if getattr(args, "data_dir", None):
        opts["data_dir"] = Path(args.data_dir).resolve()
    opts.update({k: v for k, v in extra.items() if v is not None})
    try:
        return Settings(**opts)
    except pydantic.ValidationError as exc:
        first = exc.errors()[0]
        name = ".".join(str(p) for p in first["loc"])
        msg, got = first["msg"], first.get("input")
        if not name:  # a check across settings names its field first: "NAME: expected …, got …"
            msg, got = msg.removeprefix("Value error, "), None
            field, _, rest = msg.partition(": ")
            name, msg = (
                (field, rest.removeprefix("expected "))
                if field in Settings.model_fields
                else ("settings", msg)
            )
        raise InputError(f"{name} (or $CACAD_{name.upper()})", msg, got) from None


def _sessions(url: str) -> tuple[Any, Any]:
    from db.engine import make_engine, make_sessionmaker
    from db.migrate import ensure_at_head

    with _database_errors(url):
        ensure_at_head(url)
        engine = make_engine(url)
    return engine, make_sessionmaker(engine)


def _hand_out_token(token: str, path: Path) -> None:
    """Print the bootstrap token on a terminal; otherwise write it to *path* (0600) and print the path."""
    if sys.stdout.isatty():
        print("bootstrap admin token (shown once, store it now; it is kept only hashed):", flush=True)
        print(f"  {token}", flush=True)
        return
    from db.files import private_dir, write_private_text

    private_dir(path.parent)
    write_private_text(path, token + "\n")
    print(f"bootstrap admin token written to {path} (mode 0600; store it, then delete the file)", flush=True)


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _parse_sims(text: str | None) -> tuple[str, ...]:
    """The simulator kinds of ``--simulators`` (``None``: every family with a simulator)."""
    from station.drivers.families import SIM_FAMILY_NAMES

    if text is None:
        return SIM_FAMILY_NAMES
    kinds = tuple(k for k in text.split(",") if k)
    for k in kinds:
        if k not in SIM_FAMILY_NAMES:
            raise InputError(
                "--simulators", f"comma-separated subset of {','.join(SIM_FAMILY_NAMES)} or ''", text
            )
    return kinds


def _load_demo_library(session: Any) -> None:
    """Load the demo library into the service's database on its first start, saying so; a failure is a
    warning (the service still runs; the library routes then list nothing)."""
    from station.api.services.library import load_demo_library

    print("checking the demo library (the first start loads ~6000 paints)…", flush=True)
    try:
        added = load_demo_library(session=session)
    except Exception as exc:
        session.rollback()
        print(
            f"warning: demo library not loaded: {type(exc).__name__}: {exc}"[:500],
            file=sys.stderr,
            flush=True,
        )
        return
    if added:
        print(f"library: {added} synthetic demo paints loaded", flush=True)


def serve(args: argparse.Namespace) -> dict[str, Any] | None:
    """Run the service until interrupted (each start-up step is announced on stdout as it begins)."""
    print("starting the station service: loading its modules…", flush=True)
    import uvicorn

    from db.files import private_dir
    from station.api import create_app
    from station.api.connections import ConnectionGuard, RequestConcurrencyLimit, guarded_protocol
    from station.api.services.users import bootstrap_admin
    from station.api.timeouts import BodyReadTimeout

    if args.port is not None and not 1 <= args.port <= 65535:
        raise InputError("--port", "1..65535", args.port)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    logging.getLogger("alembic").setLevel(logging.WARNING)
    settings = _settings(
        args,
        host=args.host,
        port=args.port,
        simulators=_parse_sims(args.simulators),
        simulator_drift=args.drift,
        simulator_state_dir=None if args.state is None else Path(args.state).resolve(),
        load_demo_library=not args.no_demo_library,
    )
    url = settings.effective_database_url
    private_dir(settings.data_dir)
    engine, sessions = _sessions(url)
    print("opening the database (migrations are applied on the first start)…", flush=True)
    try:
        with _database_errors(url), sessions() as session:
            token = bootstrap_admin(session=session)
            if settings.load_demo_library:
                _load_demo_library(session)
    finally:
        engine.dispose()
    print(f"database: {engine.url.render_as_string(hide_password=True)}", flush=True)
    if token:
        _hand_out_token(token, settings.bootstrap_token_path)
    if not _is_loopback(settings.host):
        print(
            f"warning: binding {settings.host}, which is not loopback: the service is reachable from the network",
            file=sys.stderr,
            flush=True,
        )
    guard = ConnectionGuard(
        header_timeout_s=settings.header_timeout_s,
        max_connections=settings.max_connections,
        max_per_client=settings.max_connections_per_client,
    )
    app = RequestConcurrencyLimit(
        BodyReadTimeout(create_app(settings), settings.body_timeout_s), settings.limit_concurrency
    )
    print(
        f"starting the web server on http://{settings.host}:{settings.port} "
        f"(simulators: {', '.join(settings.simulators) or 'none'}; Ctrl+C stops it)…",
        flush=True,
    )
    uvicorn.run(
        app,
        host=settings.host,
        port=settings.port,
        log_level=args.log_level,
        http=guarded_protocol(guard),
        ws="none",  # no WebSocket routes: an upgrade request is an ordinary request
        timeout_keep_alive=settings.keep_alive_timeout_s,
        h11_max_incomplete_event_size=settings.max_header_bytes,
    )
    return None


def db_command(args: argparse.Namespace) -> dict[str, Any]:
    """Migrate, revert, inspect, verify or checkpoint the database."""
    from db import migrate
    from db.engine import make_engine

    settings = _settings(args)
    url = settings.effective_database_url
    with _database_errors(url, args.revision):
        if args.db_action == "upgrade":
            migrate.upgrade(url, args.revision)
        elif args.db_action == "downgrade":
            migrate.downgrade(url, args.revision)
        engine = make_engine(url)
        try:
            if args.db_action in ("verify", "checkpoint"):
                return _verify(engine, url, settings.data_dir, args)
            current = migrate.current_revision(engine)
        finally:
            engine.dispose()
    return {
        "database": engine.url.render_as_string(hide_password=True),
        "revision": current,
        "head": migrate.head_revision(),
    }


@contextlib.contextmanager
def _snapshot(engine: Any) -> Iterator[Any]:
    """A connection that reads one snapshot of the whole database while writers go on appending.

    PostgreSQL: a read-only REPEATABLE READ transaction; SQLite: one deferred read transaction (WAL).
    """
    from db.engine import reading

    conn = reading(engine).connect()  # a read: never takes or waits for the SQLite write lock
    try:
        if engine.dialect.name == "postgresql":
            conn = conn.execution_options(isolation_level="REPEATABLE READ", postgresql_readonly=True)
        yield conn
    finally:
        conn.close()


def _verify(engine: Any, url: str, data_dir: Path, args: argparse.Namespace) -> dict[str, Any]:
    """Verify every chain, sealed record and checkpoint; report every finding (``db.chain_audit.audit_database``).

    Intact: the report is the result (exit 0). Broken: the report is printed (JSON with ``--json``, else
    one ``finding: …`` line each) and :class:`TamperedError` (exit 1) names the first finding and the
    count. ``checkpoint`` verifies first and appends a signed checkpoint only when intact.
    """
    from db import chain, chain_audit
    from db.errors import TamperedError
    from db.migrate import current_revision
    from station.cli._common import emit

    if current_revision(engine) is None:
        raise InputError("database", "a migrated database (run `station db upgrade`)", None)
    database = chain_audit.database_identity(url)
    with _snapshot(engine) as conn:
        report = chain_audit.audit_database(conn, checkpoint_folder=data_dir, database=database)
    result: dict[str, Any] = {"chain": "intact" if report.intact else "broken", "intact": report.intact}
    for name in chain.CHAINS:
        if name in report.rows:
            result[name] = report.rows[name]
    for name in chain.CHAINS:
        if name in report.heads:
            result[f"{name}_head"] = report.heads[name]
    result["checkpoints"] = report.checkpoints
    result["checkpoint_file"] = str(data_dir / chain_audit.CHECKPOINT_FILE)
    result["findings"] = [f.as_dict() for f in report.findings]
    if not report.intact:
        if getattr(args, "json", False):
            emit(result, True)
        else:
            for finding in report.findings:
                print(f"finding: {finding.message}")
        sys.stdout.flush()
        count = len(report.findings)
        raise TamperedError(
            f"chain broken: {report.findings[0].message} ({count} finding{'s' if count != 1 else ''})"
        )
    if args.db_action == "checkpoint":
        from db.files import private_dir

        private_dir(data_dir)
        written = chain_audit.write_checkpoint(report, data_dir, database)  # exactly the heads verified
        result["checkpoint"] = {c: v["length"] for c, v in written["chains"].items()}
        result["checkpoints"] = report.checkpoints + 1
    return result


def users_command(args: argparse.Namespace) -> dict[str, Any]:
    """Manage users and tokens from the workstation (audited as actor ``None``, via ``cli``)."""
    from db.models import Role
    from station.api.services import users

    url = _settings(args).effective_database_url
    engine, sessions = _sessions(url)
    try:
        with _database_errors(url), sessions() as session:
            if args.users_action == "add":
                user, token, secret = users.create_user(
                    session=session, actor=None, name=args.name, role=Role(args.role), label="cli"
                )
                return {
                    "user": user.name,
                    "role": user.role.value,
                    "token_id": token.id,
                    "token": secret,
                    "expires_at": _iso(token.expires_at),
                }
            if args.users_action == "token":
                user = users.find_user(session=session, name=args.name)
                token, secret = users.issue_token(session=session, actor=None, user=user, label=args.label)
                return {
                    "user": user.name,
                    "token_id": token.id,
                    "token": secret,
                    "expires_at": _iso(token.expires_at),
                }
            if args.users_action == "revoke-token":  # name: the token id (from `users tokens NAME`)
                token = users.revoke_token(
                    session=session,
                    actor=None,
                    token=users.get_token(session=session, token_id=_id(args.name)),
                )
                return {
                    "token_id": token.id,
                    "revoked_at": token.revoked_at.isoformat() if token.revoked_at else None,
                }
            if args.users_action == "tokens":
                user = users.find_user(session=session, name=args.name)
                return {
                    "user": user.name,
                    "tokens": [
                        {
                            "id": t.id,
                            "label": t.label,
                            "expires_at": _iso(t.expires_at),
                            "revoked_at": _iso(t.revoked_at),
                        }
                        for t in users.list_tokens(session=session, user=user)
                    ],
                }
            if args.users_action == "deactivate":
                user = users.deactivate(
                    session=session, actor=None, user=users.find_user(session=session, name=args.name)
                )
                return {"user": user.name, "active": user.active}
            return {
                "users": [
                    {"id": u.id, "name": u.name, "role": u.role.value, "active": u.active}
                    for u in users.list_users(session=session)
                ]
            }
    finally:
        engine.dispose()


def _db_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--database",
        metavar="URL",
        help="sqlite:///PATH or postgresql://USER@HOST/DB "
        "(default: $CACAD_DATABASE_URL or SQLite in the data folder)",
    )
    p.add_argument("--data-dir", metavar="DIR", help="data folder (default: $CACAD_DATA_DIR or ./var)")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``serve``, ``db`` and ``users``."""
    p = subparsers.add_parser(
        "serve", help="run the workstation service (FastAPI) with simulated instruments"
    )
    _db_args(p)
    p.add_argument("--host", help="bind address (default: $CACAD_HOST, else loopback 127.0.0.1)")
    p.add_argument("--port", type=int, help="TCP port (default: $CACAD_PORT, else 8000)")
    p.add_argument(
        "--simulators",
        default=None,
        help="simulators to attach, comma-separated family names (default: all; '' for none)",
    )
    p.add_argument(
        "--drift",
        type=float,
        metavar="SCALE",
        help="the simulators' drift across runs, scale of the stated one (1 = stated, 0 = none; "
        "default: theirs)",
    )
    p.add_argument(
        "--state",
        metavar="DIR",
        help="keep the simulators' run counters in DIR (FAMILY.json): each start is their next run, so "
        "their drift grows from one start of the service to the next",
    )
    p.add_argument("--no-demo-library", action="store_true", help="do not load the demo paint library")
    p.add_argument("--log-level", default="info", choices=("critical", "error", "warning", "info", "debug"))
    p.set_defaults(handler=serve)

    p = subparsers.add_parser(
        "db",
        help="database migrations (upgrade, downgrade, current), the tamper check (verify) and checkpoint",
    )
    p.add_argument("db_action", choices=("upgrade", "downgrade", "current", "verify", "checkpoint"))
    p.add_argument("revision", nargs="?", default=None, help="target revision (default head / one step back)")
    _db_args(p)
    add_json_flag(p)
    p.set_defaults(handler=_db_defaults)

    p = subparsers.add_parser("users", help="users and bearer tokens (admin, on this workstation)")
    p.add_argument("users_action", choices=("list", "add", "token", "tokens", "revoke-token", "deactivate"))
    p.add_argument(
        "name", nargs="?", help="user name (add, token, tokens, deactivate) or token id (revoke-token)"
    )
    p.add_argument(
        "--role", choices=("technician", "qa", "stylist", "chemist", "admin"), default="technician"
    )
    p.add_argument("--label", default="cli", help="token label")
    _db_args(p)
    add_json_flag(p)
    p.set_defaults(handler=_users_checked)


def _db_defaults(args: argparse.Namespace) -> dict[str, Any]:
    if args.revision is None:
        args.revision = "head" if args.db_action == "upgrade" else "-1"
    return db_command(args)


def _validated(model: Any, data: dict[str, Any]) -> None:
    """Validate *data* with the API's request schema *model*; :class:`InputError` naming the first field."""
    import pydantic

    try:
        model.model_validate(data)
    except pydantic.ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"]) or "input"
        raise InputError(
            field, first["msg"].removeprefix("String should ").replace("Value error, ", ""), data.get(field)
        ) from None


def _id(text: str) -> int:
    if not text.isdigit() or not 1 <= int(text) <= 2**31 - 1:
        raise InputError("token_id", "a token id, 1 to 2147483647 (see `station users tokens NAME`)", text)
    return int(text)


def _iso(at: Any) -> str | None:
    return None if at is None else str(at.isoformat())


def _users_checked(args: argparse.Namespace) -> dict[str, Any]:
    from station.api.schemas.users import TokenCreate, UserCreate

    if args.users_action != "list" and not args.name:
        raise InputError("name", f"a user name for 'users {args.users_action}'", None)
    if args.users_action == "add":
        _validated(UserCreate, {"name": args.name, "role": args.role})
    if args.users_action in ("add", "token"):
        _validated(TokenCreate, {"label": args.label})
    return users_command(args)
