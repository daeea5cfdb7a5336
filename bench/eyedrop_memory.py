"""Peak memory of concurrent eyedrops against a real ``station serve``.

The upload is the case that cost the most memory before the bounded decoder: a 16 KB PNG of
2000 × 2000 pixels (two flat colours, so it compresses ~750:1). The benchmark starts ``station serve``
twice on loopback, each time on a fresh data folder:

1. **bounded** — the defaults (``CACAD_IMAGE_DECODE_CONCURRENCY`` = 2);
2. **baseline, same run** — the same service with the bound lifted to 16, so all 16 uploads are
   decoded at once (the service's behaviour before the bound, with today's 8-bit decoder).

For each it reads the server process's resident set from ``/proc/<pid>/status``: ``VmRSS`` when idle
(after one small warm-up eyedrop, so imports are not counted), then ``VmHWM`` (peak RSS, reset through
``/proc/<pid>/clear_refs`` before each phase) after one eyedrop and after 16 concurrent eyedrops. The
figure is the peak above idle; the bar is ≤ 300 MiB for 16 concurrent eyedrops on the defaults.

``python -m bench.eyedrop_memory`` (``--no-report`` to skip rewriting docs/benchmarks.md).
"""

from __future__ import annotations

import io
import os
import statistics
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import httpx
import numpy as np
from PIL import Image

from bench._report import ROOT, Case, bench_parser, write_section
from tests.serve_process import serving

MIB = 1024 * 1024
BAR_MIB = 300.0
CLIENTS = 16
SIDE = 2000
POINTS = {"face_x": 10, "face_y": 10, "flop_x": 1500, "flop_y": 10, "gloss_x": 1000, "gloss_y": 500}


def board_png(side: int = SIDE) -> bytes:
    """Two flat colours, *side* × *side* pixels, as an optimised PNG (16 KB at 2000 px)."""
    a = np.zeros((side, side, 3), np.uint8)
    a[:, : side // 2] = (200, 180, 40)
    a[:, side // 2 :] = (40, 30, 10)
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def _status_kib(pid: int, field: str) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1])
    raise RuntimeError(f"{field} missing from /proc/{pid}/status")


def _reset_peak(pid: int) -> bool:
    """Reset VmHWM to the current RSS (``echo 5 > clear_refs``); False where the kernel refuses."""
    try:
        Path(f"/proc/{pid}/clear_refs").write_text("5")
    except OSError:
        return False
    return True


@contextmanager
def serve(data_dir: Path, concurrency: int, root: Path = ROOT) -> Iterator[tuple[str, str, int]]:
    """A real ``station serve`` of the checkout *root* on a free loopback port: (URL, admin token, pid)."""
    env = dict(os.environ, CACAD_IMAGE_DECODE_CONCURRENCY=str(concurrency), PYTHONPATH=str(root))
    with serving(data_dir, "--no-demo-library", "--simulators", "", env=env, cwd=root) as svc:
        if not svc.token:
            raise RuntimeError("no bootstrap token printed or written:\n" + svc.tail())
        yield svc.base, svc.token, svc.pid


def measure(concurrency: int, png: bytes, root: Path = ROOT) -> dict[str, float]:
    """Idle RSS, peak above idle for 1 and for :data:`CLIENTS` concurrent eyedrops (MiB), latencies (s)."""
    with (
        tempfile.TemporaryDirectory(prefix="cacad-bench-") as tmp,
        serve(Path(tmp), concurrency, root) as (
            base,
            token,
            pid,
        ),
    ):
        headers = {"Authorization": f"Bearer {token}", "Content-Type": "image/png"}
        url = f"{base}/api/v1/styling/eyedrop"
        small = board_png(32)
        small_points = {"face_x": 2, "face_y": 2, "flop_x": 30, "flop_y": 2, "gloss_x": 16, "gloss_y": 16}
        with httpx.Client(timeout=120) as client:
            r = client.post(url, params=small_points, content=small, headers=headers)
            r.raise_for_status()
        time.sleep(0.5)
        idle = _status_kib(pid, "VmRSS") / 1024
        resettable = _reset_peak(pid)

        def one(_i: int) -> float:
            t0 = time.perf_counter()
            with httpx.Client(timeout=120) as c:
                resp = c.post(url, params=POINTS, content=png, headers=headers)
            resp.raise_for_status()
            return time.perf_counter() - t0

        one(0)
        single = _status_kib(pid, "VmHWM") / 1024 - idle
        if resettable:
            _reset_peak(pid)
        with ThreadPoolExecutor(CLIENTS) as pool:
            latencies = sorted(pool.map(one, range(CLIENTS)))
        peak = _status_kib(pid, "VmHWM") / 1024 - idle
        return {
            "idle_mib": idle,
            "single_mib": single,
            "peak_mib": peak,
            "p50_s": statistics.median(latencies),
            "max_s": latencies[-1],
            "resettable": float(resettable),
        }


