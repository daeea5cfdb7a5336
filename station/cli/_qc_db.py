"""The measurement database of the ``station qc`` commands: ``--db URL`` (default: the ``station serve``
database), refused with one line when an SQLite file does not exist (only ``station db upgrade``
creates a database), and ISO 8601 times of the search options."""

from __future__ import annotations

import argparse
import datetime as dt
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from station.errors import InputError

__all__ = ["_session", "_shown", "_time"]


def _url(args: argparse.Namespace) -> str:
    from db.engine import configured_database_url

    return args.db or configured_database_url()


def _existing_sqlite(url: str) -> None:
    """Refuse an SQLite URL whose file does not exist: only ``station db upgrade`` creates a database."""
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import ArgumentError

    try:
        parsed = make_url(url)
    except ArgumentError as exc:
        raise InputError("db", "a database URL (sqlite:///PATH or postgresql://…)", url) from exc
    name = parsed.database or ""
    if (
        parsed.get_backend_name() == "sqlite"
        and name not in ("", ":memory:")
        and not name.startswith("file:")
    ):
        if not Path(name).is_file():
            raise InputError("db", "an existing database file (station db upgrade creates one)", name)


@contextmanager
def _session(args: argparse.Namespace) -> Iterator[Any]:
    from sqlalchemy.exc import SQLAlchemyError

    from db.engine import make_engine, make_sessionmaker
    from db.migrate import ensure_at_head

    url = _url(args)
    _existing_sqlite(url)
    try:
        ensure_at_head(url)
        engine = make_engine(url)
    except SQLAlchemyError as exc:
        raise InputError("db", "a reachable measurement database URL", url.split("@")[-1]) from exc
    try:
        with make_sessionmaker(engine)() as session:
            yield session
    finally:
        engine.dispose()


def _time(text: str | None, field: str) -> dt.datetime | None:
    if text is None:
        return None
    try:
        t = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError as exc:
        raise InputError(
            field, "an ISO 8601 date or time, e.g. 2026-12-01 or 2026-12-01T08:00Z", text
        ) from exc
    return t if t.tzinfo is not None else t.replace(tzinfo=dt.UTC)


def _shown(args: argparse.Namespace, out: dict[str, Any], table: Callable[[dict[str, Any]], None]) -> Any:
    """*out* for ``--json``; else *table* prints it for a person and nothing more is printed."""
    if args.json:
        return out
    table(out)
    return None
