"""Soak: every front of the product on one database, SIGKILLed at random; nothing lost, nothing twice.

For a bounded time (``$CACAD_SOAK_SECONDS``, default :data:`DEFAULT_SOAK_S`; set it to minutes for a
dedicated run) four writers store into ONE database, an SQLite file and, second, a PostgreSQL database:
the viewer's models (headless child process), ``station import FILE --store`` run from a folder outside
the checkout, a real ``station serve`` measuring its MA6 simulator over HTTP, and ``station import
watch`` fed by dropped files (see :mod:`tests.soak._fronts`). They join as on a technician's day: the
viewer and the terminal imports first, the service and the watch folder once the viewer has stored a
scan.
Then a seeded chaos loop SIGKILLs a random subset of them every few seconds; each killed front is
restarted after a random while and each sender retries what it was sending, as a person or a station
would. Every sender keeps its own fsynced log of what it sent and what the product acknowledged
(:mod:`tests.soak._log`; the watch folder's acknowledgements are its ``--json`` outcome lines).

At the end (senders stopped, what they had in hand left unacknowledged, fronts asked to end, the
outboxes drained by the product's ingest loop as a restart would) the logs are accounted against the
database (:mod:`tests.soak._accounting`): every acknowledged reading stored exactly once under the id it
was given, no id given to two readings, an unacknowledged send stored at most once, one audit event
each; and ``station db verify`` says intact.

The soak lasts at least the configured time and until every sender has had :data:`MIN_ACKS` answers
and every front has been killed once, so a slow machine makes it longer, never weaker; past
:data:`OVERRUN_S` more it fails as too slow. A front that crashes or answers an error ends the chaos at
once (the run has failed). The seed is printed (``$CACAD_SOAK_SEED`` replays the chaos schedule; the
timing of the processes is the machine's).

The detector itself is tested below: one acknowledged reading deleted with raw SQL and the chain heads
rewound must show up in the accounting and in ``station db verify``.
"""

from __future__ import annotations

import json
import os
import random
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from sqlalchemy import Connection, create_engine, select, text
from sqlalchemy.pool import NullPool

from db.chain_audit import verify as verify_chains
from db.engine import normalise_url
from db.models import Measurement
from station.ingest import Ingestor
from tests.ingest._readings import make_reading
from tests.processes import run
from tests.soak._accounting import Accounts, account, format_problems, read_stored
from tests.soak._fronts import (
    START_TIMEOUT_S,
    STOP_TIMEOUT_S,
    DropSender,
    Findings,
    Front,
    ImportFront,
    MeasureSender,
    ServiceFront,
    Target,
    ViewerFront,
    WatcherFront,
    child_env,
    wait_until,
)
from tests.soak._log import SenderLog, read_log, read_logs, read_watch_outcomes, read_watch_rejections

DEFAULT_SOAK_S = 20.0
#: Answers every sender must have had before the soak may end.
MIN_ACKS = 2
#: How much longer than the configured time the soak may run to reach its minimum (seconds).
OVERRUN_S = 150.0
#: Pause between two chaos rounds (seconds, drawn uniformly).
CHAOS_PAUSE_S = (1.0, 4.0)
#: The chance that a chaos round kills each front (an import lives a few seconds: killed more often, it
#: would hardly ever finish).
KILL_SHARE = {"viewer": 0.3, "import": 0.15, "service": 0.4, "watcher": 0.4}
#: Time for the senders to finish the send in hand once told to stop, through a last restart (seconds).
FINISH_S = 300.0


def soak_seconds() -> float:
    """``$CACAD_SOAK_SECONDS`` (a positive number of seconds) or :data:`DEFAULT_SOAK_S`."""
    raw = os.environ.get("CACAD_SOAK_SECONDS", "")
    if not raw:
        return DEFAULT_SOAK_S
    try:
        value = float(raw)
    except ValueError:
        value = -1.0
    if not 0 < value <= 86_400:
        raise pytest.UsageError(f"CACAD_SOAK_SECONDS: a number of seconds, 0 < s <= 86400; got {raw!r}")
    return value


def soak_seed() -> int:
    """``$CACAD_SOAK_SEED`` (to replay a run) or a fresh random seed."""
    raw = os.environ.get("CACAD_SOAK_SEED", "")
    return int(raw) if raw else int.from_bytes(os.urandom(4), "little")


@dataclass(frozen=True)
class Verify:
    """``station db verify --json``: exit status and what it printed."""

    status: int
    report: dict[str, object]
    stderr: str

    @property
    def intact(self) -> bool:
        return self.status == 0 and self.report.get("chain") == "intact"


