"""ColorSnap on the service restricted to one named stored library: the first request builds that
library's exact index, later ones reuse it; baseline: the same request over every stored library, in the
same run (the service on SQLite in-process, the demo library plus a second SYNTHETIC book).

Run ``python -m bench.named_library_snap``; writes its section of docs/benchmarks.md.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

#: Requests timed per case (the median is reported).
REPEATS = 15
DESIGN = {"face": [62.0, -4.0, -38.0], "flop": [24.0, 1.0, -20.0], "travel_deg": 70.0, "gloss_gu": 88.0}


def _rows() -> list[dict[str, Any]]:
    from station.api.services.library import library_rows
    from station.formulate.demo import demo_library, generate_library

    demo = library_rows(demo_library())
    book = library_rows(generate_library(n_solid=1500, n_metallic=1000, n_pearl=500, seed=11))
    for r in book:
        r["code"] = r["name"] = f"B-{r['code']}"
        r["extra"]["library"] = "book B"
    return demo + book


def run() -> None:
    """Time the three cases and write the section."""
    from fastapi.testclient import TestClient
    from sqlalchemy import insert

    from bench._report import Case, write_section
    from db.models import LibraryPaint, Role
    from station.api import Settings, create_app
    from station.api.services import users

    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        opts: dict[str, Any] = {
            "database_url": f"sqlite:///{tmp / 'bench.sqlite3'}",
            "data_dir": tmp,
            "simulators": (),
            "load_demo_library": False,
        }
        app = create_app(Settings(**opts))
        with TestClient(app) as client:
            with app.state.sessions() as session:
                users.bootstrap_admin(session=session)
                _u, _t, secret = users.create_user(
                    session=session, actor=None, name="chemist-1", role=Role.CHEMIST
                )
                rows = _rows()
                session.execute(insert(LibraryPaint), rows)
                session.commit()
            auth = {"Authorization": f"Bearer {secret}"}

            def post(body: dict) -> float:
                t = time.perf_counter()
                r = client.post(
                    "/api/v1/formulation/snap", json={"design": DESIGN, "k": 5, **body}, headers=auth
                )
                assert r.status_code == 200, r.text
                return (time.perf_counter() - t) * 1e3

            post({})  # builds the whole library's index once (not timed: both cases share it)
            every = statistics.median(post({}) for _ in range(REPEATS))
            first = post({"library": "book B"})
            again = statistics.median(post({"library": "book B"}) for _ in range(REPEATS))
            builds = app.state.library_cache.named_builds
    size = f"{len(rows)} paints"
    cases = [
        Case("snap, every stored library (baseline)", size, every, "ms", "median request"),
        Case(
            "snap, one named library, first request",
            size,
            first,
            "ms",
            f"builds its index; ×{first / every:.2f}",
        ),
        Case(
            "snap, one named library, later requests",
            size,
            again,
            "ms",
            f"median; ×{again / every:.2f} of the baseline; {builds} index build(s) in all",
        ),
    ]
    write_section("named_library_snap", "ColorSnap restricted to one named library (service)", cases)


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "named_library_snap")
    run()
