"""Command-line start-up: ``station --help``, ``station --version`` and every ``station X --help``
against a bare ``python -c "import numpy"`` measured in the same run.

Each command runs as its own process (the console script's interpreter, from a temporary folder),
interleaved with the baseline, *--n* times (default 7); the figure is the median wall time and the ratio
is median over the baseline's median. Bar: ≤ 3× a bare ``import numpy`` (issue 28). Process time is
what a person waits for, so the figure includes the interpreter's own start.

Run: ``.venv/bin/python -m bench.cli_start [--n 7]``.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench._report import Case, bench_parser, write_section

ROOT = Path(__file__).resolve().parents[1]
BAR = 3.0


def _wall(argv: list[str], cwd: str) -> float:
    """Seconds *argv* took from start to exit (output discarded; a failure stops the benchmark)."""
    start = time.perf_counter()
    subprocess.run(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - start


def main() -> None:
    """Measure and rewrite the ``cli-start`` section of docs/benchmarks.md."""
    parser = bench_parser(__doc__, "cli_start")
    parser.add_argument("--n", type=int, default=7, help="runs of each command (default 7)")
    args = parser.parse_args()
    from station.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")  # argparse has no public API
    assert sub.choices is not None
    station = [sys.executable, "-m", "station.cli"]
    commands = {"station --help": ["--help"], "station --version": ["--version"]}
    commands |= {f"station {name} --help": [name, "--help"] for name in sorted(sub.choices)}
    baseline = [sys.executable, "-c", "import numpy"]
    times: dict[str, list[float]] = {name: [] for name in commands}
    base: list[float] = []
    with tempfile.TemporaryDirectory() as cwd:
        env_cwd = os.path.realpath(cwd)
        for _ in range(args.n):
            for name, argv in commands.items():
                base.append(_wall(baseline, env_cwd))
                times[name].append(_wall([*station, *argv], env_cwd))
    base_median = statistics.median(base)
    cases = [Case("python -c 'import numpy' (baseline)", f"{len(base)} runs", base_median * 1e3, "ms")]
    worst = 0.0
    for name, values in times.items():
        ratio = statistics.median(values) / base_median
        worst = max(worst, ratio)
        cases.append(
            Case(name, f"{len(values)} runs", statistics.median(values) * 1e3, "ms", f"{ratio:.2f}× numpy")
        )
    verdict = "PASS" if worst <= BAR else "MISS"
    write_section(
        "cli-start",
        "Command line start-up against a bare import numpy",
        cases,
        f"Verdict: {verdict}, the slowest is {worst:.2f}× a bare `import numpy` (bar ≤ {BAR:g}×). Each "
        "command is a fresh process run from a temporary folder, interleaved with the baseline; "
        "`tests/cli/test_startup_imports.py` fails when any of them imports a package beyond the standard "
        "library and NumPy.",
    )


if __name__ == "__main__":
    main()
