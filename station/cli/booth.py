"""``station booth``: standard and sample side by side under the booth's illuminants (station.qc.booth).

``station booth --standard FILE --sample FILE [--illuminants D65,A,F11] [--observer 2|10]
[--shape panels|seam|car] [--out booth.png] [--json]``

FILE is anything ``station import`` reads that carries spectra (CxF3, CGATS.17, the CSV template, or
``station measure --json`` / ``station import --json`` output) or a recipe (the JSON ``station
formulate --json`` writes: its colorant model's predicted spectra at the other side's geometries, or at
15/45/110° when both sides are recipes); a file that is neither is refused with one line naming it. ``--illuminants`` takes booth names (D65, D50, A, F2, F11, TL84, LED-B3, LED-B4) and
user SPD files (``lamp.csv``: ``wavelength_nm,value`` rows covering 400–700 nm). The JSON is
``{"illuminants": [{"name", "per_geometry": [{"geometry", "standard_lab", "sample_lab", "dE00",
"metamerism_index"}], "mean_de"}], "reference": "D65"}``; without ``--json`` the same numbers as a
table. ``--out`` writes the booth image through the booth renderer (``station.render.booth``).
Exit 0 whatever the differences, 2 with one line for bad input.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from station.cli._common import add_json_flag
from station.errors import InputError


def _illuminants(text: str) -> list[Any]:
    from station.model.illuminants import illuminant_from_text

    parts = [p.strip() for p in text.split(",") if p.strip()]
    if not parts:
        raise InputError("illuminants", "comma-separated illuminants, e.g. D65,A,F11", text)
    return [illuminant_from_text(p) for p in parts]


def _booth(args: argparse.Namespace) -> dict[str, Any] | None:
    from station.model.booth import check_booth_shape
    from station.model.illuminants import observer_cie_name
    from station.qc.booth import booth_compare, booth_sides, load_booth_side

    shape = check_booth_shape(args.shape)
    observer = observer_cie_name(args.observer)
    illuminants = _illuminants(args.illuminants)
    standard, sample = booth_sides(
        load_booth_side(args.standard, "standard"), load_booth_side(args.sample, "sample")
    )
    comparison = booth_compare(standard, sample, illuminants, observer)
    result = comparison.to_dict()
    if args.out:
        from station.render.booth import render_booth_file  # the renderer draws it; the CLI only calls it

        render_booth_file(
            comparison=comparison,
            standard=standard,
            sample=sample,
            illuminants=illuminants,
            observer=observer,
            shape=shape,
            out=Path(args.out),
        )
    if args.json:
        return result
    _print_table(result, args.out)
    return None


def _print_table(result: dict[str, Any], out: str | None) -> None:
    print(
        f"reference illuminant: {result['reference']} (metamerism index: CIE special index, additive correction)"
    )
    print(
        f"{'illuminant':<10} {'geometry':<9} {'standard L,a,b':>24} {'sample L,a,b':>24} {'dE00':>7} {'MI':>7}"
    )
    for ill in result["illuminants"]:
        for g in ill["per_geometry"]:
            std = ",".join(f"{v:.2f}" for v in g["standard_lab"])
            smp = ",".join(f"{v:.2f}" for v in g["sample_lab"])
            print(
                f"{ill['name']:<10} {g['geometry']:<9} {std:>24} {smp:>24} "
                f"{g['dE00']:>7.2f} {g['metamerism_index']:>7.2f}"
            )
        print(f"{ill['name']:<10} {'mean':<9} {'':>24} {'':>24} {ill['mean_de']:>7.2f}")
    if out:
        print(f"image: {out}")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station booth``."""
    from station.model.domain import BOOTH_ILLUMINANTS, BOOTH_SHAPES, DEFAULT_BOOTH_ILLUMINANTS

    p = subparsers.add_parser(
        "booth", help="virtual light booth: standard against sample under booth illuminants, from spectra"
    )
    p.add_argument(
        "--standard",
        required=True,
        help="the standard: a file station import reads, with spectra, or a recipe (station formulate --json)",
    )
    p.add_argument("--sample", required=True, help="the sample (trial): a file with spectra or a recipe JSON")
    p.add_argument(
        "--illuminants",
        default=",".join(DEFAULT_BOOTH_ILLUMINANTS),
        help=f"comma-separated: {', '.join(BOOTH_ILLUMINANTS)} or SPD.csv files "
        f"(default {','.join(DEFAULT_BOOTH_ILLUMINANTS)})",
    )
    p.add_argument("--observer", default="10", help="2 or 10 (degrees; default 10)")
    p.add_argument(
        "--shape", default=BOOTH_SHAPES[0], help=f"{' | '.join(BOOTH_SHAPES)} (default {BOOTH_SHAPES[0]})"
    )
    p.add_argument("--out", help="write the booth image (PNG) to this file")
    add_json_flag(p)
    p.set_defaults(handler=_booth)
