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

from sqlalchemy import Engine, text

PROBE_BUSY_TIMEOUT_S = 0.2


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


def probe_database(engine: Engine) -> None:
    """Raise unless the database takes a write transaction now (SQLite: within 0.2 s; PostgreSQL: ``SELECT 1``).

    SQLite is probed on its own connection with ``BEGIN IMMEDIATE`` and a short busy timeout, so a
    competing writer holding the lock makes the probe fail fast instead of waiting the engine's
    busy timeout.
    """
    if engine.dialect.name == "sqlite":
        path = engine.url.database
        if not path or path == ":memory:":
            return
        raw = sqlite3.connect(path, timeout=PROBE_BUSY_TIMEOUT_S, isolation_level=None)
        try:
            raw.execute("BEGIN IMMEDIATE")
            raw.execute("ROLLBACK")
        finally:
            raw.close()
        return
    with engine.connect() as conn:
        conn.execute(text("SELECT 1"))
