"""``station library|snap|formulate|export``: the formulation bridge (thesis §5.3; docs/design.md §6).

* ``station library import FILE [--out FILE]`` — read and validate a CSV or CxF3 library, optionally
  convert it; ``station library export demo|FILE --format csv|cxf --out FILE``; ``station library
  browse [--library demo|FILE] --filter type=metallic,pearl --filter flop=3:10 …``.
* ``station snap --library FILE|demo --lab "L,a,b;L,a,b;L,a,b" [--k 5] [--de cie76|cie2000|din6175]
  [--png OUT]`` → ``{"matches": [{"code", "sum_de", "de_per_angle"}], "warnings": [...]}``.
* ``station formulate DESIGN [--line solid|metallic|pearl] [--max-colorants 5] [--scale-resolution 0.1]
  [--recipes 3] [--closed-loop] [--illuminants A,F11 [--candidates N]]`` — the best few recipes of at
  most N colorants from the design's toner line, amounts rounded to the scale, side by side (g per
  batch, ΔE00 before/after rounding, metamerism index A/F11, colorants, cost; ``--json`` keeps every
  field); with ``--illuminants`` the distinct candidate recipes ranked by their metamerism index under
  those illuminants (``metamerism_ranking``, rule in :mod:`station.formulate.metamerism`).
* ``station export DESIGN --format xml|cxf --out FILE`` — the design (both angle sets) and its match.

DESIGN is a ``cacad.design/1`` JSON file or ``"L,a,b;L,a,b;L,a,b"`` at 15/45/110°. The demo
library and the colorants are SYNTHETIC; every output that uses them says so.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from station.cli._common import Steps, add_json_flag, parse_lab_list
from station.errors import InputError
from station.model.domain import ANGLES_3, PAINT_TYPES, SNAP_METRICS

_FILTER_KEYS = ("type", "flop", "chroma", "hue_shift", "set", "kind", "group")


def _load_library(spec: str) -> Any:
    from station.formulate.demo import demo_library
    from station.formulate.library_io import read_library_file

    if spec == "demo":
        return demo_library()
    if spec == "munsell":
        from station.formulate.munsell import munsell_library

        return munsell_library()
    path = Path(spec)
    if path.suffix.lower() not in (".csv", ".cxf", ".xml"):
        raise InputError(
            "library", "demo, munsell, or a .csv / .cxf / .xml (thesis XML or CxF3) library file", spec
        )
    return read_library_file(path)


def _design_lab(text: str) -> tuple[np.ndarray, float | None, str]:
    """Return (Lab at 15/45/110, gloss or None, name) from a design file or a Lab list."""
    from station.model.design_io import load_design

    if ";" in text or ("," in text and not Path(text).exists()):
        lab = np.asarray(parse_lab_list(text, "design"))
        if lab.shape != (3, 3):
            raise InputError("design", '3 Lab triples at 15/45/110: "L,a,b;L,a,b;L,a,b"', text)
        return lab, None, "design"
    design = load_design(text)
    return design.lab_at(np.array(ANGLES_3)), design.gloss_target_gu, design.name or Path(text).stem


def _library_summary(lib: Any) -> dict[str, Any]:
    from station.formulate.library import hierarchy_counts

    return {
        "library": lib.name,
        "synthetic": lib.synthetic,
        "paints": len(lib),
        "angles_deg": list(lib.angles_deg),
        "types": {t: int(np.sum(lib.types == t)) for t in PAINT_TYPES},
        "hierarchy": hierarchy_counts(lib),
    }


def _write_library(lib: Any, out: Path, fmt: str | None) -> str:
    from station.formulate.cxf import write_library_cxf
    from station.formulate.library_csv import write_library_csv

    fmt = fmt or ("cxf" if out.suffix.lower() in (".cxf", ".xml") else "csv")
    if fmt == "csv":
        write_library_csv(lib, out)
    elif fmt == "cxf":
        write_library_cxf(lib, out)
    else:
        raise InputError("format", "csv | cxf", fmt)
    return fmt


def cmd_library_import(args: argparse.Namespace) -> dict[str, Any]:
    """Validate a library file; convert it with ``--out``."""
    lib = _load_library(str(args.file))
    out = _library_summary(lib)
    if args.out:
        out["written"] = str(args.out)
        out["format"] = _write_library(lib, Path(args.out), args.format)
    return out


def cmd_library_export(args: argparse.Namespace) -> dict[str, Any]:
    """Write a library (``demo`` or a file) as CSV or CxF3."""
    lib = _load_library(args.library)
    fmt = _write_library(lib, Path(args.out), args.format)
    return {
        "library": lib.name,
        "synthetic": lib.synthetic,
        "paints": len(lib),
        "format": fmt,
        "out": str(args.out),
    }


def _bounds(text: str, key: str) -> tuple[float | None, float | None]:
    lo, sep, hi = text.partition(":")
    if not sep:
        raise InputError(f"filter.{key}", f"{key}=MIN:MAX (either side may be empty)", text)
    try:
        return (float(lo) if lo.strip() else None, float(hi) if hi.strip() else None)
    except ValueError as exc:
        raise InputError(f"filter.{key}", f"{key}=MIN:MAX with numbers", text) from exc


def parse_filters(items: list[str]) -> Any:
    """``["type=metallic,pearl", "flop=3:10", "group=red"]`` → :class:`LibraryFilter`."""
    from station.formulate.library import LibraryFilter

    kw: dict[str, Any] = {}
    for item in items:
        for part in item.split(";"):
            if not part.strip():
                continue
            key, sep, value = part.partition("=")
            key = key.strip().replace("-", "_")
            if not sep or key not in _FILTER_KEYS:
                raise InputError("filter", f"KEY=VALUE with KEY in {', '.join(_FILTER_KEYS)}", part)
            if key == "type":
                kw["types"] = frozenset(v.strip() for v in value.split(",") if v.strip())
                if not kw["types"] <= set(PAINT_TYPES):
                    raise InputError("filter.type", " , ".join(PAINT_TYPES), value)
            elif key in ("flop", "chroma", "hue_shift"):
                kw[key] = _bounds(value, key)
            else:
                kw["set_name" if key == "set" else key] = value.strip()
    return LibraryFilter(**kw)


def cmd_library_browse(args: argparse.Namespace) -> dict[str, Any]:
    """Filter a library (type check boxes, index bounds, hierarchy) and list the first paints."""
    lib = _load_library(args.library)
    flt = parse_filters(args.filter)
    mask = flt.mask(lib)
    rows = np.flatnonzero(mask)
    idx = lib.indices() if any(b != (None, None) for b in (flt.flop, flt.chroma, flt.hue_shift)) else None
    top, kind, group = lib.groups()
    std = lib.angle_columns()
    paints = []
    for r in rows[: args.limit]:
        item: dict[str, Any] = {
            "code": str(lib.codes[r]),
            "type": str(lib.types[r]),
            "gloss_gu": float(lib.gloss_gu[r]),
            "group": [str(top[r]), str(kind[r]), str(group[r])],
            "lab_15_45_110": std[r].tolist(),
        }
        if idx is not None:
            item["indices"] = {k: (None if np.isnan(v[r]) else float(v[r])) for k, v in idx.items()}
        paints.append(item)
    return {
        "library": lib.name,
        "synthetic": lib.synthetic,
        "matched": int(rows.size),
        "shown": len(paints),
        "paints": paints,
    }


def cmd_snap(args: argparse.Namespace) -> dict[str, Any]:
    """ColorSnap: nearest library paints by summed ΔE over 15/45/110°."""
    from station.formulate.snap import color_snap, view_data

    if args.lab is None and args.design is None:
        raise InputError("lab", '--lab "L,a,b;L,a,b;L,a,b" or --design FILE', None)
    lab, _, name = _design_lab(args.lab if args.lab is not None else str(args.design))
    lib = _load_library(args.library)
    result = color_snap(lib, lab, k=args.k, method=args.de, types=args.types)
    out: dict[str, Any] = result.to_dict()
    out.update({"library": lib.name, "synthetic": lib.synthetic, "types": sorted(args.types or PAINT_TYPES)})
    for row, match in zip(out["matches"], result.matches, strict=True):
        row["type"] = str(lib.types[match.index])
    if args.png or args.view:
        view = view_data(lib, result)
        if args.view:
            out["view"] = view
        if args.png:
            from station.formulate.snap_plot import plot_snap_view

            out["png"] = str(plot_snap_view(view, args.png, f"ColorSnap: {name} in {lib.name}"))
    return out


def cmd_formulate(args: argparse.Namespace) -> dict[str, Any]:
    """Formulate the best few recipes from the ColorSnap match's recipe; optionally run the simulated
    closed loop."""
    from station.formulate.gamut import formulate_in_gamut

    options = _options(args)
    lab, gloss, name = _design_lab(args.design)
    if args.gloss is not None:
        gloss = args.gloss
    with Steps(3 if args.closed_loop else 2, "formulate") as steps:
        steps(f"loading the library {args.library}")
        lib = _load_library(args.library)
        steps("ColorSnap and formulation")
        illuminants = _illuminants(args)
        result, snap = formulate_in_gamut(
            lab,
            lib,
            gloss_gu=gloss,
            tolerance=args.tolerance,
            types=args.types,
            candidates=args.candidates if illuminants else 0,
            options=options,
        )
        if args.closed_loop:
            steps("closed loop: spraying, measuring, correcting")
        out = _formulated(args, lab, gloss, name, lib, result, snap, options)
        if not args.json:
            out["recipes"] = "\n" + recipes_table(out["recipes"])
        if illuminants:
            out["metamerism_ranking"] = _ranking(args, result, illuminants)
        return out


def _options(args: argparse.Namespace) -> Any:
    """The chemist's limits from the command line, each checked (one line, exit 2, naming the option)."""
    from station.formulate.batch import batch_masses
    from station.formulate.errors import FormulateInputError
    from station.formulate.formulation import FormulationOptions, formulation_options

    batch_masses({}, args.batch)  # refuse a bad batch size before formulating
    try:
        return formulation_options(
            FormulationOptions(
                line=args.line,
                max_colorants=args.max_colorants,
                scale_resolution_g=args.scale_resolution,
                batch_g=args.batch,
                recipes=args.recipes,
            )
        )
    except FormulateInputError as exc:
        flag = {"scale_resolution_g": "scale-resolution", "batch_g": "batch"}.get(exc.field, exc.field)
        raise InputError(f"--{flag.replace('_', '-')}", exc.accepted, exc.got) from exc