def db_verify(url: str, cwd: Path) -> Verify:
    """Run ``station db verify --database URL --json`` in *cwd* (a folder outside the checkout)."""
    res = run(
        [sys.executable, "-m", "station.cli", "db", "verify", "--database", url, "--json"],
        cwd=cwd, env=child_env(cwd), timeout=300,
    )  # fmt: skip
    try:
        report = json.loads(res.stdout) if res.stdout.strip() else {}
    except json.JSONDecodeError:
        report = {"output": res.stdout[-2000:]}
    return Verify(
        res.returncode, report if isinstance(report, dict) else {"output": report}, res.stderr[-2000:]
    )


@dataclass
class SoakReport:
    """What one soak run did and found."""

    seed: int
    url: str
    phases: dict[str, float] = field(default_factory=dict)
    kills: dict[str, int] = field(default_factory=dict)
    starts: dict[str, int] = field(default_factory=dict)
    sends: dict[str, int] = field(default_factory=dict)
    acks: dict[str, int] = field(default_factory=dict)
    timeline: list[str] = field(default_factory=list)
    drained: int = 0
    findings: list[str] = field(default_factory=list)
    accounts: Accounts | None = None
    verify: Verify | None = None

    def summary(self) -> str:
        """The figures, one paragraph."""
        acc = self.accounts.summary() if self.accounts is not None else "not accounted"
        verify = (
            "not run"
            if self.verify is None
            else f"status {self.verify.status} {self.verify.report} {self.verify.stderr.strip()[-300:]}"
        )
        phases = ", ".join(f"{name} {s:.0f} s" for name, s in self.phases.items())
        return (
            f"soak seed {self.seed} on {self.url.split(':', 1)[0]} ({phases}): "
            f"kills {self.kills}; starts {self.starts}; sends {self.sends}; answers {self.acks}; "
            f"{self.drained} readings drained from outboxes; {acc}; station db verify: {verify}"
        )


def _answers(log: Path) -> int:
    return sum(1 for e in read_log(log) if e.event == "ack")


def _drain(url: str, outbox: Path, findings: Findings) -> int:
    """Replay *outbox* into *url* as the front's next start would; how many readings left it."""
    if not outbox.exists():
        return 0
    with Ingestor(url, outbox) as ingestor:  # from a URL: the ingest loop closes its engine with it
        try:
            receipts = ingestor.drain()
        except Exception as exc:  # a database the fronts broke
            findings.add(f"outbox {outbox.name}: drain failed: {type(exc).__name__}: {exc}")
            return 0
        for r in receipts:
            if r.status not in ("stored", "duplicate"):
                findings.add(f"outbox {outbox.name}: reading {r.client_id} {r.status}: {r.message}")
        if len(ingestor.outbox) or ingestor.outbox.dead_letters():
            findings.add(
                f"outbox {outbox.name}: {len(ingestor.outbox)} queued, "
                f"{len(ingestor.outbox.dead_letters())} dead letters after the drain"
            )
    return len(receipts)


