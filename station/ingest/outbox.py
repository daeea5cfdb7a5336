"""A durable, ordered on-disk outbox for readings the database could not take.

The outbox is a small SQLite file (WAL, ``synchronous=FULL``: an entry is on disk when :meth:`put`
returns), private to its owner (0600). Entries keep their arrival order (``seq``); a client id is queued at most once. Entries that
the database refuses for a reason other than being unreachable move to a dead-letter table with the
error, so one bad reading cannot block the readings behind it.
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from db.files import private_dir, private_sqlite
from station.closing import Closing

_SCHEMA = """
CREATE TABLE IF NOT EXISTS outbox (
    seq INTEGER PRIMARY KEY AUTOINCREMENT,
    client_id TEXT NOT NULL UNIQUE,
    body TEXT NOT NULL,
    queued_at TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS dead_letter (
    seq INTEGER PRIMARY KEY,
    client_id TEXT NOT NULL,
    body TEXT NOT NULL,
    error TEXT NOT NULL,
    failed_at TEXT NOT NULL
);
"""


@dataclass(frozen=True)
class OutboxEntry:
    """One queued reading: its order, client id and canonical JSON body."""

    seq: int
    client_id: str
    body: str


class Outbox(Closing):
    """The on-disk queue; open one per process (SQLite serialises writers across processes)."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        if not self.path.parent.exists():
            private_dir(self.path.parent)
        # 0600 before SQLite opens it; its -wal/-shm files take the same mode
        private_sqlite(self.path, "outbox")
        self._conn = sqlite3.connect(self.path, isolation_level=None, timeout=30.0, check_same_thread=False)
        self._conn.execute("PRAGMA journal_mode=WAL")
        self._conn.execute("PRAGMA synchronous=FULL")
        self._conn.executescript(_SCHEMA)

    def close(self) -> None:
        """Close the file."""
        self._conn.close()

    def put(self, client_id: str, body: str) -> None:
        """Append a reading (durable on return); a client id already queued is left as it is."""
        now = dt.datetime.now(dt.UTC).isoformat()
        self._conn.execute(
            "INSERT OR IGNORE INTO outbox (client_id, body, queued_at) VALUES (?, ?, ?)",
            (client_id, body, now),
        )

    def entries(self) -> Iterator[OutboxEntry]:
        """Queued readings, oldest first."""
        rows = self._conn.execute("SELECT seq, client_id, body FROM outbox ORDER BY seq").fetchall()
        for seq, client_id, body in rows:
            yield OutboxEntry(seq, client_id, body)

    def remove(self, seq: int) -> None:
        """Acknowledge an entry the database now holds."""
        self._conn.execute("DELETE FROM outbox WHERE seq = ?", (seq,))

    def bury(self, entry: OutboxEntry, error: str) -> None:
        """Move an entry the database refused (not unreachable: refused) to the dead-letter table."""
        now = dt.datetime.now(dt.UTC).isoformat()
        self._conn.execute("BEGIN IMMEDIATE")
        try:
            self._conn.execute(
                "INSERT OR REPLACE INTO dead_letter (seq, client_id, body, error, failed_at) VALUES (?, ?, ?, ?, ?)",
                (entry.seq, entry.client_id, entry.body, error[:2000], now),
            )
            self._conn.execute("DELETE FROM outbox WHERE seq = ?", (entry.seq,))
            self._conn.execute("COMMIT")
        except BaseException:
            self._conn.execute("ROLLBACK")
            raise

    def __len__(self) -> int:
        return int(self._conn.execute("SELECT count(*) FROM outbox").fetchone()[0])

    def dead_letters(self) -> list[tuple[str, str]]:
        """``(client_id, error)`` of every reading the database refused."""
        return [tuple(r) for r in self._conn.execute("SELECT client_id, error FROM dead_letter ORDER BY seq")]
