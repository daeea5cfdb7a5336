"""``station model …``: the appearance model from the command line (issue contract).

* ``from-angles`` — aspecular Lab (+ gloss) → face/flop/travel/gloss with the residual per angle;
  its JSON is a valid design file.
* ``eval`` — a design (``--design FILE`` or ``--face/--flop/--travel``) → Lab at aspecular angles.
* ``indices`` — Flop, Chroma and Hue Shift Index with failure warnings.
* ``gloss`` — 60° GU ⇄ the render lobe's Phong exponent (``--gu`` or ``--lobe-exponent``), with the
  simulated meter's 20/60/85° GU, haze, DOI and Rspec of the clear coat of that gloss.
* ``de`` — colour difference per angle and aggregated between two Lab lists.
* ``plot`` — PNG of L*, a*, b* against aspecular angle for one or more designs.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from station.cli._common import add_design_args, add_json_flag, design_from_args, parse_floats, parse_lab_list
from station.errors import InputError
from station.model import ANGLES_3
from station.model.domain import ANGLES_5, DELTA_E_METHOD_NAMES, format_angle
from station.model.gloss import PHONG_MAX, PHONG_MIN, STANDARD_INDEX

STANDARD_EVAL_ANGLES = ",".join(format_angle(a) for a in ANGLES_5)


def _angles(text: str) -> list[float]:
    return parse_floats(text, "angles")


def _from_angles(args: argparse.Namespace) -> dict[str, Any]:
    from station.model import AspecularMeasurements, fit_fftg
    from station.model.design_io import design_to_dict

    angles = _angles(args.angles)
    lab = parse_lab_list(args.lab)
    if len(lab) != len(angles):
        raise InputError("lab", f"{len(angles)} triples (one per angle in --angles)", len(lab))
    result = fit_fftg(AspecularMeasurements(tuple(angles), np.asarray(lab), args.gloss))
    d = result.design
    return design_to_dict(
        d,
        gloss_gu=args.gloss,
        residual_de=list(result.residual_de),
        exact=result.exact,
        method=result.method,
        warnings=list(result.warnings),
        angles=angles,
    )


def _eval(args: argparse.Namespace) -> dict[str, Any]:
    design = design_from_args(args)
    angles = _angles(args.angles)
    return {"angles": angles, "lab": design.lab_at(np.asarray(angles)).tolist()}


def _indices(args: argparse.Namespace) -> dict[str, Any]:
    from station.model import AspecularMeasurements, fit_fftg
    from station.model.design_io import load_design
    from station.model.indices import library_indices

    angles = _angles(args.angles)
    warnings: list[str] = []
    if args.design:
        lab3 = load_design(args.design).lab_at(np.asarray(ANGLES_3))
    else:
        if args.lab is None:
            raise InputError("lab", '"L,a,b;L,a,b;L,a,b" (or --design FILE)')
        lab = np.asarray(parse_lab_list(args.lab))
        if len(lab) != len(angles):
            raise InputError("lab", f"{len(angles)} triples (one per angle in --angles)", len(lab))
        if all(a in angles for a in ANGLES_3):
            lab3 = lab[[angles.index(a) for a in ANGLES_3]]
        else:
            fit = fit_fftg(AspecularMeasurements(tuple(angles), lab))
            lab3 = fit.design.lab_at(np.asarray(ANGLES_3))
            warnings.append("15/45/110 not all measured: indices computed from the fitted model")
    res = library_indices(*lab3)
    return {
        "flop_index": res.flop_index,
        "chroma_index": res.chroma_index,
        "hue_shift_index": res.hue_shift_index,
        "warnings": warnings + list(res.warnings),
    }


def _gloss(args: argparse.Namespace) -> dict[str, Any]:
    """60° GU ⇄ render lobe, plus the meter's readings of the clear coat of that gloss."""
    from station.model.gloss import (
        SpecularLobe,
        coat_from_gloss,
        coat_readings,
        fresnel_unpolarised,
        gloss_from_lobe,
        lobe_from_gloss,
        simulate_gloss_meter,
    )

    if args.lobe_exponent is not None:
        n = args.lobe_exponent
        if not (PHONG_MIN <= n <= PHONG_MAX):
            raise InputError("lobe_exponent", f"{PHONG_MIN:g} <= n <= {PHONG_MAX:g} (Phong exponent)", n)
        albedo = fresnel_unpolarised(60.0, args.coat_index)
        gu = gloss_from_lobe(SpecularLobe(n, albedo, 0.0, args.coat_index))
        lobe = lobe_from_gloss(min(gu, 100.0), args.coat_index)
    else:
        gu = args.gu
        lobe = lobe_from_gloss(gu, args.coat_index)
    coat = coat_from_gloss(min(gu, 100.0))
    meter = coat_readings(coat)
    return {
        "gloss_gu": gu,
        "phong_exponent": lobe.phong_exponent if args.lobe_exponent is None else args.lobe_exponent,
        "specular_albedo": lobe.specular_albedo,
        "ward_alpha": lobe.ward_alpha,
        "simulated_gu": simulate_gloss_meter(lobe, 60, "phong"),
        "simulated_gu_ward": simulate_gloss_meter(lobe, 60, "ward"),
        "meter_gu_20": meter.g20_gu,
        "meter_gu_60": meter.g60_gu,
        "meter_gu_85": meter.g85_gu,
        "haze_hu": meter.haze_hu,
        "log_haze": meter.log_haze,
        "doi": meter.doi,
        "rspec_gu": meter.rspec_gu,
        "d4039_haze_gu": meter.d4039_haze_gu,
        "coat_index": coat.coat_index,
        "coat_haze_weight": coat.haze_weight,
        "coat_peak_exponent": coat.peak_exponent,
        "coat_haze_exponent": coat.haze_exponent,
    }


