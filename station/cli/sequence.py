"""``station sequence``: metallic colour sequences between principal colours (thesis §5.4.4).

``station sequence A.json B.json [C.json …] --steps 9 [--formulate] [--out palette.json] [--json]``: the
steps from A to the last principal colour, evenly spaced by mean CIEDE2000 over 15/45/110°
(:mod:`station.formulate.sequence`); with ``--formulate`` each step is formulated with the shipped
(SYNTHETIC) colorants and says whether it is formulable; ``--out`` writes the steps as a palette file
the viewer opens (File → Open palette).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.cli._common import add_json_flag
from station.errors import InputError
from station.model.domain import ANGLES_3

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss


def _principal(text: str) -> FaceFlopTravelGloss:
    """A design file, or ``"L,a,b;L,a,b;L,a,b"`` at 15/45/110° (fitted to a design)."""
    from station.model import AspecularMeasurements, fit_fftg
    from station.model.design_io import load_design

    if ";" in text:
        from station.cli._common import parse_lab_list

        lab = np.asarray(parse_lab_list(text, "principal"), dtype=float)
        if lab.shape != (3, 3):
            raise InputError("principal", '"L,a,b;L,a,b;L,a,b" at 15/45/110 degrees', text)
        return fit_fftg(AspecularMeasurements(ANGLES_3, lab, 90.0)).design
    return load_design(Path(text))


def cmd_sequence(args: argparse.Namespace) -> dict[str, Any]:
    """Steps between the principal colours; optionally formulated and written as a palette."""
    from station.formulate.sequence import colour_sequence

    principals = [_principal(t) for t in args.principal]
    seq = colour_sequence(principals, args.steps)
    out: dict[str, Any] = seq.to_dict()
    if args.formulate:
        from station.formulate.demo import demo_library
        from station.formulate.formulation import formulate_from_library
        from station.formulate.snap import SnapIndex

        lib = demo_library()
        index = SnapIndex(lib)
        for row, design in zip(out["steps"], seq.designs, strict=True):
            result, _ = formulate_from_library(
                design.lab_at(np.asarray(ANGLES_3)), lib, index=index, gloss_gu=design.gloss_gu
            )
            row.update(
                formulable=result.formulable,
                mean_de=result.mean_de,
                recipe=result.recipe,
                message=result.message,
            )
        out["formulable_steps"] = sum(bool(r["formulable"]) for r in out["steps"])
        out["colorants"] = "SYNTHETIC colorant model"
    if args.out:
        from station.design.palette import save_palette

        out["palette"] = str(
            save_palette([(d.name or f"step {i + 1}", d) for i, d in enumerate(seq.designs)], args.out)
        )
    return out


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station sequence``."""
    p = subparsers.add_parser(
        "sequence", help="colour sequence between principal colours, evenly spaced by eye (thesis §5.4.4)"
    )
    p.add_argument(
        "principal",
        nargs="+",
        help='principal colours in order: design files or "L,a,b;L,a,b;L,a,b" at 15/45/110 (two or more)',
    )
    p.add_argument(
        "--steps", type=int, default=7, help="colours in the sequence, principal ones included (default 7)"
    )
    p.add_argument(
        "--formulate", action="store_true", help="formulate every step with the SYNTHETIC colorants"
    )
    p.add_argument("--out", type=Path, help="write the steps as a palette file (cacad.palette/1 JSON)")
    add_json_flag(p)
    p.set_defaults(handler=cmd_sequence)
