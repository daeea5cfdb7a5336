"""A station that ingests a deterministic stream of readings; the kill test SIGKILLs it at random.

Usage: ``python -m tests.ingest._child URL OUTBOX ACKS SEED COUNT [BUSY_MS]``. Each acknowledged
reading (``submit`` returned: stored, duplicate or queued) is appended to ACKS and fsynced. On start
the outbox is replayed, then the stream resumes a few readings before the last acknowledged one (a
station resends what it cannot prove was delivered; the overlap exercises the duplicate path).
"""

from __future__ import annotations

import os
import sys

from db.engine import make_engine
from station.ingest import Ingestor
from tests.ingest._readings import make_reading

RESEND_OVERLAP = 3


def _resume_from(acks: str) -> int:
    try:
        with open(acks, encoding="utf-8") as f:
            done = [int(line.split()[0]) for line in f if len(line.split()) == 3]
    except FileNotFoundError:
        return 0
    return max(0, max(done, default=-1) + 1 - RESEND_OVERLAP)


def main(argv: list[str]) -> int:
    url, outbox, acks, seed, count = argv[:5]
    busy_ms = int(argv[5]) if len(argv) > 5 else 30_000
    engine = make_engine(
        url,
        busy_timeout_ms=busy_ms,
        connect_args={"connect_timeout": 2} if url.startswith("postgres") else {},
    )
    with Ingestor(engine, outbox) as ingestor, open(acks, "a", encoding="utf-8") as ack:
        ingestor.replay()
        for i in range(_resume_from(acks), int(count)):
            receipt = ingestor.submit(make_reading(int(seed), i))
            ack.write(f"{i} {receipt.client_id} {receipt.status}\n")
            ack.flush()
            os.fsync(ack.fileno())
    engine.dispose()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