def run_soak(work: Path, url: str, seed: int, soak_s: float) -> SoakReport:
    """Run the fronts on *url* for *soak_s* seconds of chaos (see the module docstring); the report."""
    report = SoakReport(seed, url)
    findings = Findings()
    stop_sending = threading.Event()
    logs = {name: work / f"{name}.log" for name in ("viewer", "import", "service", "watcher")}
    viewer = ViewerFront(work, findings, seed + 4, url, logs["viewer"])
    service = ServiceFront(work, findings, seed + 5, url)
    watcher = WatcherFront(work, findings, seed + 6, url)
    fronts: list[Front] = [service, watcher, viewer]
    importer = ImportFront(work, findings, stop_sending, url, logs["import"], seed + 1)
    senders = [
        importer,
        MeasureSender(service, findings, stop_sending, logs["service"], seed + 2),
        DropSender(watcher, findings, stop_sending, logs["watcher"], seed + 3),
    ]
    targets: list[Target] = [viewer, importer, service, watcher]
    rng = random.Random(seed)
    pause = threading.Event()  # never set: the chaos loop's pause between rounds
    clock = [time.monotonic()]

    def lap(phase: str) -> None:
        now = time.monotonic()
        report.phases[phase] = now - clock[0]
        clock[0] = now

    def answers() -> dict[str, int]:
        got = {name: _answers(path) for name, path in logs.items() if name != "watcher"}
        got["watcher"] = len(read_watch_outcomes(watcher.outcomes, "watcher"))
        return got

    def started(front: Front) -> None:
        if not front.wait_ready(START_TIMEOUT_S):
            pytest.fail(
                f"{front.label} did not start in {START_TIMEOUT_S:g} s:\n" + "\n".join(findings.items())
            )

    try:
        # A technician's day: the viewer and imports from a terminal first; the service and the watch
        # folder join once the viewer has stored a scan.
        viewer.supervise()
        importer.start()
        started(viewer)
        if not wait_until(lambda: answers()["viewer"] >= 1, START_TIMEOUT_S):
            pytest.fail(
                f"no scan stored in {START_TIMEOUT_S:g} s: {answers()}\n" + "\n".join(findings.items())
            )
        service.supervise()
        watcher.supervise()
        started(service)
        started(watcher)
        for sender in senders[1:]:
            sender.start()
        lap("start")

        t0 = time.monotonic()
        while True:
            elapsed = time.monotonic() - t0
            if elapsed >= soak_s and all(t.kills for t in targets) and min(answers().values()) >= MIN_ACKS:
                break
            if findings.items():  # a front crashed or answered an error: the run has failed already
                break
            if elapsed >= soak_s + OVERRUN_S:
                findings.add(
                    f"too slow: after {elapsed:.0f} s answers {answers()}, kills "
                    f"{ {t.label: t.kills for t in targets} } (wanted {MIN_ACKS} answers and a kill each)"
                )
                break
            pause.wait(rng.uniform(*CHAOS_PAUSE_S))
            chosen = [t for t in targets if rng.random() < KILL_SHARE[t.label]] or [rng.choice(targets)]
            landed = [t.label for t in chosen if t.kill()]
            if landed:
                report.timeline.append(f"{time.monotonic() - t0:.1f} s: killed {', '.join(landed)}")
        lap("chaos")

        stop_sending.set()
        importer.close()  # the import in hand is killed, the last unacknowledged send
        for front in fronts:
            front.hurry()  # a front killed in the last round comes back at once to end cleanly
        for sender in senders:
            sender.join(FINISH_S)
            if sender.is_alive():
                findings.add(f"{sender.sender} sender did not finish its last send in {FINISH_S:g} s")
        for front in fronts:  # files still in the drop folder stay unacknowledged sends
            front.ask_to_end()
        for front in fronts:
            front.wait_ended()
        lap("wind-down")
        report.kills = {t.label: t.kills for t in targets}
        report.starts = {f.label: f.starts for f in fronts}
        report.sends = {s.sender: s.sends for s in senders}
        report.acks = answers()
        for outbox in (viewer.outbox, importer.outbox, service.outbox, watcher.outbox):
            report.drained += _drain(url, outbox, findings)
        for rejected in read_watch_rejections(watcher.outcomes):
            findings.add(f"watcher rejected {rejected}")
        entries = read_logs(logs.values()) + read_watch_outcomes(watcher.outcomes, "watcher")
        try:
            report.accounts = account(entries, read_stored(url))
        except Exception as exc:  # a database the fronts broke
            findings.add(f"the database cannot be read: {type(exc).__name__}: {exc}")
        lap("accounting")
        report.verify = db_verify(url, work)
        lap("verify")
    finally:
        stop_sending.set()
        importer.close()
        for front in fronts:
            front.close()
        for sender in senders:
            sender.join(STOP_TIMEOUT_S)
        report.findings = findings.items()
    return report


@pytest.mark.slow
@pytest.mark.timeout(soak_seconds() + OVERRUN_S + FINISH_S + 300)
def test_soak_every_front_on_one_database(database_url: str, tmp_path: Path) -> None:
    """Four fronts, random SIGKILLs: every acknowledged reading stored once, verify intact."""
    report = run_soak(tmp_path, database_url, soak_seed(), soak_seconds())
    print(report.summary())
    problems = [*report.findings, *(report.accounts.problems if report.accounts is not None else ())]
    if report.verify is None or not report.verify.intact:
        problems.append(f"station db verify does not say intact: {report.verify}")
    assert not problems, (
        f"{report.summary()}\nchaos: {'; '.join(report.timeline)}\n{format_problems(problems)}"
    )
    assert report.accounts is not None and report.accounts.acknowledged >= MIN_ACKS * 4
    assert all(report.kills.values()), report.kills


# --- the detector: a reading deleted behind the product's back ---------------------------------------

READINGS = 4


@dataclass(frozen=True)
class Tampered:
    """A database whose last acknowledged reading was deleted, and the sender log that acknowledged it."""

    url: str
    log: Path
    deleted: str
    work: Path


#: The tables the deletion touches; their append-only and forward-only triggers are lifted for it.
TAMPERED_TABLES = ("measurements", "audit_events", "ledger_heads")