def _de(args: argparse.Namespace) -> dict[str, Any]:
    from station.model.difference import delta_e

    ref = np.asarray(parse_lab_list(args.reference, "reference"))
    smp = np.asarray(parse_lab_list(args.sample, "sample"))
    if ref.shape != smp.shape:
        raise InputError("sample", f"{len(ref)} triples (as many as --reference)", len(smp))
    angles = None
    if args.angles is not None:
        angles = _angles(args.angles)
        if len(angles) != len(ref):
            raise InputError(
                "angles", f"{len(ref)} aspecular angles (one per --reference triple)", len(angles)
            )
    per = delta_e(ref, smp, args.de, aspecular_deg=angles)
    return {
        "method": args.de,
        "de_per_angle": per.tolist(),
        "mean": float(per.mean()),
        "max": float(per.max()),
        "rms": float(np.sqrt(np.mean(per**2))),
    }


def _plot(args: argparse.Namespace) -> dict[str, Any]:
    from station.design.plots import plot_designs
    from station.model.design_io import load_design

    designs = []
    for p in args.designs:  # an unnamed design is called by its file's name in the legend and here
        d = load_design(p)
        designs.append(d if d.name else d.replace(name=Path(p).stem))
    out = plot_designs(designs, args.out)
    return {"out": str(out), "designs": [d.name for d in designs]}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station model`` and its subcommands."""
    model = subparsers.add_parser("model", help="appearance model: fits, evaluation, indices, gloss")
    sub = model.add_subparsers(dest="model_command", required=True, metavar="SUBCOMMAND")

    p = sub.add_parser("from-angles", help="aspecular Lab → face/flop/travel/gloss (a design file)")
    p.add_argument("--angles", required=True, help="aspecular angles, e.g. 15,45,110")
    p.add_argument("--lab", required=True, help='Lab per angle: "L,a,b;L,a,b;L,a,b"')
    p.add_argument("--gloss", type=float, help="60° gloss in GU (0–100)")
    add_json_flag(p)
    p.set_defaults(handler=_from_angles)

    p = sub.add_parser("eval", help="design → Lab at aspecular angles")
    add_design_args(p)
    p.add_argument("--angles", default=STANDARD_EVAL_ANGLES, help=f"default {STANDARD_EVAL_ANGLES}")
    add_json_flag(p)
    p.set_defaults(handler=_eval)

    p = sub.add_parser("indices", help="Flop, Chroma and Hue Shift Index (thesis eqs 5.3.1–5.3.3)")
    p.add_argument("--angles", default=",".join(format_angle(a) for a in ANGLES_3))
    p.add_argument("--lab", help='Lab per angle: "L,a,b;L,a,b;L,a,b"')
    p.add_argument("--design", help="design file instead of --lab")
    add_json_flag(p)
    p.set_defaults(handler=_indices)

    p = sub.add_parser(
        "gloss",
        help="60° gloss (GU) ⇄ render lobe exponent, with the gloss meter's 20/60/85° GU, haze and DOI",
        description=(
            "Give the 60° gloss (--gu) or the render lobe's Phong exponent (--lobe-exponent) and get the "
            "other, with what the simulated gloss meter reads on a clear coat of that gloss: gloss at "
            "20/60/85° (GU), haze (HU), log haze, DOI (0-100) and Rspec. The renderers draw one lobe "
            "(phong_exponent, specular_albedo, ward_alpha); the meter reads the clear coat, a sharp "
            "peak plus haze (coat_*)."
        ),
    )
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--gu", type=float, help="60° gloss in GU (0–100)")
    which.add_argument(
        "--lobe-exponent", type=float, help=f"Phong exponent of the render lobe ({PHONG_MIN:g}–{PHONG_MAX:g})"
    )
    p.add_argument(
        "--coat-index",
        type=float,
        default=STANDARD_INDEX,
        help=f"refractive index of the render lobe's Fresnel albedo (default {STANDARD_INDEX:g})",
    )
    add_json_flag(p)
    p.set_defaults(handler=_gloss)

    p = sub.add_parser("de", help="colour difference per angle between two Lab lists")
    p.add_argument("--reference", required=True, help='"L,a,b;L,a,b;…"')
    p.add_argument("--sample", required=True, help='"L,a,b;L,a,b;…"')
    p.add_argument("--de", default="cie2000", choices=sorted(DELTA_E_METHOD_NAMES))
    p.add_argument("--angles", help="aspecular angle of each triple, degrees (required by din6175)")
    add_json_flag(p)
    p.set_defaults(handler=_de)

    p = sub.add_parser("plot", help="PNG of L*, a*, b* against aspecular angle for design files")
    p.add_argument("designs", nargs="+", help="design files")
    p.add_argument("--out", required=True, help="output PNG")
    add_json_flag(p)
    p.set_defaults(handler=_plot)