def recipes_table(recipes: list[dict[str, Any]]) -> str:
    """The recipes side by side, as a chemist compares them: grams per batch (rounded to the scale),
    binder, ΔE00 after and before rounding, metamerism index per illuminant, colorants, cost."""
    from station.decimals import step_decimals

    if not recipes:
        return "(no recipe)"
    names = sorted({n for r in recipes for n in r["grams"]})
    ills = sorted({i for r in recipes for i in (r["metamerism_index"] or {})})
    res = recipes[0]["scale_resolution_g"]
    digits = step_decimals(res)

    def grams(v: float | None) -> str:
        return "-" if v is None else f"{v:.{digits}f}"

    rows: list[tuple[str, list[str]]] = [("", [f"#{r['rank']}" for r in recipes])]
    rows.append(("line", [r["line"] for r in recipes]))
    rows += [(f"{n} (g)", [grams(r["grams"].get(n)) for r in recipes]) for n in names]
    rows.append(("binder (g)", [grams(r["binder_g"]) for r in recipes]))
    rows.append(("batch (g)", [f"{r['batch_g']:g}" for r in recipes]))
    rows.append(("dE00 rounded", [f"{r['mean_de']:.2f}" for r in recipes]))
    rows.append(("dE00 unrounded", [f"{r['mean_de_unrounded']:.2f}" for r in recipes]))
    for ill in ills:
        rows.append(
            (f"MI {ill}", [f"{(r['metamerism_index'] or {}).get(ill, float('nan')):.2f}" for r in recipes])
        )
    rows.append(("colorants", [str(r["colorants"]) for r in recipes]))
    rows.append(("cost / kg", [f"{r['cost_per_kg']:.2f}" for r in recipes]))
    rows.append(("formulable", ["yes" if r["formulable"] else "no" for r in recipes]))
    width = max(len(label) for label, _ in rows)
    cols = [max(len(row[1][k]) for row in rows) for k in range(len(recipes))]
    return "\n".join(
        f"{label:<{width}}  " + "  ".join(f"{v:>{w}}" for v, w in zip(vals, cols, strict=True))
        for label, vals in rows
    )


