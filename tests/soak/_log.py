"""The senders' logs of the soak test: append-only JSON lines, each fsynced before the sender goes on.

A sender writes ``sent`` before it hands a reading to the product and ``ack`` once the product has
acknowledged it: the status (``stored``, ``duplicate``, ``queued``, ``refused``), the measurement id
when one was given and the Lab it knows (rows of L*, a*, b*, D65/10°). A sender killed between the two
leaves a ``sent`` without an ``ack``: an unacknowledged send. A line torn by a kill is skipped.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from station.closing import Closing

Event = Literal["sent", "ack"]
Lab = tuple[tuple[float, ...], ...]

#: The statuses that acknowledge a reading: the product stored it, had it already, or holds it on disk.
ACCEPTED = frozenset({"stored", "duplicate", "queued"})


@dataclass(frozen=True)
class Entry:
    """One line of a sender's log."""

    sender: str
    event: Event
    client_id: str
    status: str = ""
    measurement_id: int | None = None
    lab: Lab | None = None


def _lab(rows: Sequence[Sequence[float]] | None) -> list[list[float]] | None:
    return None if rows is None else [[float(v) for v in row] for row in rows]


class SenderLog(Closing):
    """The log of one sender at *path* (appended to across restarts; mode 0600)."""

    def __init__(self, path: Path | str, sender: str) -> None:
        self.path = Path(path)
        self.sender = sender
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)

    def sent(self, client_id: str, lab: Sequence[Sequence[float]] | None = None) -> None:
        """Record that *client_id* is about to be handed to the product (durable on return)."""
        self._write({"event": "sent", "client_id": client_id, "lab": _lab(lab)})

    def ack(
        self,
        client_id: str,
        status: str,
        measurement_id: int | None,
        lab: Sequence[Sequence[float]] | None = None,
    ) -> None:
        """Record the product's answer for *client_id* (durable on return)."""
        self._write(
            {
                "event": "ack",
                "client_id": client_id,
                "status": status,
                "measurement_id": measurement_id,
                "lab": _lab(lab),
            }
        )

    def _write(self, doc: dict[str, Any]) -> None:
        line = json.dumps({"sender": self.sender, **doc}, separators=(",", ":")) + "\n"
        os.write(self._fd, line.encode("utf-8"))  # one write per line: O_APPEND keeps lines whole
        os.fsync(self._fd)

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


def _entry(doc: dict[str, Any]) -> Entry:
    lab = doc.get("lab")
    mid = doc.get("measurement_id")
    return Entry(
        sender=str(doc["sender"]),
        event="ack" if doc["event"] == "ack" else "sent",
        client_id=str(doc["client_id"]),
        status=str(doc.get("status") or ""),
        measurement_id=None if mid is None else int(mid),
        lab=None if lab is None else tuple(tuple(float(v) for v in row) for row in lab),
    )


def read_log(path: Path) -> list[Entry]:
    """The complete lines of the log at *path* (none when it does not exist), in order."""
    if not path.exists():
        return []
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            doc = json.loads(line)
        except json.JSONDecodeError:  # torn by a kill mid-line
            continue
        if isinstance(doc, dict) and doc.get("event") in ("sent", "ack") and "client_id" in doc:
            out.append(_entry(doc))
    return out


def read_logs(paths: Iterable[Path]) -> list[Entry]:
    """Every entry of every log at *paths*."""
    return [e for p in paths for e in read_log(p)]


def _outcomes(path: Path) -> list[dict[str, Any]]:
    """The complete JSON lines of a watch folder's outcome file."""
    if not path.exists():
        return []
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            doc = json.loads(line)
        except json.JSONDecodeError:  # torn by a kill mid-line
            continue
        if isinstance(doc, dict):
            out.append(doc)
    return out


def read_watch_rejections(path: Path) -> list[str]:
    """``file: reason`` of each file the watch folder moved to ``rejected/`` (none was meant to be)."""
    return [f"{d.get('file')}: {d.get('reason')}" for d in _outcomes(path) if d.get("status") == "rejected"]


def read_watch_outcomes(path: Path, sender: str) -> list[Entry]:
    """The acknowledgements a watch folder printed (``station import watch --json``: one outcome per
    line, a receipt per reading of a file moved to ``done/``), as ``ack`` entries of *sender*."""
    out = []
    for doc in _outcomes(path):
        if doc.get("status") != "done":
            continue
        for r in doc.get("receipts", []):
            mid = r.get("measurement_id")
            out.append(
                Entry(sender, "ack", str(r["client_id"]), str(r["status"]), None if mid is None else int(mid))
            )
    return out