@contextmanager
def _triggers_lifted(conn: Connection) -> Iterator[None]:
    """Inside *conn*'s transaction, without the triggers of :data:`TAMPERED_TABLES`, as the database's
    owner can: PostgreSQL replica mode (a superuser), SQLite dropped and recreated with their own SQL."""
    if conn.dialect.name == "postgresql":
        conn.execute(text("SET LOCAL session_replication_role = replica"))
        yield
        return
    names = ", ".join(f"'{t}'" for t in TAMPERED_TABLES)
    triggers = conn.execute(
        text(f"SELECT name, sql FROM sqlite_master WHERE type = 'trigger' AND tbl_name IN ({names})")
    ).all()
    for t in triggers:
        conn.execute(text(f'DROP TRIGGER "{t.name}"'))
    yield
    for t in triggers:
        conn.execute(text(t.sql))


def _delete_last_reading(url: str) -> str:
    """Delete the newest measurement and its audit event with raw SQL and rewind both chain heads to
    the rows now last (length, hash, time), as the database's owner could; its client id."""
    engine = create_engine(normalise_url(url), poolclass=NullPool)
    try:
        with engine.begin() as conn, _triggers_lifted(conn):
            last = conn.execute(
                select(Measurement.id, Measurement.client_id).order_by(Measurement.id.desc())
            ).first()
            assert last is not None
            audit = conn.execute(text("SELECT max(id) FROM audit_events")).scalar_one()
            entity = conn.execute(
                text("SELECT entity_id FROM audit_events WHERE id = :i"), {"i": audit}
            ).scalar_one()
            assert entity == str(last.id), "the newest audit event is not the newest reading's"
            conn.execute(text("DELETE FROM audit_events WHERE id = :i"), {"i": audit})
            conn.execute(text("DELETE FROM measurements WHERE id = :i"), {"i": last.id})
            for chain, at in (("measurements", "received_at"), ("audit_events", "at")):
                conn.execute(
                    text(
                        "UPDATE ledger_heads SET length = length - 1, "
                        f"head_sha256 = (SELECT chain_sha256 FROM {chain} ORDER BY id DESC LIMIT 1), "
                        f"head_at = (SELECT {at} FROM {chain} ORDER BY id DESC LIMIT 1) WHERE chain = :c"
                    ),
                    {"c": chain},
                )
    finally:
        engine.dispose()
    return str(last.client_id)


@pytest.fixture
def tampered(database_url: str, tmp_path: Path) -> Tampered:
    """READINGS readings stored and acknowledged (logged as a sender does), both chains intact and the
    accounting clean; then the last reading deleted and the heads rewound."""
    log = tmp_path / "ingest.log"
    with SenderLog(log, "ingest") as sender, Ingestor(database_url, tmp_path / "outbox.sqlite3") as ingestor:
        for i in range(READINGS):
            reading = make_reading(7, i)
            sender.sent(str(reading.client_id), reading.lab)
            receipt = ingestor.submit(reading)
            sender.ack(receipt.client_id, receipt.status, receipt.measurement_id, reading.lab)
    before = account(read_log(log), read_stored(database_url))
    assert before.problems == () and before.acknowledged == READINGS, before.problems
    engine = create_engine(normalise_url(database_url), poolclass=NullPool)
    try:
        with engine.connect() as conn:
            assert [v.broken for v in verify_chains(conn)] == [None, None]
    finally:
        engine.dispose()
    # the lab's routine after a shift: a signed checkpoint of the heads, kept in the data folder
    checkpoint = run(
        [sys.executable, "-m", "station.cli", "db", "checkpoint", "--database", database_url, "--json"],
        cwd=tmp_path, env=child_env(tmp_path), timeout=300,
    )  # fmt: skip
    assert checkpoint.returncode == 0, checkpoint.stderr[-2000:]
    return Tampered(database_url, log, _delete_last_reading(database_url), tmp_path)


def test_accounting_reports_a_deleted_reading(tampered: Tampered) -> None:
    accounts = account(read_log(tampered.log), read_stored(tampered.url))
    assert accounts.lost == (tampered.deleted,)
    assert len(accounts.problems) == 1 and tampered.deleted in accounts.problems[0]


def test_verify_reports_a_deleted_reading(tampered: Tampered) -> None:
    result = db_verify(tampered.url, tampered.work)
    assert not result.intact, f"station db verify says {result.report} after a reading was deleted"
    findings = result.report.get("findings", [])
    assert isinstance(findings, list), result.report
    kinds = {(f["chain"], f["kind"]) for f in findings}
    assert ("measurements", "rewound") in kinds, result.report
