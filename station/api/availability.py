"""Whether the service's database is reachable now: the state the routes read, and the probe that sets it.

While the database is away the service keeps taking readings (into the outbox, with tokens from the
:class:`~station.api.security.TokenCache`) without waiting on the database per request; the
background watcher in ``station.api.app`` probes it every ``Settings.outbox_replay_s`` seconds and,
once it answers, marks it back and drains the outbox.
"""

from __future__ import annotations

import sqlite3
import threading
import time
from urllib.parse import quote

from sqlalchemy import Engine, text

PROBE_BUSY_TIMEOUT_S = 0.2  # how long the probe's read may wait (WAL readers do not wait for writers)
PROBE_OK = "ok"  # the database answers and its write lock is free
PROBE_BUSY = "busy"  # the database answers; another connection holds the write lock (writers queue)


class DatabaseState:
    """Reachable or away since a moment (``time.monotonic`` seconds), with the reason; one per app.

    While away, :meth:`should_try` lets one caller per *retry_s* seconds try the database again (the
    others do without it), so a request path notices the database is back even between the
    background watcher's probes, and at most one request per *retry_s* pays a busy wait.
    """

    def __init__(self, retry_s: float = 2.0) -> None:
        self.retry_s = retry_s
        self._lock = threading.Lock()
        self._away_since: float | None = None
        self._last_try = 0.0
        self._reason = ""

    def should_try(self) -> bool:
        """Whether this caller should use the database now (reachable, or its turn to retry)."""
        with self._lock:
            if self._away_since is None:
                return True
            now = time.monotonic()
            if now - self._last_try >= self.retry_s:
                self._last_try = now
                return True
            return False

    @property
    def away(self) -> bool:
        """Whether the last attempt found the database away."""
        with self._lock:
            return self._away_since is not None

    def away_for_s(self) -> float | None:
        """Seconds since the database went away, or ``None`` when it is reachable."""
        with self._lock:
            since = self._away_since
        return None if since is None else time.monotonic() - since

    @property
    def reason(self) -> str:
        """Why the database counts as away (empty when reachable)."""
        with self._lock:
            return self._reason

    def mark_away(self, reason: BaseException | str) -> None:
        """Note that an attempt found the database away (the first failure sets the start)."""
        text_ = reason if isinstance(reason, str) else f"{type(reason).__name__}"
        with self._lock:
            now = time.monotonic()
            if self._away_since is None:
                self._away_since = now
            self._last_try = now
            self._reason = text_

    def mark_back(self) -> None:
        """Note that the database answered."""
        with self._lock:
            self._away_since = None
            self._reason = ""


def probe_database(engine: Engine) -> str:
    """``"ok"`` or ``"busy"`` when the database answers a read now; raises when it cannot be opened or read.

    SQLite is probed on its own connection (opened by SQLite, ``mode=rw``: a missing file is not
    created) with a deferred read, which in WAL mode does not wait for a writer; then a zero-wait
    ``BEGIN IMMEDIATE`` (rolled back at once, nothing written) tells whether another connection holds
    the write lock: ``"busy"``, a healthy database whose writers queue. Only a database that cannot
    be opened or read (within :data:`PROBE_BUSY_TIMEOUT_S`) raises, which the callers count as away.
    PostgreSQL: ``SELECT 1`` on a read-only transaction.
    """
    if engine.dialect.name == "sqlite":
        path = engine.url.database
        if not path or path == ":memory:" or path.startswith("file:"):
            return PROBE_OK
        raw = sqlite3.connect(
            f"file:{quote(path)}?mode=rw", uri=True, timeout=PROBE_BUSY_TIMEOUT_S, isolation_level=None
        )
        try:
            raw.execute("BEGIN")
            raw.execute("SELECT count(*) FROM sqlite_master").fetchone()
            raw.execute("COMMIT")
            raw.execute("PRAGMA busy_timeout=0")
            try:
                raw.execute("BEGIN IMMEDIATE")
            except sqlite3.OperationalError as exc:
                if exc.sqlite_errorcode & 0xFF in (sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED):
                    return PROBE_BUSY
                raise
            raw.execute("ROLLBACK")
        finally:
            raw.close()
        return PROBE_OK
    with engine.connect() as conn:
        conn.execute(text("SELECT 1"))
    return PROBE_OK
