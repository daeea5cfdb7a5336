"""The workstation's database as a read source of the viewer's screens (Qt-free).

:class:`LocalDatabase` is the plumbing the QC and booth screens share: the database URL (as
``station serve``: ``$CACAD_DATABASE_URL``, else the default SQLite of ``db.engine.data_dir``), Alembic
migrations applied on first use, and one session factory opened lazily. A database that cannot be
opened or migrated raises the subclass's :attr:`LocalDatabase.source_error` naming where and why.
"""

from __future__ import annotations

from typing import Any, ClassVar

from station.errors import StationError


class LocalDatabaseError(StationError):
    """The workstation's database could not be opened or migrated (the message says which and why)."""


class DatabaseLocation:
    """Where the workstation's database is: the URL given, else the one ``station serve`` uses
    (``$CACAD_DATABASE_URL``, else ``station.sqlite3`` in :func:`db.engine.data_dir`: ``$CACAD_DATA_DIR``
    or ``./var``), resolved on first use. The class that mixes it in sets ``_url`` (``None``: configured)."""

    _url: str | None

    @property
    def url(self) -> str:
        """The database URL (the configured ``station serve`` database when none was given)."""
        if self._url is None:
            from db.engine import configured_database_url

            self._url = configured_database_url()
        return self._url

    @property
    def where(self) -> str:
        """Plain name of the source, for messages."""
        return f"database {self.url}"


class LocalDatabase(DatabaseLocation):
    """The workstation's database, opened (and migrated to head) on the first :meth:`_session`."""

    #: The error a source raises when the database cannot be opened; subclasses name their own.
    source_error: ClassVar[type[StationError]] = LocalDatabaseError

    def __init__(self, url: str | None = None) -> None:
        self._url = url
        self._sessions: Any = None

    def _session(self) -> Any:
        """A new ORM session (the caller closes it: ``with self._session() as session``)."""
        if self._sessions is None:
            from db.engine import make_engine, make_sessionmaker
            from db.migrate import ensure_at_head

            try:
                ensure_at_head(self.url)
            except Exception as exc:  # any driver or migration error: said with the database named
                raise self.source_error(f"{self.where}: {type(exc).__name__}: {exc}") from exc
            self._sessions = make_sessionmaker(make_engine(self.url))
        return self._sessions()
