"""The soak test's accounting rules on hand-made logs and stored rows (no processes, no database)."""

from __future__ import annotations

from pathlib import Path

from tests.soak._accounting import Stored, StoredRow, account
from tests.soak._log import Entry, SenderLog, read_log, read_watch_outcomes, read_watch_rejections

LAB = ((50.0, 1.0, -2.0), (30.0, 0.5, -1.0))


def _stored(*rows: tuple[int, str]) -> Stored:
    return Stored(tuple(StoredRow(i, c, LAB) for i, c in rows), {i: 1 for i, _ in rows})


def _sent_and_acked(cid: str, mid: int | None, status: str = "stored") -> list[Entry]:
    return [Entry("s", "sent", cid, lab=LAB), Entry("s", "ack", cid, status, mid)]


def test_every_acknowledged_reading_stored_once_is_clean() -> None:
    entries = [
        *_sent_and_acked("a", 1),
        *_sent_and_acked("b", None, "queued"),
        *_sent_and_acked("c", 3, "duplicate"),
        Entry("s", "sent", "d", lab=LAB),  # killed mid-flight, never stored
        Entry("s", "sent", "e", lab=LAB),  # killed mid-flight, stored once
    ]
    accounts = account(entries, _stored((1, "a"), (2, "b"), (3, "c"), (4, "e")))
    assert accounts.problems == ()
    assert (accounts.sent, accounts.acknowledged, accounts.unacknowledged, accounts.stored) == (5, 3, 2, 4)


def test_each_broken_rule_is_a_problem() -> None:
    entries = [
        *_sent_and_acked("lost", 1),
        *_sent_and_acked("moved", 2),
        *_sent_and_acked("twin-1", 5),
        *_sent_and_acked("twin-2", 5),
        *_sent_and_acked("refused", None, "refused"),
    ]
    stored = _stored((3, "moved"), (5, "twin-1"), (6, "twin-2"), (7, "phantom"))
    accounts = account(entries, stored)
    assert (accounts.lost, accounts.lost_by_sender, accounts.reused_ids) == (("lost",), {"s": 1}, 1)
    problems = "\n".join(accounts.problems)
    assert "reading lost (measurement [1]) is not stored" in problems
    assert "reading moved acknowledged as measurement 2, stored as 3" in problems
    assert "measurement id 5 acknowledged for 2 different readings" in problems
    assert "twin-2 acknowledged as measurement 5, stored as 6" in problems
    assert "reading refused answered 'refused'" in problems
    assert "reading phantom (measurement 7) is stored but no sender sent it" in problems


def test_another_lab_or_a_missing_audit_event_is_a_problem() -> None:
    entries = _sent_and_acked("a", 1)
    other = Stored((StoredRow(1, "a", ((50.0, 1.0, -2.5), (30.0, 0.5, -1.0))),), {1: 1})
    assert "stored with another Lab" in account(entries, other).problems[0]
    unaudited = Stored((StoredRow(1, "a", LAB),), {})
    assert account(entries, unaudited).problems == ("measurement 1 (a) has 0 audit events",)


def test_logs_keep_whole_lines_and_skip_a_torn_one(tmp_path: Path) -> None:
    path = tmp_path / "sender.log"
    with SenderLog(path, "s") as log:
        log.sent("a", [[1.0, 2.0, 3.0]])
        log.ack("a", "stored", 7)
    with open(path, "a", encoding="utf-8") as f:
        f.write('{"sender": "s", "event": "sent", "client_')  # killed mid-line
    assert read_log(path) == [
        Entry("s", "sent", "a", lab=((1.0, 2.0, 3.0),)),
        Entry("s", "ack", "a", "stored", 7),
    ]


def test_watch_outcomes_acknowledge_the_files_moved_to_done(tmp_path: Path) -> None:
    path = tmp_path / "outcomes.jsonl"
    path.write_text(
        '{"file": "a.cxf", "status": "done", "receipts": [{"client_id": "x", "status": "stored", '
        '"measurement_id": 4}, {"client_id": "y", "status": "queued", "measurement_id": null}]}\n'
        '{"file": "b.cxf", "status": "rejected", "receipts": [], "reason": "bad"}\n'
        '{"file": "c.cxf", "status": "do',
        encoding="utf-8",
    )
    assert read_watch_outcomes(path, "w") == [
        Entry("w", "ack", "x", "stored", 4),
        Entry("w", "ack", "y", "queued", None),
    ]
    assert read_watch_rejections(path) == ["b.cxf: bad"]
