"""Load: 8 HTTP clients ingest readings through a real ``station serve`` on loopback, SQLite and PostgreSQL.

Each client is a process with one keep-alive connection (the standard library's ``http.client``: the
load generator shares the machine, so it is kept lean), posting synthetic multi-angle readings
(3 geometries × 31-band spectra, Lab, gloss) to ``POST /api/v1/measurements`` as fast as the service
answers, each under its own ``client_id``, and re-sending every ``--resend-every``-th one (the
idempotent path: 200, nothing stored). Latency is the wall time of one request, token check, validation,
store, hash chain and audit row included. After the run the database must hold every distinct reading
sent exactly once, each with one audit row.

The baseline is raw inserts of the same measurement rows through SQLAlchemy Core from as many threads
as there are clients, one transaction and one commit per row, on an engine with the service's
durability settings (``db.engine.make_engine``: SQLite in WAL mode with ``synchronous=FULL``;
PostgreSQL with its synchronous commit), no HTTP, no chain, no audit row, no validation. Baseline
and service run in the same run on the same database, interleaved in ``--rounds`` rounds (raw, then
service, each ``--duration`` seconds), so both see the same machine load; the 1-minute load average
is sampled at every phase boundary and reported, and so is the CPU time (user + system, from ``/proc``)
of ``station serve`` per request and of the raw inserting process per row: on a machine shared with
other work, CPU per reading is what decides throughput. Bars: service ≥ 0.5× raw throughput and p99 ≤ 150 ms.
The exit status says only whether every reading was stored exactly once.

    python -m bench.service_load [--clients 8] [--rounds 3] [--duration 10] [--no-postgres]
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
from multiprocessing.pool import Pool
from pathlib import Path
from typing import Any

import numpy as np

from bench._report import ROOT, Case, bench_parser, write_section
from bench.ingest_load import PG_ADMIN, _reading
from tests.serve_process import ServeProcess

P99_BAR_MS = 150.0
RATIO_BAR = 0.5


class Service(ServeProcess):
    """``station serve`` on a free loopback port (no simulators, no demo library); the admin token."""

    def __init__(self, data_dir: Path, database_url: str | None) -> None:
        args: tuple[str, ...] = ("--database", database_url) if database_url else ()
        # the default log level: the readiness line is logged at info (a deployment runs so too)
        args += ("--no-demo-library", "--simulators", "", "--log-level", "info")
        super().__init__(data_dir, args, cwd=ROOT)
        self.start()


def _warm(_k: int) -> int:
    """Import what a client needs before any clock starts (a pool worker keeps it for every phase)."""
    import http.client  # noqa: F401

    _reading(random.Random(0), "warm", -1)
    return os.getpid()


def _client(args: tuple[str, str, str, float, int, int, float]) -> dict[str, Any]:
    base, token, serial, duration, resend_every, seed, start_at = args
    import http.client
    from urllib.parse import urlsplit

    rng = random.Random(seed)
    time.sleep(max(0.0, start_at - time.time()))  # every client starts together
    latencies: list[float] = []
    sent: list[str] = []
    resent = errors = 0
    headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/json"}
    where = urlsplit(base)
    # the standard library's client on one keep-alive connection: the load generator shares the
    # service's CPUs, so it spends as little per request as a client can
    conn = http.client.HTTPConnection(where.hostname or "127.0.0.1", where.port, timeout=30)
    try:
        deadline = time.perf_counter() + duration
        last: bytes | None = None
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
                body = reading.model_dump_json().encode()
                sent.append(str(reading.client_id))
                expect = 201
            t0 = time.perf_counter()
            conn.request("POST", "/api/v1/measurements", body=body, headers=headers)
            answer = conn.getresponse()
            answer.read()
            latencies.append(time.perf_counter() - t0)
            errors += answer.status != expect
            last = body
    finally:
        conn.close()
    return {"sent": sent, "resent": resent, "errors": errors, "latencies": latencies}


def run_service(
    pool: Pool, base: str, token: str, clients: int, duration: float, resend_every: int, tag: str
) -> dict[str, Any]:
    """*clients* processes of *pool* (warmed by :func:`_warm`) posting for *duration* seconds; the figures.

    ``throughput`` counts distinct readings stored (re-sends excluded) per second of the phase.
    """
    start_at = time.time() + 0.5
    seed = secrets.randbits(30)
    jobs = [
        (base, token, f"{tag}-{i:02d}", duration, resend_every, seed + i, start_at) for i in range(clients)
    ]
    results = pool.map(_client, jobs)
    lat = np.concatenate([np.asarray(r["latencies"]) for r in results]) * 1000.0
    sent = [c for r in results for c in r["sent"]]
    return {
        "sent": sent,
        "requests": int(lat.size),
        "resent": sum(r["resent"] for r in results),
        "errors": sum(r["errors"] for r in results),
        "seconds": duration,
        "latencies_ms": lat,
    }


def run_raw(engine: Any, threads: int, duration: float, tag: str) -> dict[str, Any]:
    """Raw SQLAlchemy Core inserts of the same rows (the store's :func:`reading_columns`) on *engine*,
    *threads* threads, one transaction (one commit) per row, for *duration* seconds; the figures."""
    from sqlalchemy import insert, select

    from db.base import utcnow
    from db.models import Instrument, Measurement
    from station.ingest.store import reading_columns

    serial = f"{tag}-raw-{secrets.token_hex(3)}"
    _reading(random.Random(0), serial, -1)  # imports done before the clock starts
    with engine.begin() as conn:
        conn.execute(insert(Instrument).values(serial=serial, model="MA-98 simulator", kind="multiangle"))
        instrument_id = conn.execute(select(Instrument.id).where(Instrument.serial == serial)).scalar_one()
    counts = [0] * threads
    latencies: list[list[float]] = [[] for _ in range(threads)]

    def work(k: int) -> None:
        rng = random.Random(3000 + k)
        deadline = time.perf_counter() + duration
        while time.perf_counter() < deadline:
            r = _reading(rng, serial, counts[k])
            t0 = time.perf_counter()
            with engine.begin() as conn:
                conn.execute(
                    insert(Measurement).values(
                        instrument_id=instrument_id,
                        received_at=utcnow(),
                        **reading_columns(r),
                    )
                )
            latencies[k].append(time.perf_counter() - t0)
            counts[k] += 1

    workers = [threading.Thread(target=work, args=(k,)) for k in range(threads)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    lat = np.concatenate([np.asarray(x) for x in latencies]) * 1000.0
    return {"rows": sum(counts), "seconds": duration, "latencies_ms": lat}


def count_check(url: str, sent: list[str]) -> dict[str, int]:
    """Rows stored under the sent client ids, distinct ids, missing ones, and audit rows per stored row
    (the database read as the soak test reads it: ``tests.soak._accounting.read_stored``)."""
    from tests.soak._accounting import read_stored

    stored = read_stored(url)
    wanted = set(sent)
    ours = [(r.client_id, r.id) for r in stored.rows if r.client_id in wanted]
    return {
        "rows": len(ours),
        "distinct": len({c for c, _ in ours}),
        "missing": len(wanted - {c for c, _ in ours}),
        "audited_once": sum(1 for _, i in ours if stored.audits.get(i) == 1),
    }


def process_cpu_s(pid: int) -> float:
    """CPU seconds (user + system) process *pid* has used so far (Linux ``/proc``; NaN elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _pct(lat: np.ndarray, q: float) -> float:
    return float(np.percentile(lat, q)) if lat.size else float("nan")


def _backend(name: str, url: str | None, data_dir: Path, args: argparse.Namespace) -> dict[str, Any]:
    """Raw and service phases interleaved on one database (a fresh service, its own SQLite file or the
    throwaway PostgreSQL database *url*); the figures, the count check and the load averages seen."""
    from db.engine import make_engine

    db_url = url or f"sqlite:///{data_dir / 'station.sqlite3'}"
    loads = [os.getloadavg()[0]]
    service = Service(data_dir, url)  # creates and migrates the database
    engine = make_engine(db_url, pool_size=args.clients)
    raws: list[dict[str, Any]] = []
    phases: list[dict[str, Any]] = []
    ctx = mp.get_context("spawn")
    try:
        with ctx.Pool(args.clients) as pool:
            pool.map(_warm, range(args.clients))
            for k in range(args.rounds):
                loads.append(os.getloadavg()[0])
                cpu0 = process_cpu_s(os.getpid())
                raws.append(run_raw(engine, args.clients, args.duration, f"{name}{k}"))
                raws[-1]["cpu_s"] = process_cpu_s(os.getpid()) - cpu0
                loads.append(os.getloadavg()[0])
                cpu0 = process_cpu_s(service.pid)
                phases.append(
                    run_service(
                        pool,
                        service.base,
                        service.token,
                        args.clients,
                        args.duration,
                        args.resend_every,
                        f"{name}{k}",
                    )
                )
                phases[-1]["cpu_s"] = process_cpu_s(service.pid) - cpu0
                loads.append(os.getloadavg()[0])
    finally:
        service.stop()
        engine.dispose()
    sent = [c for p in phases for c in p["sent"]]
    lat = np.concatenate([p["latencies_ms"] for p in phases])
    raw_lat = np.concatenate([r["latencies_ms"] for r in raws])
    seconds = sum(p["seconds"] for p in phases)
    raw_seconds = sum(r["seconds"] for r in raws)
    load = {
        "sent": sent,
        "requests": int(lat.size),
        "resent": sum(p["resent"] for p in phases),
        "errors": sum(p["errors"] for p in phases),
        "throughput": len(sent) / seconds,
        "p50": _pct(lat, 50),
        "p99": _pct(lat, 99),
        "cpu_ms": 1000.0 * sum(p["cpu_s"] for p in phases) / max(1, int(lat.size)),
    }
    raw_rows = sum(r["rows"] for r in raws)
    raw = {
        "throughput": raw_rows / raw_seconds,
        "p99": _pct(raw_lat, 99),
        "cpu_ms": 1000.0 * sum(r["cpu_s"] for r in raws) / max(1, raw_rows),
    }
    rounds = [
        len(p["sent"]) / p["seconds"] / (r["rows"] / r["seconds"]) for p, r in zip(phases, raws, strict=True)
    ]
    check = count_check(db_url, sent)
    ok = (
        check["rows"] == check["distinct"] == check["audited_once"] == len(set(sent)) and not check["missing"]
    )
    return {
        "load": load,
        "raw": raw,
        "round_ratios": rounds,
        "check": check,
        "loadavg": loads,
        "exactly_once": ok and load["errors"] == 0,
    }


def main(argv: list[str] | None = None) -> int:
    args = _arguments(argv)
    results = _run_backends(args)
    n = args.clients
    phase = f"{args.rounds}×{args.duration:g} s"
    cases: list[Case] = []
    verdicts: list[str] = []
    for backend, r in results.items():
        backend_cases, backend_verdict = _backend_cases(backend, r, n, phase)
        cases += backend_cases
        verdicts.append(backend_verdict)
    exactly_once = all(r["exactly_once"] for r in results.values())
    verdict = f"exactly once: {'PASS' if exactly_once else 'FAIL'}; " + "; ".join(verdicts)
    print(verdict)
    if args.no_report:
        for c in cases:
            print(c.line())
    else:
        extra = (
            f"Verdict: {verdict}. Clients are {n} processes with one keep-alive HTTP/1.1 connection each (Python's `http.client`) to a real "
            f"`station serve` (uvicorn, one worker, default log level) on 127.0.0.1, posting "
            f"`POST /api/v1/measurements` (token check, strict validation, insert, hash chain, audit row; "
            f"readings posted together share one transaction and one commit, each answered once committed). "
            f"Every {args.resend_every}th request re-sends the previous reading (200, nothing stored). Baseline: "
            f"raw SQLAlchemy Core inserts of the same rows from {n} threads, one commit per row, WAL + "
            f"`synchronous=FULL` on SQLite, synchronous commit on PostgreSQL, same database. Raw and service phases "
            f"alternate ({args.rounds} rounds of {args.duration:g} s each) so both see the same load; the 1-minute "
            f"load average at the phase boundaries is in the table ({os.cpu_count()} CPUs shared with other jobs; "
            f"clients, service and database compete for them)."
        )
        write_section("service_load", f"Service load: {n} HTTP clients, SQLite and PostgreSQL", cases, extra)
    return 0 if exactly_once else 1


def _arguments(argv: list[str] | None) -> argparse.Namespace:
    """The command line, checked (clients 1–64, rounds 1–20, 0 < duration ≤ 60 s)."""
    parser = bench_parser(__doc__, "service_load")
    parser.add_argument("--clients", type=int, default=8, help="client processes and raw threads (default 8)")
    parser.add_argument("--rounds", type=int, default=3, help="raw/service rounds per backend (default 3)")
    parser.add_argument(
        "--duration", type=float, default=10.0, help="seconds of each raw and each service phase (≤ 60)"
    )
    parser.add_argument("--resend-every", type=int, default=20, help="re-send every Nth reading (0: never)")
    parser.add_argument(
        "--pg-admin", default=PG_ADMIN, help="maintenance database URL (a throwaway DB is made)"
    )
    parser.add_argument("--no-postgres", action="store_true")
    parser.add_argument("--no-report", action="store_true", help="print only; leave docs/ alone")
    args = parser.parse_args(argv)
    if not 0 < args.duration <= 60:
        parser.error("--duration: 0 < seconds ≤ 60")
    if not 1 <= args.clients <= 64 or not 1 <= args.rounds <= 20:
        parser.error("--clients: 1 to 64; --rounds: 1 to 20")
    return args


def _run_backends(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """The measured phases on SQLite and (unless ``--no-postgres``) on a throwaway PostgreSQL database."""
    results: dict[str, dict[str, Any]] = {}
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
    return results


def _backend_cases(backend: str, r: dict[str, Any], n: int, phase: str) -> tuple[list[Case], str]:
    """One backend's lines (throughput, latency, CPU, load, counts) and its one-line verdict."""
    load, raw, check = r["load"], r["raw"], r["check"]
    ratio = load["throughput"] / raw["throughput"]
    lo, hi = min(r["loadavg"]), max(r["loadavg"])
    cases = [
        Case(f"{backend}: service ingest, {n} clients", phase, load["throughput"], "readings/s"),
        Case(
            f"{backend}: raw SQLAlchemy inserts, {n} threads",
            phase,
            raw["throughput"],
            "rows/s",
            "one commit per row, interleaved with the service phases",
        ),
        Case(
            f"{backend}: service / raw throughput",
            "",
            ratio,
            "x",
            f"bar ≥ {RATIO_BAR:g}; rounds {', '.join(f'{x:.2f}' for x in r['round_ratios'])}",
        ),
        Case(f"{backend}: service latency p50", "", load["p50"], "ms"),
        Case(f"{backend}: service latency p99", "", load["p99"], "ms", f"bar ≤ {P99_BAR_MS:g} ms"),
        Case(f"{backend}: raw insert latency p99", "", raw["p99"], "ms"),
        Case(
            f"{backend}: service process CPU per request",
            "",
            load["cpu_ms"],
            "ms",
            "user + system of `station serve` during the service phases",
        ),
        Case(
            f"{backend}: raw inserts CPU per row",
            "",
            raw["cpu_ms"],
            "ms",
            "the inserting process (reading made, SQLAlchemy, driver); the database's own CPU in neither",
        ),
        Case(
            f"{backend}: load average during the run",
            "",
            hi,
            "max 1-min",
            f"min {lo:.1f}, {os.cpu_count()} CPUs",
        ),
        Case(
            f"{backend}: rows stored / distinct sent",
            "",
            check["rows"],
            "rows",
            f"of {len(set(load['sent']))} sent (+{load['resent']} re-sent duplicates); missing {check['missing']}; "
            f"audited once {check['audited_once']}; unexpected statuses {load['errors']}",
        ),
    ]
    verdict = (
        f"{backend} {'PASS' if ratio >= RATIO_BAR else 'MISS'} {ratio:.2f}× raw (bar {RATIO_BAR:g}×), "
        f"{'PASS' if load['p99'] <= P99_BAR_MS else 'MISS'} p99 {load['p99']:.0f} ms (bar {P99_BAR_MS:g} ms)"
    )
    return cases, verdict


if __name__ == "__main__":
    raise SystemExit(main())
