"""``station design …``: colour styling tools from the command line (thesis §3.4–§3.7).

* ``variations`` — the ring of variations of a design (face | flop | travel-gloss, a degree).
* ``eyedrop`` — face/flop(/gloss) eyedroppers on an image → a design.
* ``render`` — a design in a built-in scene as a PNG (the initial image an artist paints over, §3.7.1).
* ``palette`` — the palette swatch and the booklet thumbnail as PNGs.
* ``sketch-fit`` — fit a design to concept art painted over a built-in scene; JSON
  ``{"design", "rms_de", "failed", "seconds", ...}``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from station.cli._common import add_design_args, add_json_flag, design_from_args, parse_floats
from station.design.images import load_image, save_png
from station.design.moodboard import eyedrop_design
from station.design.palette import booklet, swatch
from station.design.scene import BUILTIN_SCENES, builtin_scene, shade, srgb_encode
from station.design.sketch import fit_point_light
from station.design.variations import CATEGORIES, variations
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_to_dict

#: The thesis's default starting colour for a sketch (§3.7.1: "The system's default is silver").
DEFAULT_SILVER = FaceFlopTravelGloss((85.0, 0.0, 0.0), (40.0, 0.0, 0.0), 70.0, 50.0, "silver")


def _xy(text: str, field: str) -> tuple[float, float]:
    x, y = parse_floats(text, field, 2)
    return (x, y)


def _variations(args: argparse.Namespace) -> dict[str, Any]:
    ring = variations(design_from_args(args), args.degree, args.category)
    return ring.to_dict()


def _eyedrop(args: argparse.Namespace) -> dict[str, Any]:
    img = load_image(args.image)
    face, flop = _xy(args.face, "face"), _xy(args.flop, "flop")
    r = eyedrop_design(
        img.pixels,
        face,
        flop,
        travel_deg=args.travel,
        gloss_gu=args.gloss_gu,
        radius=args.radius,
        auto_swap=not args.no_swap,
        gloss_xy=None if args.gloss is None else _xy(args.gloss, "gloss"),
    )
    return r.to_dict(colour=img.colour_note)


def _render(args: argparse.Namespace) -> dict[str, Any]:
    design = design_from_args(args) if (args.design or args.face) else DEFAULT_SILVER
    scene = builtin_scene(args.scene, args.size)
    path = save_png(args.out, srgb_encode(shade(scene, design)))
    return {"path": str(path), "scene": args.scene, "size": args.size, "design": design_to_dict(design)}


def _palette(args: argparse.Namespace) -> dict[str, Any]:
    design = design_from_args(args)
    out = Path(args.out)
    sw = swatch(design)
    p1 = save_png(out.with_name(out.stem + "-swatch.png"), sw.pixels)
    p2 = save_png(out.with_name(out.stem + "-booklet.png"), booklet(design))
    return {"swatch": str(p1), "booklet": str(p2), "out_of_gamut_columns": sw.out_of_gamut_columns}


def _sketch_fit(args: argparse.Namespace) -> dict[str, Any]:
    art = load_image(args.art).pixels
    h, w = art.shape[:2]
    if h != w:
        raise InputError(
            "art",
            "a square image the size of the scene (render one with `station design render`)",
            f"{w}x{h}",
        )
    scene = builtin_scene(args.scene, h)
    initial = load_image(args.initial).pixels if args.initial else srgb_encode(shade(scene, DEFAULT_SILVER))
    fit = fit_point_light(scene, art, initial, gloss=args.gloss_mode)
    return fit.to_dict()


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station design …`` to the top-level parser."""
    top = subparsers.add_parser("design", help="colour styling tools (variations, eyedroppers, sketch fit)")
    sub = top.add_subparsers(dest="design_command", required=True, metavar="TOOL")

    p = sub.add_parser("variations", help="ring of variations of a design (thesis §3.4.4)")
    add_design_args(p)
    p.add_argument(
        "--degree",
        type=float,
        default=5.0,
        help="step: ΔE*ab for colours, degrees for travel, GU for gloss (0 < d <= 50; default 5)",
    )
    p.add_argument("--category", choices=CATEGORIES, default="face")
    add_json_flag(p)
    p.set_defaults(handler=_variations)

    p = sub.add_parser("eyedrop", help="seed a design from an image with the eyedroppers (thesis §3.5)")
    p.add_argument("image", help="PNG or JPEG")
    p.add_argument("--face", required=True, help="face eyedropper pixel X,Y")
    p.add_argument("--flop", required=True, help="flop eyedropper pixel X,Y")
    p.add_argument("--gloss", help="gloss eyedropper pixel X,Y (contrast gloss); default --gloss-gu")
    p.add_argument("--gloss-gu", type=float, default=50.0, help="gloss without the gloss eyedropper (GU)")
    p.add_argument("--travel", type=float, default=75.0, help="travel slider, degrees (default 75)")
    p.add_argument("--radius", type=int, default=3, help="eyedropper radius in pixels (default 3)")
    p.add_argument(
        "--no-swap", action="store_true", help="keep a face darker than the flop (retroreflective)"
    )
    add_json_flag(p)
    p.set_defaults(handler=_eyedrop)

    p = sub.add_parser("render", help="render a design (default silver) in a built-in scene to PNG")
    add_design_args(p)
    p.add_argument("--scene", choices=tuple(BUILTIN_SCENES), default="sphere-point")
    p.add_argument("--size", type=int, default=128, help="image size in pixels (square)")
    p.add_argument("--out", required=True, help="PNG to write")
    add_json_flag(p)
    p.set_defaults(handler=_render)

    p = sub.add_parser("palette", help="palette swatch and booklet thumbnail PNGs (thesis §3.4.6)")
    add_design_args(p)
    p.add_argument("--out", required=True, help="base path: writes BASE-swatch.png and BASE-booklet.png")
    add_json_flag(p)
    p.set_defaults(handler=_palette)

    p = sub.add_parser("sketch-fit", help="fit a design to concept art over a built-in scene (thesis §3.7)")
    p.add_argument("--scene", choices=tuple(BUILTIN_SCENES), default="sphere-point")
    p.add_argument("--art", required=True, help="the artist's image (PNG/JPEG, the scene's size)")
    p.add_argument("--initial", help="the image the artist started from (default: the scene in silver)")
    p.add_argument(
        "--gloss-mode",
        choices=("contrast", "default", "fit"),
        default="contrast",
        help="contrast gloss (thesis), 50 GU, or fitted with the colour (extension)",
    )
    add_json_flag(p)
    p.set_defaults(handler=_sketch_fit)
