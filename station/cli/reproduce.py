"""``station reproduce``: run the thesis's experiments on our code, its numbers beside ours.

* ``station reproduce`` — every experiment (the slow ones included: the full 1–11 lobe basis search
  takes minutes); prints one line per quantity and writes DIR/thesis.md with its PNGs in DIR/thesis/
  (DIR = ``--out``, default ``docs``).
* ``--figure ID`` — only the experiments reproducing thesis figure ID (``4.4``, ``3.3``, ``5.4``, …) or
  the experiment key; without ``--out`` nothing is written.
* ``--quick`` — leave out the slow experiments.
* ``--json`` — a list of ``{"figure", "quantity", "unit", "thesis", "ours", "tolerance", "verdict",
  "reason", …}`` on stdout.

Progress (one step per experiment) goes to stderr. Exit status 0 whatever the verdicts (a difference is
a documented result, not a failure); 2 for an unknown figure id.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from station.cli._common import add_json_flag, to_jsonable


def _run(args: argparse.Namespace) -> dict[str, Any] | None:
    from tqdm import tqdm

    from station.reproduce import registry, report

    experiments = registry.select(args.figure, include_slow=not args.quick)
    out: Path | None = args.out
    if out is None and args.figure is None:
        out = Path("docs")
    png_dir = None
    if out is not None:
        png_dir = out / "thesis"
        png_dir.mkdir(parents=True, exist_ok=True)
    bar = tqdm(total=len(experiments), desc="reproduce", unit="experiment", file=sys.stderr, leave=False)

    def progress(e: Any) -> None:
        bar.set_postfix_str(e.key)
        bar.update(0)

    try:
        results = []
        for e in experiments:
            progress(e)
            results += registry.run([e], png_dir)
            bar.update(1)
    finally:
        bar.close()
    if out is not None:
        md = out / "thesis.md"
        md.write_text(report.markdown(experiments, results, out))
        print(f"wrote {md}", file=sys.stderr)
    if args.json:
        print(json.dumps(to_jsonable(report.records(results))))
    else:
        print(report.text_table(results))
    return None


def register(subparsers: Any) -> None:
    """Add ``station reproduce``."""
    p = subparsers.add_parser(
        "reproduce",
        help="run the thesis's experiments on our code: thesis value, ours, difference, verdict",
        description=(__doc__ or "").replace("``", ""),  # plain text for people, not reStructuredText
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--figure", help="thesis figure id (4.4, 3.3, 5.4, 2.4, …) or experiment key")
    p.add_argument("--out", type=Path, default=None, help="write DIR/thesis.md and DIR/thesis/*.png")
    p.add_argument("--quick", action="store_true", help="leave out the slow experiments")
    add_json_flag(p)
    p.set_defaults(handler=_run)
