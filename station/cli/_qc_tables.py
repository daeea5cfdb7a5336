"""Terminal tables of the database ``station qc`` commands (``jobs``, ``search``, ``standard``, ``summary``,
``report``, ``trend``, ``spc``); ``--json`` prints the handler's dict unchanged instead.

Each printer takes that dict (JSON types) and prints aligned columns with
:func:`station.cli._text.format_table`; Lab and ΔE values to 2 decimals, times to the minute (UTC).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping, Sequence
from typing import Any

from station.cli._text import format_table

__all__ = [
    "print_jobs",
    "print_search",
    "print_spc",
    "print_standard",
    "print_summary",
    "print_texture",
    "print_written",
]


def _when(text: str | None) -> str:
    if not text:
        return "—"
    t = dt.datetime.fromisoformat(text)
    return t.astimezone(dt.UTC).strftime("%Y-%m-%d %H:%M")


def _ids(ids: Sequence[int]) -> str:
    return ", ".join(str(i) for i in ids) or "—"


def print_jobs(out: Mapping[str, Any]) -> None:
    """``qc jobs``: one row a job with its parts, panel and measurement counts and time span."""
    jobs = out["jobs"]
    if not jobs:
        print("no jobs in this database")
        return
    rows = []
    for j in jobs:
        rows.append(
            [
                j["job"],
                ", ".join(j["parts"]),
                str(j["panels"]),
                str(j["measurements"]),
                _when(j["first_measured"]),
                _when(j["last_measured"]),
            ]
        )
    print(format_table(rows, ["job", "parts", "panels", "measurements", "first (UTC)", "last (UTC)"]))


def print_search(out: Mapping[str, Any]) -> None:
    """``qc search``: one row a measurement (id, panel, job/part, instrument, operator, time, geometries)."""
    rows = [
        [
            str(m["measurement_id"]),
            "—" if m["panel_id"] is None else str(m["panel_id"]),
            f"{m['job'] or '—'}/{m['part'] or '—'}",
            m["instrument"],
            m["operator"] or "—",
            _when(m["measured_at"]),
            " ".join(m["geometries"]),
        ]
        for m in out["measurements"]
    ]
    if not rows:
        print("no measurements match")
        return
    print(
        format_table(
            rows, ["id", "panel", "job/part", "instrument", "operator", "measured (UTC)", "geometries"]
        )
    )
    print(f"{len(rows)} measurement{'s' if len(rows) != 1 else ''}")


def print_standard(out: Mapping[str, Any]) -> None:
    """``qc standard set|show``: what the standard is and, for ``show``, its Lab per geometry."""
    what = (
        f"measurement {out['measurement_id']}"
        if out["measurement_id"] is not None
        else f"design {out['design_id']}"
    )
    print(f"standard of {out['job']}/{out['part']}: {what} (set {_when(out['created_at'])} UTC)")
    if "lab" in out:
        rows = [[g, *(f"{v:.2f}" for v in lab)] for g, lab in zip(out["geometries"], out["lab"], strict=True)]
        print(format_table(rows, ["geometry", "L*", "a*", "b*"], indent="  "))


def _standard_line(std: Mapping[str, Any] | None) -> str:
    if std is None:
        return "no standard set"
    what = (
        f"measurement {std['measurement_id']}"
        if std["measurement_id"] is not None
        else f"design {std['design_id']}"
    )
    ids = std.get("measurement_ids") or []
    if ids:
        left = std.get("left_out") or []
        what += f", mean of {len(ids) - len(left)} of {len(ids)} readings"
        what += f" (left out: measurement {_ids(left)})" if left else ""
    return f"standard: {what}"


def _sample_row(s: Mapping[str, Any]) -> list[str]:
    qc = s["qc"]
    ids = s.get("measurement_ids") or [s["measurement_id"]]
    left = s.get("left_out") or []
    return [
        f"panel {s['panel_id']}" if s["panel_id"] is not None else f"measurement {s['measurement_id']}",
        _ids(ids),
        _ids(left),
        s["instrument"],
        s["operator"] or "—",
        _when(s["measured_at"]),
        f"{qc['mean_de']:.2f}",
        f"{qc['max_de']:.2f}",
        qc["worst_geometry"],
        "—" if "texture" not in s else s["texture"]["verdict"],
        s.get("overall", qc["verdict"]).upper(),
    ]


def print_summary(out: Mapping[str, Any]) -> None:
    """``qc summary``: per part the standard, then one row a sample (panel) with its verdict."""
    c = out["counts"]
    tol = out.get("tolerance")
    rule = f", tolerance {tol['name'] or 'file'} ({tol['aggregation']} rule)" if tol else ""
    print(f"job {out['job']}: {out['formula']}{rule}; {c['pass']} pass, {c['warn']} warn, {c['fail']} fail")
    head = [
        "sample",
        "measurement ids",
        "left out",
        "instrument",
        "operator",
        "measured (UTC)",
        "mean dE",
        "max dE",
    ]
    for p in out["parts"]:
        pc = p["counts"]
        print(
            f"\n{p['part']} — {_standard_line(p['standard'])}; {pc['pass']} pass, {pc['warn']} warn, {pc['fail']} fail"
        )
        if p["samples"]:
            print(
                format_table(
                    [_sample_row(s) for s in p["samples"]],
                    [*head, "worst", "texture", "verdict"],
                    indent="  ",
                )
            )
        if p["unjudged"]:
            print(f"  unjudged: measurement {_ids(p['unjudged'])}")
        if p["note"]:
            print(f"  note: {p['note']}")


def print_written(out: Mapping[str, Any]) -> None:
    """``qc report|trend``: what was written."""
    written = out["written"]
    for path in [written] if isinstance(written, str) else written:
        print(f"wrote {path}")
    if "counts" in out:
        c = out["counts"]
        print(f"job {out['job']}: {c['pass']} pass, {c['warn']} warn, {c['fail']} fail ({out['formula']})")


def print_spc(out: Mapping[str, Any]) -> None:
    """``qc spc``: per geometry the chart's limits, Cp/Cpk and every rule hit."""
    print(
        f"SPC of {out['job']}/{out['part']}: {out['samples']} samples, baseline {out['baseline']} ({out['chart']})"
    )
    rows = []
    for g in [*out["geometries"], *out.get("texture", [])]:
        ch, cap = g["chart"], g["capability"]
        cp = "—" if cap is None or cap["cp"] is None else f"{cap['cp']:.2f}"
        cpk = "—" if cap is None or cap["cpk"] is None else f"{cap['cpk']:.2f}"
        usl = "—" if cap is None else f"{cap['usl']:.2f}"
        hits = " ".join(f"{h['rule']}@{h['points'][0] + 1}" for h in ch["hits"]) or "none"
        name = g["geometry"] if g["quantity"] == "ΔE" else f"{g['quantity']} {g['geometry'] or 'sample'}"
        rows.append([name, f"{ch['centre']:.3f}", f"{ch['lcl']:.3f}", f"{ch['ucl']:.3f}", usl, cp, cpk, hits])
    print(
        format_table(
            rows, ["geometry", "centre", "LCL", "UCL", "limit", "Cp", "Cpk", "rules @ first sample #"]
        )
    )
    drift = out.get("drift") or []
    print("drift: none flagged" if not drift else "drift:")
    for line in drift:
        print(f"  {line}")
    if out.get("written"):
        print(f"wrote {out['written']}")


def print_texture(tex: dict[str, Any]) -> None:
    """The texture rows of a verdict as a table (``qc check --texture-limits``)."""
    print(f"texture ({tex['vendor'] or 'no values'}): {tex['verdict']}")

    def num(v: float | None) -> str:
        return "—" if v is None else f"{v:.2f}"

    rows = [
        [
            r["name"],
            r["geometry"] or "sample",
            num(r["standard"]),
            num(r["sample"]),
            num(r["delta"]),
            f"{r['tolerance']} ≤ {r['limit']:g}" if r["limit"] is not None else "—",
            r["verdict"] or "unjudged",
        ]
        for r in tex["rows"]
    ]
    if rows:
        print(
            format_table(
                rows, ["quantity", "geometry", "standard", "sample", "Δ", "tolerance", "verdict"], "  "
            )
        )
