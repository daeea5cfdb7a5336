"""``station serve``, ``station db …`` and ``station users …``: the workstation service and its admin commands.

``station serve`` applies migrations, loads the demo library on first start, attaches the simulated
instruments, prints the bootstrap admin token once (first start only) and serves on loopback.
"""

from __future__ import annotations

import argparse
import ipaddress
import logging
import sys
from pathlib import Path
from typing import Any

from station.cli._common import add_json_flag
from station.errors import InputError

SIM_CHOICES = ("ma6", "ma3", "gloss")


def _settings(args: argparse.Namespace, **extra: Any) -> Any:
    from station.api.settings import Settings

    opts: dict[str, Any] = {}
    if getattr(args, "database", None):
        opts["database_url"] = args.database
    if getattr(args, "data_dir", None):
        opts["data_dir"] = Path(args.data_dir).resolve()
    opts.update(extra)
    return Settings(**opts)


def _sessions(url: str) -> tuple[Any, Any]:
    from db.engine import make_engine, make_sessionmaker
    from db.migrate import ensure_at_head

    ensure_at_head(url)
    engine = make_engine(url)
    return engine, make_sessionmaker(engine)


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _parse_sims(text: str) -> tuple[str, ...]:
    kinds = tuple(k for k in text.split(",") if k)
    for k in kinds:
        if k not in SIM_CHOICES:
            raise InputError("--simulators", f"comma-separated subset of {','.join(SIM_CHOICES)} or ''", text)
    return kinds


def serve(args: argparse.Namespace) -> dict[str, Any] | None:
    """Run the service until interrupted."""
    import uvicorn

    from station.api import create_app
    from station.api.services.library import load_demo_library
    from station.api.services.users import bootstrap_admin

    if not 1 <= args.port <= 65535:
        raise InputError("--port", "1..65535", args.port)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    logging.getLogger("alembic").setLevel(logging.WARNING)
    settings = _settings(
        args,
        host=args.host,
        port=args.port,
        simulators=_parse_sims(args.simulators),
        load_demo_library=not args.no_demo_library,
    )
    url = settings.effective_database_url
    engine, sessions = _sessions(url)
    try:
        with sessions() as session:
            token = bootstrap_admin(session=session)
            if settings.load_demo_library:
                try:
                    added = load_demo_library(session=session)
                except Exception as exc:  # the service still runs; the library routes then list nothing
                    session.rollback()
                    print(
                        f"warning: demo library not loaded: {type(exc).__name__}: {exc}"[:500],
                        file=sys.stderr,
                        flush=True,
                    )
                    added = 0
                if added:
                    print(f"library: {added} synthetic demo paints loaded", flush=True)
    finally:
        engine.dispose()
    print(f"database: {engine.url.render_as_string(hide_password=True)}", flush=True)
    if token:
        print("bootstrap admin token (shown once, store it now; it is kept only hashed):", flush=True)
        print(f"  {token}", flush=True)
    if not _is_loopback(args.host):
        print(
            f"warning: binding {args.host}, which is not loopback: the service is reachable from the network",
            file=sys.stderr,
            flush=True,
        )
    uvicorn.run(create_app(settings), host=args.host, port=args.port, log_level=args.log_level)
    return None


def db_command(args: argparse.Namespace) -> dict[str, Any]:
    """Migrate, revert or inspect the database."""
    from db import migrate
    from db.engine import make_engine

    url = _settings(args).effective_database_url
    if args.db_action == "upgrade":
        migrate.upgrade(url, args.revision)
    elif args.db_action == "downgrade":
        migrate.downgrade(url, args.revision)
    engine = make_engine(url)
    try:
        current = migrate.current_revision(engine)
    finally:
        engine.dispose()
    return {
        "database": engine.url.render_as_string(hide_password=True),
        "revision": current,
        "head": migrate.head_revision(),
    }


def users_command(args: argparse.Namespace) -> dict[str, Any]:
    """Manage users and tokens from the workstation (audited as actor ``None``, via ``cli``)."""
    from db.models import Role
    from station.api.services import users

    engine, sessions = _sessions(_settings(args).effective_database_url)
    try:
        with sessions() as session:
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
    p.add_argument("--host", default="127.0.0.1", help="bind address (default: loopback 127.0.0.1)")
    p.add_argument("--port", type=int, default=8000)
    p.add_argument(
        "--simulators",
        default=",".join(SIM_CHOICES),
        help="simulators to attach, comma-separated (default: all; '' for none)",
    )
    p.add_argument("--no-demo-library", action="store_true", help="do not load the demo paint library")
    p.add_argument("--log-level", default="info", choices=("critical", "error", "warning", "info", "debug"))
    p.set_defaults(handler=serve)

    p = subparsers.add_parser("db", help="database migrations (upgrade, downgrade, current)")
    p.add_argument("db_action", choices=("upgrade", "downgrade", "current"))
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


def _id(text: str) -> int:
    if not text.isdigit() or not 1 <= int(text) <= 2**31 - 1:
        raise InputError("token_id", "a token id, 1 to 2147483647 (see `station users tokens NAME`)", text)
    return int(text)


def _iso(at: Any) -> str | None:
    return None if at is None else str(at.isoformat())


def _users_checked(args: argparse.Namespace) -> dict[str, Any]:
    if args.users_action != "list" and not args.name:
        raise InputError("name", f"a user name for 'users {args.users_action}'", None)
    return users_command(args)
