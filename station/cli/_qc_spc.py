"""``station qc spc``: control charts of a part's ΔE per geometry (and, with ``--texture-limits``, of its
sparkle and graininess within one vendor), run rules, capability and drift.

The work is :mod:`station.qc.spc_part` (charts, Western Electric and Nelson rules, Cp/Cpk against
the tolerance, drift) and :mod:`station.qc.spc_chart` (the PNG with the rule hits marked).
"""

from __future__ import annotations

import argparse
from typing import Any

from station.cli._qc_db import _session, _shown
from station.cli._qc_files import LoadTolerance, _add_db, _add_judging, _add_texture_limits, _summary_of


def _spc(args: argparse.Namespace, load_tolerance: LoadTolerance) -> dict[str, Any] | None:
    from station.cli._qc_tables import print_spc
    from station.qc.spc_part import part_spc

    args.parts = [args.part]
    with _session(args) as s:
        summary = _summary_of(args, s, load_tolerance)
    spc = part_spc(summary, args.part, args.baseline, args.subgroup)
    out: dict[str, Any] = dict(spc.to_dict())
    if args.out:
        from station.qc.spc_chart import write_spc_png

        out["written"] = str(write_spc_png(spc, args.out))
    return _shown(args, out, print_spc)


def register(sub: argparse._SubParsersAction, load_tolerance: LoadTolerance) -> None:
    """Add ``qc spc``."""
    p = sub.add_parser("spc", help="control charts, run rules, Cp/Cpk and drift of a part's ΔE")
    p.add_argument("--job", required=True)
    p.add_argument("--part", required=True)
    p.add_argument("--baseline", type=int, help="points (subgroups) that set the limits (default: all)")
    p.add_argument("--subgroup", type=int, default=1, help="1: individuals chart (default); 2…10: X̄/R chart")
    p.add_argument("--out", help="also draw the chart with its rule hits to this .png")
    _add_judging(p)
    _add_texture_limits(p)
    _add_db(p)
    p.set_defaults(handler=lambda a: _spc(a, load_tolerance))
