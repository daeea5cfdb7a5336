"""The soak test's accounting: what the senders' logs say against what the database holds.

Rules (a broken one is a *problem*, named with the client id):

* every acknowledged reading (``stored``, ``duplicate`` or ``queued``) is stored exactly once, under
  the measurement id it was acknowledged with (when one was given) and with the Lab the sender knew;
* no measurement id is acknowledged for two different readings;
* an unacknowledged send (its sender was killed mid-flight) is stored at most once;
* nothing is stored that no sender sent, and every stored reading has exactly one audit event;
* no reading was refused.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from sqlalchemy import create_engine, func, select
from sqlalchemy.pool import NullPool

from db.engine import normalise_url
from db.models import AuditEvent, Measurement
from tests.soak._log import ACCEPTED, Entry, Lab

#: Largest difference (CIELAB units) between a logged Lab and the stored one: the files carry 4 decimals.
LAB_TOLERANCE = 1e-3


@dataclass(frozen=True)
class StoredRow:
    """One stored measurement: id, client id and Lab per geometry."""

    id: int
    client_id: str
    lab: Lab


@dataclass(frozen=True)
class Stored:
    """What the database holds: the measurements and the number of audit events of each id."""

    rows: tuple[StoredRow, ...]
    audits: dict[int, int]


def read_stored(url: str) -> Stored:
    """Every measurement of the database at *url* and its audit event count."""
    engine = create_engine(normalise_url(url), poolclass=NullPool)
    try:
        with engine.connect() as conn:
            rows = conn.execute(select(Measurement.id, Measurement.client_id, Measurement.lab)).all()
            audits = conn.execute(
                select(AuditEvent.entity_id, func.count())
                .where(AuditEvent.entity == "measurement")
                .group_by(AuditEvent.entity_id)
            ).all()
    finally:
        engine.dispose()
    return Stored(
        tuple(
            StoredRow(int(r.id), str(r.client_id), tuple(tuple(float(v) for v in row) for row in r.lab))
            for r in rows
        ),
        {int(e): int(n) for e, n in audits},
    )


@dataclass(frozen=True)
class Accounts:
    """The outcome of :func:`account`: figures and problems (empty when every rule holds)."""

    sent: int
    acknowledged: int
    unacknowledged: int
    stored: int
    lost: tuple[str, ...] = ()
    lost_by_sender: dict[str, int] = field(default_factory=dict)
    reused_ids: int = 0
    problems: tuple[str, ...] = field(default=())

    def summary(self) -> str:
        """One line of figures."""
        return (
            f"{self.sent} sent, {self.acknowledged} acknowledged, {self.unacknowledged} unacknowledged, "
            f"{self.stored} stored, {len(self.lost)} acknowledged readings missing {self.lost_by_sender}, "
            f"{self.reused_ids} measurement ids acknowledged for two readings or more, "
            f"{len(self.problems)} problems"
        )


def _same_lab(a: Lab, b: Lab) -> bool:
    return len(a) == len(b) and all(
        len(x) == len(y) and all(math.isclose(u, v, abs_tol=LAB_TOLERANCE) for u, v in zip(x, y, strict=True))
        for x, y in zip(a, b, strict=True)
    )


def account(entries: Iterable[Entry], stored: Stored) -> Accounts:
    """Check the rules of the module docstring for the senders' *entries* against *stored*."""
    sent: dict[str, list[Entry]] = defaultdict(list)
    acks: dict[str, list[Entry]] = defaultdict(list)
    for e in entries:
        (acks if e.event == "ack" else sent)[e.client_id].append(e)
    rows: dict[str, list[StoredRow]] = defaultdict(list)
    for r in stored.rows:
        rows[r.client_id].append(r)
    problems: list[str] = []
    lost: list[str] = []
    lost_by: dict[str, int] = defaultdict(int)
    ids_acknowledged: dict[int, set[str]] = defaultdict(set)

    for cid, answers in sorted(acks.items()):
        here = rows.get(cid, [])
        for a in answers:
            if a.status not in ACCEPTED:
                problems.append(f"{a.sender}: reading {cid} answered {a.status!r}")
            if a.measurement_id is not None:
                ids_acknowledged[a.measurement_id].add(cid)
        if not any(a.status in ACCEPTED for a in answers):
            continue
        senders = sorted({a.sender for a in answers})
        if not here:
            lost.append(cid)
            for sender in senders:
                lost_by[sender] += 1
            given = sorted({a.measurement_id for a in answers if a.measurement_id is not None})
            problems.append(
                f"{'/'.join(senders)}: acknowledged reading {cid} (measurement {given}) is not stored"
            )
            continue
        if len(here) > 1:
            problems.append(f"{'/'.join(senders)}: reading {cid} stored {len(here)} times")
        row = here[0]
        for a in answers:
            if a.measurement_id is not None and a.measurement_id != row.id:
                problems.append(
                    f"{a.sender}: reading {cid} acknowledged as measurement {a.measurement_id}, "
                    f"stored as {row.id}"
                )
        for e in (*sent.get(cid, ()), *answers):
            if e.lab is not None and not _same_lab(e.lab, row.lab):
                problems.append(f"{e.sender}: reading {cid} stored with another Lab than it {e.event}")
                break

    reused = 0
    for mid, cids in sorted(ids_acknowledged.items()):
        if len(cids) > 1:
            reused += 1
            problems.append(
                f"measurement id {mid} acknowledged for {len(cids)} different readings: {sorted(cids)}"
            )

    unacknowledged = [cid for cid in sent if cid not in acks]
    for cid in unacknowledged:
        if len(rows.get(cid, [])) > 1:
            problems.append(f"unacknowledged reading {cid} stored {len(rows[cid])} times")

    known = set(sent) | set(acks)
    for cid in sorted(set(rows) - known):
        problems.append(f"reading {cid} (measurement {rows[cid][0].id}) is stored but no sender sent it")

    for r in stored.rows:
        n = stored.audits.get(r.id, 0)
        if n != 1:
            problems.append(f"measurement {r.id} ({r.client_id}) has {n} audit events")

    return Accounts(
        sent=len(known),
        acknowledged=sum(1 for answers in acks.values() if any(a.status in ACCEPTED for a in answers)),
        unacknowledged=len(unacknowledged),
        stored=len(stored.rows),
        lost=tuple(lost),
        lost_by_sender=dict(lost_by),
        reused_ids=reused,
        problems=tuple(problems),
    )


def format_problems(problems: Sequence[str], limit: int = 20) -> str:
    """The first *limit* problems, one a line, and how many more there are."""
    head = "\n".join(f"  {p}" for p in problems[:limit])
    more = f"\n  … and {len(problems) - limit} more" if len(problems) > limit else ""
    return head + more