def _illuminants(args: argparse.Namespace) -> tuple[Any, ...]:
    """The ``--illuminants`` list as catalogue names or user SPD files (``*.csv``; one line, exit 2 for an
    unknown name or a bad file)."""
    from station.formulate.metamerism import chosen_illuminants

    if args.illuminants is None:
        return ()
    if args.candidates < 1:
        raise InputError("candidates", "a count >= 1", args.candidates)
    names = [n for n in args.illuminants.replace(" ", "").split(",") if n]
    return chosen_illuminants(names, "illuminants", allow_files=True)


def _ranking(args: argparse.Namespace, result: Any, illuminants: tuple[Any, ...]) -> Any:
    """The candidates ranked by metamerism index: the full record with --json, one line each without
    (printed below the ``metamerism_ranking:`` key)."""
    from station.formulate.metamerism import rank_formulation

    ranking = rank_formulation(result, illuminants).to_dict()
    if args.json:
        return ranking
    return "\n" + "\n".join(
        f"{c['rank']}. {c['start']}: worst MI {c['worst_index']:.2f} ({c['worst_illuminant']}, "
        f"{c['worst_geometry']}), "
        + ", ".join(f"{ill} {v:.2f}" for ill, v in c["max_index"].items())
        + f"; mean dE00 {c['mean_de']:.2f}{'' if c['formulable'] else ' (not formulable)'}"
        for c in ranking["candidates"]
    )


