"""``station qc …``: colour QC of a sample against its standard (station.qc.tolerance).

* ``verdict`` — pass / warn / fail per geometry and overall, with the reasons, from Lab lists:
  ``station qc verdict --standard "L,a,b;…" --sample "L,a,b;…" --angles 15,45,110 --formula din6175
  [--limit 1.0] [--warn 0.8] [--aggregate max|mean] [--mean-limit X] [--lc 2:1]
  [--dl X --da X --db X | --dl X --dc X --dh X] [--tolerance FILE] [--json]``
* ``tolerance`` — print a tolerance set built from the same options (``--json`` gives the file
  ``--tolerance`` reads).

The verdict is the result, not an error: the command exits 0 for pass, warn and fail alike and 2 for
bad input (one line naming the field and the accepted range). Angle lists that start with a minus
sign need the ``=`` form: ``--angles=-15,15,45``.

Readings from files (``station measure --json`` or ``station import --json`` output; station.qc):

* ``check --standard FILE --sample FILE [--tolerance FILE] [--formula din6175-2|cie2000|cie94|cie76]``
  — the verdict of the sample against the standard (several readings in a file are averaged first,
  with the repeat statistics reported);
* ``repeats FILE…`` — mean, per-geometry sd and outliers of repeat readings of one panel;
* ``correlate --a FILE --b FILE`` — bias of instrument B against A on a shared panel;
* ``metamerism --standard FILE --sample FILE [--formula]`` — metamerism index D65 → A, F11.

Jobs in the measurement database (``--db URL``, default: the ``station serve`` database):

* ``jobs``, ``search [--job J] [--part P] [--instrument SERIAL|MODEL] [--since T] [--until T]``;
* ``standard set --job J --part P --measurement ID|--design ID [--replace]``, ``standard show``;
* ``summary --job J`` — every sample's verdict against its part's standard;
* ``report --job J --out report.pdf [--csv out.csv]`` (``--out x.csv`` writes the CSV alone) and
  ``trend --job J --part P --out trend.png`` (the SPC chart of one part).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.cli._common import add_json_flag, parse_floats, parse_lab_list
from station.errors import InputError
from station.model.domain import (
    ANGLES_3,
    DELTA_E_COMPUTED,
    QC_AGGREGATION,
    QC_DE_LIMIT,
    QC_FORMULA,
    QC_WARN_FRACTION,
    TOLERANCE_AGGREGATIONS,
    format_angle,
)

if TYPE_CHECKING:
    from station.qc.tolerance import ToleranceSet

_COMPONENT_FLAGS = ("dl", "da", "db", "dc", "dh")
_SET_FLAGS = ("formula", "limit", "warn", "aggregate", "mean_limit", "lc", *_COMPONENT_FLAGS)


def _lc(text: str) -> tuple[float, float]:
    parts = text.replace(",", ":").split(":")
    try:
        values = [float(p) for p in parts]
    except ValueError as exc:
        raise InputError("lc", 'k_L:k_C as two numbers, e.g. "2:1"', text) from exc
    if len(values) != 2:
        raise InputError("lc", 'k_L:k_C as two numbers, e.g. "2:1"', text)
    return values[0], values[1]


def _load_tolerance(name: str) -> ToleranceSet:
    """A tolerance set from its JSON file (``station qc tolerance --json``)."""
    from station.qc.tolerance import ToleranceSet

    path = Path(name)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(
            "tolerance", "a readable JSON tolerance file (station qc tolerance --json)", str(path)
        ) from exc
    return ToleranceSet.from_dict(data)


def _tolerance(args: argparse.Namespace, angles: list[float]) -> ToleranceSet:
    from station.qc.tolerance import ToleranceSet

    if args.tolerance:
        given = [f for f in _SET_FLAGS if getattr(args, f) is not None]
        if given:
            raise InputError(
                given[0].replace("_", "-"), "either --tolerance FILE or limit options, not both", "both"
            )
        return _load_tolerance(args.tolerance)
    components = {c: getattr(args, c) for c in _COMPONENT_FLAGS if getattr(args, c) is not None}
    kwargs: dict[str, Any] = {
        "formula": args.formula or QC_FORMULA,
        "aggregation": args.aggregate or QC_AGGREGATION,
        "warn_fraction": QC_WARN_FRACTION if args.warn is None else args.warn,
        "mean_limit": args.mean_limit if args.mean_limit is not None else (args.limit or QC_DE_LIMIT),
    }
    if args.lc:
        kwargs["l_c"] = _lc(args.lc)
    return ToleranceSet.uniform(
        angles, QC_DE_LIMIT if args.limit is None else args.limit, components, **kwargs
    )


def _angles(args: argparse.Namespace) -> list[float]:
    return parse_floats(args.angles, "angles")


def _verdict(args: argparse.Namespace) -> dict[str, Any] | None:
    from station.qc.tolerance import judge

    std = parse_lab_list(args.standard, "standard")
    smp = parse_lab_list(args.sample, "sample")
    angles = _angles(args)
    if len(std) != len(angles):
        raise InputError("standard", f"{len(angles)} triples (one per angle in --angles)", len(std))
    if len(smp) != len(std):
        raise InputError("sample", f"{len(std)} triples (as many as --standard)", len(smp))
    result: dict[str, Any] = dict(judge(std, smp, angles, _tolerance(args, angles)).to_dict())
    if args.json:
        return result
    from station.cli._qc_files import print_verdict

    print_verdict(result)
    return None


def _show_tolerance(args: argparse.Namespace) -> dict[str, Any]:
    return _tolerance(args, _angles(args)).to_dict()


def _add_set_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--angles",
        default=",".join(format_angle(a) for a in ANGLES_3),
        help="aspecular angles of the triples, degrees (default 15,45,110; --angles=-15,… for a minus)",
    )
    p.add_argument("--formula", help=f"{' | '.join(DELTA_E_COMPUTED)} (default {QC_FORMULA})")
    p.add_argument("--limit", type=float, help=f"ΔE limit at every geometry (default {QC_DE_LIMIT:g})")
    p.add_argument(
        "--warn", type=float, help=f"warn band as a fraction of each limit (default {QC_WARN_FRACTION:g})"
    )
    p.add_argument(
        "--aggregate",
        choices=TOLERANCE_AGGREGATIONS,
        help=f"rule over the geometries (default {QC_AGGREGATION})",
    )
    p.add_argument(
        "--mean-limit", type=float, help="limit on the mean ΔE under --aggregate mean (default --limit)"
    )
    p.add_argument("--lc", help='CIEDE2000 k_L:k_C, e.g. "2:1" (default 1:1)')
    for c, sym in zip(_COMPONENT_FLAGS, ("ΔL*", "Δa*", "Δb*", "ΔC*", "ΔH*"), strict=True):
        p.add_argument(f"--{c}", type=float, help=f"limit on |{sym}| at every geometry")
    p.add_argument("--tolerance", help="tolerance set JSON file (instead of the limit options)")
    add_json_flag(p)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station qc …``."""
    top = subparsers.add_parser("qc", help="colour QC: verdicts of a sample against its standard")
    sub = top.add_subparsers(dest="qc_command", required=True, metavar="SUBCOMMAND")

    p = sub.add_parser("verdict", help="pass / warn / fail per geometry and overall")
    p.add_argument("--standard", required=True, help='standard Lab per angle: "L,a,b;L,a,b;…"')
    p.add_argument("--sample", required=True, help='sample Lab per angle: "L,a,b;L,a,b;…"')
    _add_set_args(p)
    p.set_defaults(handler=_verdict)

    p = sub.add_parser("tolerance", help="print the tolerance set the options describe")
    _add_set_args(p)
    p.set_defaults(handler=_show_tolerance)

    from station.cli import _qc_files

    _qc_files.register(sub, _load_tolerance)
    from station.cli import _qc_spc

    _qc_spc.register(sub, _load_tolerance)
