"""``station qc check|repeats|correlate|metamerism|jobs|search|standard|summary|report|trend``.

The handlers behind the commands of :mod:`station.cli.qc` that read measurement files or the
measurement database; the work is :mod:`station.qc`'s. Every command exits 0 whatever the verdict and
2 with one line on stderr for bad input.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.cli._common import add_json_flag
from station.cli._qc_db import _session, _shown, _time
from station.errors import InputError

if TYPE_CHECKING:
    from station.qc.tolerance import ToleranceSet

LoadTolerance = Callable[[str], "ToleranceSet"]

FORMULA_HELP = "din6175-2 | cie2000 | cie94 | cie76 (default din6175-2, or the tolerance file's)"


def _readings(path: str, role: str) -> list[Any]:
    from station.qc.readings import load_readings

    return load_readings(path)


def _one(
    readings: Sequence[Any], role: str, keep_outliers: bool = False
) -> tuple[Any, dict[str, Any] | None]:
    """A single reading, or the mean of several (with their repeat statistics).

    The mean leaves out the readings ``qc repeats`` flags as outliers (``left_out``, their 0-based
    indices in the file) unless *keep_outliers*.
    """
    from station.qc.repeats import summarise

    if len(readings) == 1:
        return readings[0], None
    summary = summarise(readings)
    out: dict[str, Any] = dict(summary.to_dict())
    out["left_out"] = [] if keep_outliers else list(out["outliers"])
    out["outliers_kept"] = keep_outliers
    return (summary.mean if keep_outliers else summary.mean_kept), out


def print_verdict(result: dict[str, Any]) -> None:
    """A QC verdict as a table for people (``qc verdict`` and ``qc check`` without ``--json``)."""
    print(f"verdict: {result['verdict']}  ({result['formula']}, {result['aggregation']} rule)")
    print(f"reason: {result['reason']}")
    print(f"{'geometry':>9} {'dL':>7} {'da':>7} {'db':>7} {'dC':>7} {'dH':>7} {'dE':>7}  verdict")
    for g in result["per_geometry"]:
        nums = " ".join(f"{g[k]:7.2f}" for k in ("dL", "da", "db", "dC", "dH", "dE"))
        why = f"  ({'; '.join(g['reasons'])})" if g["reasons"] else ""
        print(f"{g['geometry']:>9} {nums}  {g['verdict']}{why}")
    print(f"mean dE: {result['mean_de']:.2f}   max dE: {result['max_de']:.2f} at {result['worst_geometry']}")
    booth = result.get("illuminants")
    if booth:
        print(f"illuminant rows (metamerism index from D65, {booth['formula']}): {booth['verdict']}")
        for row in booth["rows"]:
            print(f"  {row['text']}")


def _check(args: argparse.Namespace, load_tolerance: LoadTolerance) -> dict[str, Any] | None:
    from station.qc.check import check_pair

    tolerance = load_tolerance(args.tolerance) if args.tolerance else None
    keep = args.keep_outliers
    std, std_rep = _one(_readings(args.standard, "standard"), "standard", keep)
    smp, smp_rep = _one(_readings(args.sample, "sample"), "sample", keep)
    verdict = check_pair(std, smp, tolerance, args.formula)
    booth = None
    if args.illuminant_limits is not None:
        from station.qc.illuminant_rows import check_illuminants, parse_illuminant_limits

        limits = parse_illuminant_limits(args.illuminant_limits)
        booth = check_illuminants(std, smp, limits, verdict.formula)
    from station.qc.illuminant_rows import PairVerdict

    result: dict[str, Any] = dict(PairVerdict(verdict, booth).to_dict())
    if args.texture_limits is not None:
        _texture(result, std, smp, args.texture_limits)
    result["standard"] = {"file": Path(args.standard).name, "sample": std.sample, "repeats": std_rep}
    result["sample"] = {"file": Path(args.sample).name, "sample": smp.sample, "repeats": smp_rep}
    if args.json:
        return result
    print_verdict(result)
    if "texture" in result:
        from station.cli._qc_tables import print_texture

        print_texture(result["texture"])
    for role, rep in (("standard", std_rep), ("sample", smp_rep)):
        if rep is not None:
            flagged = ", ".join(f"reading {i}" for i in rep["outliers"]) or "none"
            how = "kept in the mean (--keep-outliers)" if rep["outliers_kept"] else "left out of the mean"
            n = rep["n"] - len(rep["left_out"])
            print(
                f"{role}: mean of {n} of {rep['n']} readings; outliers: {flagged}"
                + (f", {how}" if rep["outliers"] else "")
            )
    return None


def _texture(result: dict[str, Any], std: Any, smp: Any, limits: str) -> None:
    """Add the texture verdict (``--texture-limits``) to *result*; the overall verdict is the worse."""
    from station.qc.texture import judge_texture, parse_texture_limits

    tex = judge_texture(std.texture, smp.texture, parse_texture_limits(limits))
    result["texture"] = tex.to_dict()
    rank = {"pass": 0, "warn": 1, "fail": 2}
    if rank[tex.verdict] > rank[result["verdict"]]:
        result["verdict"] = tex.verdict
        result["reason"] = f"{result['reason']}; texture ({tex.vendor}) {tex.verdict}"


def _panel_rows(args: argparse.Namespace) -> list[Any]:
    from station.qc.jobs import search_measurements

    with _session(args) as s:
        rows = search_measurements(s, panel_id=args.panel)
    if not rows:
        raise InputError("panel", "the id of a panel with stored measurements", args.panel)
    return rows


def _repeats(args: argparse.Namespace) -> dict[str, Any] | None:
    from station.qc.repeats import summarise

    if bool(args.files) == (args.panel is not None):
        raise InputError("files", "reading files or --panel ID (one of the two)", args.files or None)
    if args.panel is not None:
        readings = [r.reading for r in _panel_rows(args)]
    else:
        readings = [r for f in args.files for r in _readings(f, "readings")]
    out: dict[str, Any] = dict(summarise(readings).to_dict())
    if args.json:
        return out
    print(f"{out['n']} readings; outlier rule: {out['rule']}")
    print(f"{'geometry':>9} {'L*':>8} {'a*':>8} {'b*':>8} {'sd L*':>7} {'sd a*':>7} {'sd b*':>7}")
    for g in out["per_geometry"]:
        sd = g["sd"] or [float("nan")] * 3
        print(
            f"{g['geometry']:>9} "
            + " ".join(f"{v:8.2f}" for v in g["mean"])
            + " "
            + " ".join(f"{v:7.2f}" for v in sd)
        )
    for r in out["readings"]:
        z = "—" if r["robust_z"] is None else f"{r['robust_z']:.2f}"
        print(
            f"reading {r['index']}: ΔE to centre {r['de_to_centre']:.2f}, z {z}{'  OUTLIER' if r['outlier'] else ''}"
        )
    return None


def _correlate(args: argparse.Namespace) -> dict[str, Any]:
    from station.qc.repeats import correlate

    if args.panel is None:
        if not (args.a and args.b):
            raise InputError("a", "--a FILE and --b FILE (or --panel ID)", args.a)
        return correlate(_readings(args.a, "a"), _readings(args.b, "b")).to_dict()
    rows = _panel_rows(args)
    names = list(dict.fromkeys(r.instrument for r in rows))
    picked: list[str | None] = []
    for flag in ("a", "b"):
        want = getattr(args, flag)
        if want is None:
            picked.append(names[len(picked)] if len(names) > len(picked) else None)
        else:
            match = [n for n in names if want in n.split()]
            picked.append(match[0] if match else None)
            if not match:
                raise InputError(flag, f"an instrument of panel {args.panel} ({', '.join(names)})", want)
    if picked[0] is None or picked[1] is None or picked[0] == picked[1]:
        raise InputError("panel", "a panel measured by two instruments (or --a/--b naming them)", names)
    a = [r.reading for r in rows if r.instrument == picked[0]]
    b = [r.reading for r in rows if r.instrument == picked[1]]
    return correlate(a, b).to_dict()


def _metamerism(args: argparse.Namespace) -> dict[str, Any]:
    from station.qc.metamerism import metamerism

    std, _ = _one(_readings(args.standard, "standard"), "standard")
    smp, _ = _one(_spectral(args.sample), "sample")
    return metamerism(std, smp, args.formula or "cie2000").to_dict()


def _spectral(path: str) -> list[Any]:
    readings = _readings(path, "sample")
    if len(readings) > 1:
        from station.qc.errors import QcInputError

        raise QcInputError(
            Path(path).name, "one reading with spectra (spectra are not averaged)", len(readings)
        )
    return readings


# ---------------------------------------------------------------------------------------- database


def _jobs(args: argparse.Namespace) -> dict[str, Any] | None:
    from station.cli._qc_tables import print_jobs
    from station.qc.jobs import list_jobs

    with _session(args) as s:
        out = {"jobs": [j.to_dict() for j in list_jobs(s, args.contains)]}
    return _shown(args, out, print_jobs)


def _search(args: argparse.Namespace) -> dict[str, Any] | None:
    from station.cli._qc_tables import print_search

    return _shown(args, _found(args), print_search)


def _found(args: argparse.Namespace) -> dict[str, Any]:
    from station.qc.jobs import search_measurements

    with _session(args) as s:
        rows = search_measurements(
            s,
            job=args.job,
            part=args.part,
            instrument=args.instrument,
            since=_time(args.since, "since"),
            until=_time(args.until, "until"),
            limit=args.limit,
        )
        return {"measurements": [r.to_dict() for r in rows]}


def _standard_set(args: argparse.Namespace) -> dict[str, Any]:
    from station.qc.jobs import set_standard

    with _session(args) as s:
        std = set_standard(
            s,
            args.job,
            args.part,
            measurement_id=args.measurement,
            design_id=args.design,
            notes=args.notes,
            replace=args.replace,
        )
        s.commit()
        return {
            "job": std.job,
            "part": std.part,
            "measurement_id": std.measurement_id,
            "design_id": std.design_id,
            "created_at": std.created_at.isoformat(),
        }


def _standard_show(args: argparse.Namespace) -> dict[str, Any]:
    from station.qc.jobs import require_standard, standard_reading

    with _session(args) as s:
        std = require_standard(s, args.job, args.part)
        angles = None
        if std.design_id is not None:
            from station.model.domain import ANGLES_6

            angles = ANGLES_6
        r = standard_reading(s, std, angles)
        return {
            "job": std.job,
            "part": std.part,
            "measurement_id": std.measurement_id,
            "design_id": std.design_id,
            "created_at": std.created_at.isoformat(),
            "geometries": list(r.geometries),
            "lab": [list(x) for x in r.lab],
        }


def _summary_of(args: argparse.Namespace, session: Any, load_tolerance: LoadTolerance) -> Any:
    from station.qc.jobs import job_summary

    tolerance = load_tolerance(args.tolerance) if args.tolerance else None
    parts = getattr(args, "parts", None) or None
    limits = None
    if getattr(args, "illuminant_limits", None) is not None:
        from station.qc.illuminant_rows import parse_illuminant_limits

        limits = parse_illuminant_limits(args.illuminant_limits)
    return job_summary(
        session,
        args.job,
        tolerance,
        args.formula,
        parts,
        args.average_panels,
        illuminant_limits=limits,
        keep_outliers=args.keep_outliers,
        texture_limits=_texture_limits(args),
    )


def _texture_limits(args: argparse.Namespace) -> Any:
    text = getattr(args, "texture_limits", None)
    if text is None:
        return None
    from station.qc.texture import parse_texture_limits

    return parse_texture_limits(text)


def _summary(args: argparse.Namespace, load_tolerance: LoadTolerance) -> dict[str, Any] | None:
    from station.cli._qc_tables import print_summary

    with _session(args) as s:
        out = _summary_of(args, s, load_tolerance).to_dict()
    return _shown(args, out, print_summary)


def _progress(enabled: bool) -> Any:
    """A ``progress(done, total, what)`` callback drawing ``report [####    ] 3/7 pages`` on stderr."""
    if not enabled:
        return None

    def step(done: int, total: int, what: str) -> None:
        filled = round(20 * done / max(total, 1))
        end = "\n" if done >= total else ""
        sys.stderr.write(f"\rreport [{'#' * filled}{' ' * (20 - filled)}] {done}/{total} pages{end}")
        sys.stderr.flush()

    return step


def _report(args: argparse.Namespace, load_tolerance: LoadTolerance) -> dict[str, Any]:
    from station.qc.report import write_csv, write_pdf

    out = Path(args.out)
    suffix = out.suffix.lower()
    if suffix not in (".pdf", ".csv"):
        raise InputError("out", "a file name ending in .pdf or .csv", args.out)
    if args.csv and suffix == ".csv":
        raise InputError("csv", "--csv only beside a PDF --out", args.csv)
    for p in (out, Path(args.csv) if args.csv else None):
        if p is not None and not p.parent.is_dir():
            raise InputError("out", "a file in an existing folder", str(p))
    with _session(args) as s:
        summary = _summary_of(args, s, load_tolerance)
    written: list[str] = []
    if suffix == ".pdf":
        show = args.progress or (sys.stderr.isatty() and not args.json)
        write_pdf(summary, out, progress=_progress(show))
        written.append(str(out))
    else:
        write_csv(summary, out)
        written.append(str(out))
    if args.csv:
        write_csv(summary, args.csv)
        written.append(str(args.csv))
    return {
        "job": summary.job,
        "formula": summary.formula,
        "counts": summary.counts(),
        "parts": [p.part for p in summary.parts],
        "written": written,
    }


def _trend(args: argparse.Namespace, load_tolerance: LoadTolerance) -> dict[str, Any]:
    from station.qc.report import write_trend_png
    from station.qc.spc import control_limits

    out = Path(args.out)
    if out.suffix.lower() != ".png" or not out.parent.is_dir():
        raise InputError("out", "a .png file in an existing folder", args.out)
    args.parts = [args.part]
    with _session(args) as s:
        summary = _summary_of(args, s, load_tolerance)
    write_trend_png(summary, args.part, out)
    part = summary.parts[0]
    limits: dict[str, Any] = {}
    names: list[str] = []
    for smp in part.samples:
        for g in smp.verdict.per_geometry:
            if g.geometry not in names:
                names.append(g.geometry)
    for n in names:
        values = [g.de for smp in part.samples for g in smp.verdict.per_geometry if g.geometry == n]
        limits[n] = control_limits(values).to_dict() if len(values) >= 2 else None
    return {
        "job": summary.job,
        "part": args.part,
        "samples": len(part.samples),
        "limits": limits,
        "written": str(out),
    }


def _add_db(p: argparse.ArgumentParser) -> None:
    p.add_argument("--db", help="database URL (default: the station serve database, $CACAD_DATABASE_URL)")
    add_json_flag(p)


def _add_judging(p: argparse.ArgumentParser) -> None:
    p.add_argument("--tolerance", help="tolerance set JSON file (station qc tolerance --json)")
    p.add_argument("--formula", help=FORMULA_HELP)
    p.add_argument(
        "--average-panels",
        action="store_true",
        help="average the repeat readings of each panel (and of the standard) and judge the panel once",
    )
    p.add_argument(
        "--keep-outliers",
        action="store_true",
        help="average in the repeat readings flagged as outliers (default: leave them out and name them)",
    )


def _add_texture_limits(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--texture-limits",
        metavar="ds=X,dg=Y",
        help="judge the vendor texture values too: |ΔS| of every sparkle quantity and |ΔG| of graininess, "
        "sample minus standard, within one vendor (values of two vendors are refused)",
    )


def _add_illuminant_limits(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--illuminant-limits",
        metavar="ILL=LIMIT,…",
        help="add illuminant rows: the metamerism index from D65 per geometry judged against a limit per "
        'test illuminant, in the formula\'s ΔE units, e.g. "A=1.0,F11=1.5" (spectra needed)',
    )


def register(sub: argparse._SubParsersAction, load_tolerance: LoadTolerance) -> None:
    """Add the file and database commands under ``station qc``."""
    _register_files(sub, load_tolerance)
    _register_db(sub)
    _register_judged(sub, load_tolerance)


def _register_files(sub: argparse._SubParsersAction, load_tolerance: LoadTolerance) -> None:
    """``qc check|repeats|correlate|metamerism``: readings from files (or one stored panel)."""
    p = sub.add_parser("check", help="verdict of a sample file against a standard file")
    p.add_argument("--standard", required=True, help="standard: station measure/import --json output")
    p.add_argument("--sample", required=True, help="sample: station measure/import --json output")
    _add_judging(p)
    _add_illuminant_limits(p)
    _add_texture_limits(p)
    add_json_flag(p)
    p.set_defaults(handler=lambda a: _check(a, load_tolerance))

    p = sub.add_parser("repeats", help="mean, sd per geometry and outliers of repeat readings")
    p.add_argument("files", nargs="*", help="files of readings of one panel")
    p.add_argument("--panel", type=int, help="instead of files: the stored measurements of this panel")
    _add_db(p)
    p.set_defaults(handler=_repeats)

    p = sub.add_parser("correlate", help="bias of instrument B against A on a shared panel")
    p.add_argument("--a", help="readings of instrument A (with --panel: its serial or model)")
    p.add_argument("--b", help="readings of instrument B (with --panel: its serial or model)")
    p.add_argument("--panel", type=int, help="the stored measurements of this panel, by instrument")
    _add_db(p)
    p.set_defaults(handler=_correlate)

    p = sub.add_parser("metamerism", help="metamerism index D65 → A, F11 per geometry (spectra needed)")
    p.add_argument("--standard", required=True, help="standard reading with spectra")
    p.add_argument("--sample", required=True, help="sample reading with spectra")
    p.add_argument("--formula", help="cie2000 (default) | cie94 | cie76 | din6175-2")
    add_json_flag(p)
    p.set_defaults(handler=_metamerism)


def _register_db(sub: argparse._SubParsersAction) -> None:
    """``qc jobs|search|standard``: the measurement database."""
    from station.cli._qc_tables import print_standard

    p = sub.add_parser("jobs", help="jobs in the database with their parts and counts")
    p.add_argument("--contains", help="only jobs whose name contains this (case-insensitive)")
    _add_db(p)
    p.set_defaults(handler=_jobs)

    p = sub.add_parser("search", help="measurements by job, part, instrument and time")
    p.add_argument("--job")
    p.add_argument("--part")
    p.add_argument("--instrument", help="instrument serial or model")
    p.add_argument("--since", help="from this time (inclusive), ISO 8601; a date means 00:00 UTC")
    p.add_argument("--until", help="before this time (exclusive), ISO 8601")
    p.add_argument("--limit", type=int, default=1000, help="most rows (default 1000)")
    _add_db(p)
    p.set_defaults(handler=_search)

    top = sub.add_parser("standard", help="the standard of a job and part")
    ssub = top.add_subparsers(dest="standard_command", required=True, metavar="ACTION")
    p = ssub.add_parser("set", help="make a measurement or a design the standard")
    p.add_argument("--job", required=True)
    p.add_argument("--part", required=True)
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--measurement", type=int, help="reference measurement id (see qc search)")
    which.add_argument("--design", type=int, help="design id")
    p.add_argument("--notes", default="")
    p.add_argument("--replace", action="store_true", help="replace an existing standard")
    _add_db(p)
    p.set_defaults(handler=lambda a: _shown(a, _standard_set(a), print_standard))
    p = ssub.add_parser("show", help="print the standard (a design at the 6-angle set)")
    p.add_argument("--job", required=True)
    p.add_argument("--part", required=True)
    _add_db(p)
    p.set_defaults(handler=lambda a: _shown(a, _standard_show(a), print_standard))


def _register_judged(sub: argparse._SubParsersAction, load_tolerance: LoadTolerance) -> None:
    """``qc summary|report|trend``: a job's samples judged against their standards."""
    from station.cli._qc_tables import print_written

    p = sub.add_parser("summary", help="every sample's verdict against its part's standard")
    p.add_argument("--job", required=True)
    p.add_argument("--part", dest="parts", action="append", help="only this part (repeatable)")
    _add_judging(p)
    _add_illuminant_limits(p)
    _add_texture_limits(p)
    _add_db(p)
    p.set_defaults(handler=lambda a: _summary(a, load_tolerance))

    p = sub.add_parser("report", help="QC report of a job: PDF (and CSV)")
    p.add_argument("--job", required=True)
    p.add_argument("--out", required=True, help="report.pdf (or out.csv for the CSV alone)")
    p.add_argument("--csv", help="also write the CSV here")
    p.add_argument("--part", dest="parts", action="append", help="only this part (repeatable)")
    p.add_argument("--progress", action="store_true", help="draw a progress bar on stderr")
    _add_judging(p)
    _add_illuminant_limits(p)
    _add_texture_limits(p)
    _add_db(p)
    p.set_defaults(handler=lambda a: _shown(a, _report(a, load_tolerance), print_written))

    p = sub.add_parser("trend", help="SPC chart of ΔE per geometry over time of one part (PNG)")
    p.add_argument("--job", required=True)
    p.add_argument("--part", required=True)
    p.add_argument("--out", required=True, help="trend.png")
    _add_judging(p)
    _add_db(p)
    p.set_defaults(handler=lambda a: _shown(a, _trend(a, load_tolerance), print_written))