def _formulated(
    args: argparse.Namespace,
    lab: np.ndarray,
    gloss: float | None,
    name: str,
    lib: Any,
    result: Any,
    snap: Any,
    options: Any,
) -> dict[str, Any]:
    from station.formulate.batch import batch_masses

    out: dict[str, Any] = {
        "design": name,
        **result.to_dict(),
        "matches": [
            {**row, "type": str(lib.types[m.index])}
            for row, m in zip(snap.to_dict()["matches"], snap.matches, strict=True)
        ],
        "snap_warnings": list(snap.warnings),
        "library": lib.name,
        "types": sorted(args.types or PAINT_TYPES),
        "batch": batch_masses(result.recipe, args.batch).to_dict(),
    }
    if args.closed_loop:
        from station.formulate.closed_loop import closed_loop
        from station.formulate.sprayout import SprayOutModel

        spray = SprayOutModel(seed=args.seed)
        starts = [(m.code, lib.recipes[m.index]) for m in snap.matches]
        job = closed_loop(
            lab,
            spray.measure,
            starts=starts,
            gloss_gu=gloss,
            tolerance=args.tolerance,
            max_corrections=args.corrections,
            options=options,
        )
        out["closed_loop"] = job.to_dict()
        out["closed_loop"]["measurement"] = f"simulated spray-out panel model (SYNTHETIC), seed {args.seed}"
    return out


