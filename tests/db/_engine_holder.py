"""A process that keeps engines open on one SQLite file, as the viewer does, and stores readings on cue.

Usage: ``python -m tests.db._engine_holder URL OUTBOX SEED``. It stores reading 0 of stream *SEED*
through its first engine, then creates two more engines on the same file (the viewer makes three),
prints ``ready`` and waits for a line on stdin; then it stores reading 1 through the first engine,
prints each measurement id (``stored N``) and exits, disposing the engines.
"""

from __future__ import annotations

import sys

from db.engine import make_engine
from station.ingest import Ingestor
from tests.ingest._readings import make_reading


def main(argv: list[str]) -> int:
    url, outbox, seed = argv[0], argv[1], int(argv[2])
    first = make_engine(url)
    with Ingestor(first, outbox) as ingestor:
        print(f"stored {ingestor.submit(make_reading(seed, 0)).measurement_id}", flush=True)
        others = [make_engine(url) for _ in range(2)]
        print("ready", flush=True)
        sys.stdin.readline()
        print(f"stored {ingestor.submit(make_reading(seed, 1)).measurement_id}", flush=True)
    for engine in (first, *others):
        engine.dispose()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
