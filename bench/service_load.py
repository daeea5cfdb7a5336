"""Load: 8 HTTP clients ingest readings through a real ``station serve`` on loopback, SQLite and PostgreSQL.

Each client is a process with one keep-alive connection, posting synthetic multi-angle readings
(3 geometries × 31-band spectra, Lab, gloss) to ``POST /api/v1/measurements`` as fast as the service
answers, each under its own ``client_id``, and re-sending every ``--resend-every``-th one (the
idempotent path: 200, nothing stored). Latency is the wall time of one request, token check, validation,
store and audit row included. After the run the database must hold every distinct reading sent exactly
once, each with one audit row.

The baseline, in the same run and on the same database, is raw inserts of the same measurement rows
through SQLAlchemy Core (one transaction per row, the same number of threads, no HTTP, no audit, no
validation); the report gives the service's throughput as a fraction of it. Bar: p99 of ingest on
SQLite ≤ 150 ms.

    python -m bench.service_load [--clients 8] [--duration 20] [--baseline-duration 10]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import random
import secrets
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench._report import ROOT, Case, bench_parser, write_section
from bench.ingest_load import PG_ADMIN, _reading
from station.api.serve_process import ServeProcess

P99_BAR_MS = 150.0


class Service(ServeProcess):
    """``station serve`` on a free loopback port (no simulators, no demo library); the admin token."""

    def __init__(self, data_dir: Path, database_url: str | None) -> None:
        args = ("--database", database_url) if database_url else ()
        args += ("--no-demo-library", "--simulators", "", "--log-level", "warning")
        super().__init__(data_dir, args, cwd=ROOT)
        self.start()


def _client(args: tuple[str, str, str, float, int, int, float]) -> dict[str, Any]:
    base, token, serial, duration, resend_every, seed, start_at = args
    import httpx

    rng = random.Random(seed)
    _reading(rng, serial, -1)  # imports done before the clock starts
    time.sleep(max(0.0, start_at - time.time()))  # every client starts together, after all have warmed up
    latencies: list[float] = []
    sent: list[str] = []
    resent = errors = 0
    headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/json"}
    with httpx.Client(base_url=base, timeout=30, headers=headers) as http:
        deadline = time.perf_counter() + duration
        last: str | None = None
        while time.perf_counter() < deadline:
            if (
                last is not None
                and resend_every
                and len(sent) % resend_every == 0
                and resent * resend_every < len(sent)
            ):
                body, resent = last, resent + 1
                expect = 200
            else:
                reading = _reading(rng, serial, len(sent))
                body = reading.model_dump_json()
                sent.append(str(reading.client_id))
                expect = 201
            t0 = time.perf_counter()
            r = http.post("/api/v1/measurements", content=body)
            latencies.append(time.perf_counter() - t0)
            errors += r.status_code != expect
            last = body
    return {"sent": sent, "resent": resent, "errors": errors, "latencies": latencies}


def run_service(
    base: str, token: str, clients: int, duration: float, resend_every: int, tag: str
) -> dict[str, Any]:
    """*clients* processes posting for *duration* seconds; the figures."""
    ctx = mp.get_context("spawn")
    with ctx.Pool(clients) as pool:
        start_at = time.time() + 10.0
        jobs = [
            (base, token, f"{tag}-{i:02d}", duration, resend_every, 2000 + i, start_at)
            for i in range(clients)
        ]
        results = pool.map(_client, jobs)
    lat = np.concatenate([np.asarray(r["latencies"]) for r in results]) * 1000.0
    sent = [c for r in results for c in r["sent"]]
    return {
        "sent": sent,
        "requests": int(lat.size),
        "resent": sum(r["resent"] for r in results),
        "errors": sum(r["errors"] for r in results),
        "throughput": len(sent) / duration,
        "p50": float(np.percentile(lat, 50)),
        "p99": float(np.percentile(lat, 99)),
    }


def run_raw(url: str, threads: int, duration: float, tag: str) -> dict[str, Any]:
    """Raw SQLAlchemy Core inserts of the same rows, *threads* threads, one transaction per row."""
    from sqlalchemy import insert, select

    from db.base import utcnow
    from db.engine import make_engine
    from db.models import Instrument, Measurement

    engine = make_engine(url, pool_size=threads)
    _reading(random.Random(0), f"{tag}-raw", -1)  # imports done before the clock starts
    with engine.begin() as conn:
        conn.execute(
            insert(Instrument).values(serial=f"{tag}-raw", model="MA-98 simulator", kind="multiangle")
        )
        instrument_id = conn.execute(
            select(Instrument.id).where(Instrument.serial == f"{tag}-raw")
        ).scalar_one()
    counts = [0] * threads
    latencies: list[list[float]] = [[] for _ in range(threads)]

    def work(k: int) -> None:
        rng = random.Random(3000 + k)
        deadline = time.perf_counter() + duration
        while time.perf_counter() < deadline:
            r = _reading(rng, f"{tag}-raw", counts[k])
            t0 = time.perf_counter()
            with engine.begin() as conn:
                conn.execute(
                    insert(Measurement).values(
                        client_id=r.client_id,
                        instrument_id=instrument_id,
                        operator=r.operator,
                        measured_at=r.measured_at,
                        received_at=utcnow(),
                        illuminant=r.illuminant,
                        observer=r.observer,
                        geometries_deg=list(r.geometries_deg),
                        lab=[list(v) for v in r.lab],
                        wavelengths_nm=r.wavelengths_nm,
                        spectra=r.spectra,
                        gloss_gu=r.gloss_gu,
                        payload_sha256=r.payload_sha256(),
                    )
                )
            latencies[k].append(time.perf_counter() - t0)
            counts[k] += 1

    workers = [threading.Thread(target=work, args=(k,)) for k in range(threads)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    engine.dispose()
    lat = np.concatenate([np.asarray(x) for x in latencies]) * 1000.0
    return {
        "throughput": sum(counts) / duration,
        "p50": float(np.percentile(lat, 50)),
        "p99": float(np.percentile(lat, 99)),
    }


def count_check(url: str, sent: list[str]) -> dict[str, int]:
    """Rows stored under the sent client ids, distinct ids, missing ones, and audit rows per stored row."""
    from sqlalchemy import func, select

    from db.engine import make_engine
    from db.models import AuditEvent, Measurement

    engine = make_engine(url)
    wanted = set(sent)
    with engine.connect() as conn:
        rows = [(str(c), int(i)) for c, i in conn.execute(select(Measurement.client_id, Measurement.id))]
        audits = dict(
            conn.execute(
                select(AuditEvent.entity_id, func.count())
                .where(AuditEvent.entity == "measurement")
                .group_by(AuditEvent.entity_id)
            ).all()
        )
    engine.dispose()
    ours = [(c, i) for c, i in rows if c in wanted]
    return {
        "rows": len(ours),
        "distinct": len({c for c, _ in ours}),
        "missing": len(wanted - {c for c, _ in ours}),
        "audited_once": sum(1 for _, i in ours if audits.get(str(i)) == 1),
    }


def _backend(name: str, url: str | None, data_dir: Path, args: argparse.Namespace) -> dict[str, Any]:
    db_url = url or f"sqlite:///{data_dir / 'station.sqlite3'}"
    service = Service(data_dir, url)
    try:
        load = run_service(service.base, service.token, args.clients, args.duration, args.resend_every, name)
    finally:
        service.stop()
    raw = run_raw(db_url, args.clients, args.baseline_duration, name)
    check = count_check(db_url, load["sent"])
    ok = (
        check["rows"] == check["distinct"] == check["audited_once"] == len(set(load["sent"]))
        and not check["missing"]
    )
    return {"load": load, "raw": raw, "check": check, "exactly_once": ok and load["errors"] == 0}


def main(argv: list[str] | None = None) -> int:
    parser = bench_parser(__doc__, "service_load")
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--duration", type=float, default=20.0, help="seconds of each loaded run (≤ 60)")
    parser.add_argument(
        "--baseline-duration", type=float, default=10.0, help="seconds of each raw-insert run"
    )
    parser.add_argument("--resend-every", type=int, default=20, help="re-send every Nth reading (0: never)")
    parser.add_argument(
        "--pg-admin", default=PG_ADMIN, help="maintenance database URL (a throwaway DB is made)"
    )
    parser.add_argument("--no-postgres", action="store_true")
    parser.add_argument("--no-report", action="store_true", help="print only; leave docs/ alone")
    args = parser.parse_args(argv)
    if not 0 < args.duration <= 60 or not 0 < args.baseline_duration <= 60:
        parser.error("--duration and --baseline-duration: 0 < seconds ≤ 60")

    results: dict[str, dict[str, Any]] = {}
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        results["SQLite"] = _backend("sqlite", None, Path(tmp) / "sqlite", args)
        if not args.no_postgres:
            import psycopg

            name = f"cacad_bench_{secrets.token_hex(4)}"
            admin = psycopg.connect(args.pg_admin, autocommit=True)
            admin.execute(f'CREATE DATABASE "{name}"')
            try:
                url = args.pg_admin.rsplit("/", 1)[0] + "/" + name
                results["PostgreSQL"] = _backend("pg", url, Path(tmp) / "pg", args)
            finally:
                admin.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
                admin.close()
    load_after = os.getloadavg()[0]

    n = args.clients
    cases: list[Case] = []
    for backend, r in results.items():
        load, raw, check = r["load"], r["raw"], r["check"]
        cases += [
            Case(
                f"{backend}: service ingest, {n} clients",
                f"{args.duration:g} s",
                load["throughput"],
                "readings/s",
            ),
            Case(
                f"{backend}: raw SQLAlchemy inserts, {n} threads",
                f"{args.baseline_duration:g} s",
                raw["throughput"],
                "rows/s",
            ),
            Case(f"{backend}: service / raw throughput", "", load["throughput"] / raw["throughput"], "x"),
            Case(f"{backend}: service latency p50", "", load["p50"], "ms"),
            Case(
                f"{backend}: service latency p99",
                "",
                load["p99"],
                "ms",
                f"bar ≤ {P99_BAR_MS:g} ms on SQLite" if backend == "SQLite" else "",
            ),
            Case(f"{backend}: raw insert latency p99", "", raw["p99"], "ms"),
            Case(
                f"{backend}: rows stored / distinct sent",
                "",
                check["rows"],
                "rows",
                f"of {len(set(load['sent']))} sent (+{load['resent']} re-sent duplicates); missing {check['missing']}; "
                f"audited once {check['audited_once']}; unexpected statuses {load['errors']}",
            ),
        ]
    exactly_once = all(r["exactly_once"] for r in results.values())
    sqlite_p99 = results["SQLite"]["load"]["p99"]
    verdict = (
        ("PASS" if exactly_once else "FAIL")
        + ": exactly once; "
        + ("PASS" if sqlite_p99 <= P99_BAR_MS else "FAIL")
        + f": SQLite p99 {sqlite_p99:.0f} ms (bar {P99_BAR_MS:g} ms)"
    )
    print(verdict)
    if args.no_report:
        for c in cases:
            print(c.line())
    else:
        extra = (
            f"Verdict: {verdict}. Clients are {n} processes with one keep-alive HTTP/1.1 connection each to a real "
            f"`station serve` (uvicorn, one worker) on 127.0.0.1, posting `POST /api/v1/measurements` (token check, "
            f"strict validation, insert, audit row, one transaction). Every {args.resend_every}th request re-sends "
            f"the previous reading (200, nothing stored). Baseline: raw SQLAlchemy Core inserts of the same rows "
            f"from {n} threads, same database, same run. Machine load average {load_before:.1f} before, "
            f"{load_after:.1f} after ({os.cpu_count()} CPUs shared with other jobs; clients, service and database "
            f"compete for them)."
        )
        write_section("service_load", f"Service load: {n} HTTP clients, SQLite and PostgreSQL", cases, extra)
    return 0 if exactly_once and sqlite_p99 <= P99_BAR_MS else 1


if __name__ == "__main__":
    raise SystemExit(main())