def cmd_export(args: argparse.Namespace) -> dict[str, Any]:
    """Export a design (both 3-angle sets, optionally 5 angles) and its ColorSnap match."""
    from station.formulate.color_xml import write_color_xml
    from station.formulate.cxf import specs_to_cxf
    from station.formulate.export import export_specs
    from station.model import FaceFlopTravelGloss, fit_fftg
    from station.model.design_io import load_design

    if ";" in args.design:
        lab, _, _ = _design_lab(args.design)
        from station.model import AspecularMeasurements

        fit = fit_fftg(AspecularMeasurements(ANGLES_3, lab, args.gloss if args.gloss is not None else 90.0))
        design: FaceFlopTravelGloss = fit.design
    else:
        design = load_design(args.design)
    library = None if args.no_match and not args.recipe else _load_library(args.library)
    specs, match_code = export_specs(
        design, None if args.no_match else library, method=args.de, five_angles=args.five_angles
    )
    extras: list[Any] = [None] * len(specs)
    recipe: dict[str, float] | None = None
    batch: dict[str, float] | None = None
    if args.recipe and library is not None:
        from station.formulate.export import recipe_export
        from station.formulate.formulation import formulate_from_library

        result, _ = formulate_from_library(
            design.lab_at(np.asarray(ANGLES_3)), library, gloss_gu=design.gloss_target_gu
        )
        spec, extra = recipe_export(
            result, name=f"{design.name or 'design'} recipe", five_angles=args.five_angles, batch_g=args.batch
        )
        specs.append(spec)
        extras.append(extra)
        recipe = result.recipe
        batch = dict(extra.recipe)
    out_path = Path(args.out)
    if args.format == "xml":
        write_color_xml(specs, out_path)
    else:
        out_path.write_bytes(specs_to_cxf(specs, extras))
    return {
        "out": str(out_path),
        "format": args.format,
        "colors": [s.name for s in specs],
        "match": match_code,
        "recipe": recipe,
        "batch_g": batch,
        "angle_sets": [list(s.angles_deg) for s in specs[0].sets],
    }


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station library``, ``snap``, ``formulate`` and ``export``."""
    _register_library(subparsers)
    _register_snap(subparsers)
    _register_formulate(subparsers)
    _register_export(subparsers)


def _register_library(subparsers: argparse._SubParsersAction) -> None:
    lib = subparsers.add_parser("library", help="colour libraries: import, export, browse (thesis §5.3.3)")
    sub = lib.add_subparsers(dest="library_command", required=True, metavar="SUBCOMMAND")
    p = sub.add_parser(
        "import", help="read and validate a CSV, CxF3 or thesis-XML library; convert with --out"
    )
    p.add_argument("file", type=Path)
    p.add_argument("--out", type=Path, help="write the library again (.csv or .cxf)")
    p.add_argument("--format", choices=("csv", "cxf"), help="format of --out (default: from its suffix)")
    add_json_flag(p)
    p.set_defaults(handler=cmd_library_import)
    p = sub.add_parser("export", help="write a library (demo or a file) as CSV or CxF3")
    p.add_argument("library", help="demo (SYNTHETIC) or a library file")
    p.add_argument("--format", choices=("csv", "cxf"), help="default: from the suffix of --out")
    p.add_argument("--out", required=True, type=Path)
    add_json_flag(p)
    p.set_defaults(handler=cmd_library_export)
    p = sub.add_parser("browse", help="filter by type, Flop/Chroma/Hue Shift Index bounds and hierarchy")
    p.add_argument("--library", default="demo", help="demo (SYNTHETIC, default) or a library file")
    p.add_argument(
        "--filter",
        action="append",
        default=[],
        help=f"type={','.join(PAINT_TYPES)} | flop=MIN:MAX | chroma=MIN:MAX | hue_shift=MIN:MAX | "
        "set=solids|metallics+pearls | kind=chromatic|neutral | group=red|…|dark (repeatable)",
    )
    p.add_argument("--limit", type=int, default=20, help="paints listed (default 20)")
    add_json_flag(p)
    p.set_defaults(handler=cmd_library_browse)


def _register_snap(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("snap", help="ColorSnap: nearest library paints (thesis §5.3.5)")
    p.add_argument(
        "--library", default="demo", help="demo (SYNTHETIC, default), munsell (real solids) or a library file"
    )
    p.add_argument("--lab", help='design Lab at 15/45/110: "L,a,b;L,a,b;L,a,b"')
    p.add_argument("--design", type=Path, help="design file instead of --lab")
    p.add_argument("--k", type=int, default=5, help="matches (default 5)")
    p.add_argument(
        "--de",
        choices=SNAP_METRICS,
        default="cie76",
        help="ΔE summed over angles (default cie76 = ΔE*ab, the thesis's)",
    )
    p.add_argument(
        "--type",
        dest="types",
        action="append",
        choices=PAINT_TYPES,
        help="search only paints of this type (repeat for several; default: every paint)",
    )
    p.add_argument("--png", type=Path, help="write the 3D Lab view as PNG")
    p.add_argument("--view", action="store_true", help="include the 3D view data in the output")
    add_json_flag(p)
    p.set_defaults(handler=cmd_snap)


def _register_formulate(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("formulate", help="recipe for a design from the synthetic colorants")
    p.add_argument("design", help='design file, or "L,a,b;L,a,b;L,a,b" at 15/45/110')
    p.add_argument("--library", default="demo", help="library with recipes (default demo, SYNTHETIC)")
    p.add_argument("--gloss", type=float, help="60° gloss target in GU (default: the design's)")
    p.add_argument("--tolerance", type=float, default=1.0, help="mean ΔE00 for 'formulable' (default 1.0)")
    p.add_argument(
        "--type",
        dest="types",
        action="append",
        choices=PAINT_TYPES,
        help="start only from library paints of this type (repeat for several; default: every paint)",
    )
    p.add_argument("--closed-loop", action="store_true", help="spray, measure and correct (simulated panel)")
    p.add_argument(
        "--illuminants",
        help="rank the candidate recipes by metamerism index (reference D65) under these test "
        "illuminants, e.g. A,F11,TL84,LED-B4 or a lamp's SPD file lamp.csv (wavelength_nm,value rows)",
    )
    p.add_argument(
        "--candidates",
        type=int,
        default=4,
        help="with --illuminants: starts tried to convergence at least (default 4)",
    )
    p.add_argument("--corrections", type=int, default=3, help="closed-loop corrections (default 3)")
    p.add_argument("--seed", type=int, default=7, help="seed of the simulated spray-out panel")
    p.add_argument(
        "--batch", type=float, default=1000.0, help="batch size in g the recipe is weighed out for"
    )
    _add_selection_args(p)
    add_json_flag(p)
    p.set_defaults(handler=cmd_formulate)


def _add_selection_args(p: argparse.ArgumentParser) -> None:
    """``--line``, ``--max-colorants``, ``--scale-resolution``, ``--recipes`` (ranges checked in
    :func:`_options`)."""
    from station.model.domain import (
        DEFAULT_MAX_COLORANTS,
        DEFAULT_RECIPE_COUNT,
        DEFAULT_SCALE_RESOLUTION_G,
        MAX_COLORANTS_RANGE,
        RECIPE_COUNT_RANGE,
        SCALE_RESOLUTION_RANGE_G,
        TONER_LINES,
    )

    p.add_argument(
        "--line",
        choices=TONER_LINES,
        help="toner line the colorants come from (default: from the design's type; solids never get "
        "aluminium, pearl or interference pigment)",
    )
    p.add_argument(
        "--max-colorants",
        type=int,
        default=DEFAULT_MAX_COLORANTS,
        help=f"most colorants in a recipe, binder and matting agent not counted "
        f"({MAX_COLORANTS_RANGE[0]}-{MAX_COLORANTS_RANGE[1]}, default {DEFAULT_MAX_COLORANTS})",
    )
    p.add_argument(
        "--scale-resolution",
        type=float,
        default=DEFAULT_SCALE_RESOLUTION_G,
        help=f"scale resolution in g: amounts are rounded to it ({SCALE_RESOLUTION_RANGE_G[0]:g}-"
        f"{SCALE_RESOLUTION_RANGE_G[1]:g}, default {DEFAULT_SCALE_RESOLUTION_G:g})",
    )
    p.add_argument(
        "--recipes",
        type=int,
        default=DEFAULT_RECIPE_COUNT,
        help=f"recipes shown side by side ({RECIPE_COUNT_RANGE[0]}-{RECIPE_COUNT_RANGE[1]}, "
        f"default {DEFAULT_RECIPE_COUNT})",
    )


def _register_export(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("export", help="design + ColorSnap match as thesis XML or CxF3")
    p.add_argument("design", help='design file, or "L,a,b;L,a,b;L,a,b" at 15/45/110 (fitted)')
    p.add_argument("--format", choices=("xml", "cxf"), required=True)
    p.add_argument("--out", required=True, type=Path)
    p.add_argument("--library", default="demo", help="library for the match (default demo, SYNTHETIC)")
    p.add_argument("--de", choices=SNAP_METRICS, default="cie76")
    p.add_argument("--five-angles", action="store_true", help="also export the 15/25/45/75/110 set")
    p.add_argument("--no-match", action="store_true", help="export the design without its ColorSnap match")
    p.add_argument(
        "--recipe",
        action="store_true",
        help="also formulate the design and export the recipe as a prediction colour "
        "(CxF3: with the recipe in grams per batch and the predicted spectra per geometry)",
    )
    p.add_argument(
        "--batch", type=float, default=1000.0, help="batch size in g of the exported recipe (default 1000)"
    )
    p.add_argument("--gloss", type=float, help="gloss (GU) when DESIGN is a Lab list (default 90)")
    add_json_flag(p)
    p.set_defaults(handler=cmd_export)