def main(argv: list[str] | None = None) -> int:
    """Run both services, print the cases, rewrite the benchmark's section; exit 1 over the bar."""
    parser = bench_parser(__doc__, "eyedrop_memory")
    parser.add_argument("--no-report", action="store_true", help="do not rewrite docs/benchmarks.md")
    parser.add_argument(
        "--compare-tree",
        type=Path,
        help="also measure the service of another checkout (e.g. a git worktree of the previous release)",
    )
    args = parser.parse_args(argv)
    png = board_png()
    bounded = measure(2, png)
    baseline = measure(CLIENTS, png)
    size = f"{SIDE}x{SIDE}, {len(png) // 1024} KB"
    cases = [
        Case("idle RSS (bounded service)", "—", bounded["idle_mib"], "MiB"),
        Case("1 eyedrop, peak above idle", size, bounded["single_mib"], "MiB", "bounded"),
        Case(
            f"{CLIENTS} concurrent eyedrops, peak above idle",
            size,
            bounded["peak_mib"],
            "MiB",
            f"bounded (2 decodes at once); bar ≤ {BAR_MIB:.0f} MiB",
        ),
        Case(
            f"{CLIENTS} concurrent eyedrops, peak above idle",
            size,
            baseline["peak_mib"],
            "MiB",
            f"baseline: bound lifted to {CLIENTS}",
        ),
        Case("peak ratio bounded / baseline", "—", bounded["peak_mib"] / baseline["peak_mib"], "×"),
        Case(f"{CLIENTS} concurrent eyedrops, p50 latency", size, bounded["p50_s"] * 1000, "ms", "bounded"),
        Case(f"{CLIENTS} concurrent eyedrops, slowest", size, bounded["max_s"] * 1000, "ms", "bounded"),
        Case(f"{CLIENTS} concurrent eyedrops, p50 latency", size, baseline["p50_s"] * 1000, "ms", "baseline"),
    ]
    if args.compare_tree:
        other = measure(CLIENTS, png, args.compare_tree.resolve())
        cases += [
            Case("1 eyedrop, peak above idle", size, other["single_mib"], "MiB", "compared checkout"),
            Case(
                f"{CLIENTS} concurrent eyedrops, peak above idle",
                size,
                other["peak_mib"],
                "MiB",
                "compared checkout",
            ),
            Case(
                f"{CLIENTS} concurrent eyedrops, p50 latency", size, other["p50_s"] * 1000, "ms", "compared"
            ),
        ]
    extra = (
        "Peak RSS (`VmHWM` of the `station serve` process, reset through `clear_refs` before each phase) "
        "minus the idle `VmRSS` after a warm-up request. Uploads are decoded 8-bit, the eyedroppers read "
        "only their windows, and at most `CACAD_IMAGE_DECODE_CONCURRENCY` (default 2) are decoded at "
        "once. The previous release (float64 decode, full-image eyedropper masks, no bound) is measured "
        "with `--compare-tree` on a checkout of it (rows marked *compared checkout*)."
    )
    if not (bounded["resettable"] and baseline["resettable"]):
        extra += " (This kernel refused `clear_refs`: each peak includes the earlier phases.)"
    if not args.no_report:
        write_section(
            "eyedrop_memory", "Eyedrop memory: 16 concurrent uploads to station serve", cases, extra
        )
    else:
        for case in cases:
            print(case.line())
    return 0 if bounded["peak_mib"] <= BAR_MIB else 1


if __name__ == "__main__":
    raise SystemExit(main())
