"""``station render``: a design rendered in an environment to an sRGB PNG (issue 3).

``station render --design FILE [--design2 FILE] --env booth|sky|overcast|PATH
--shape sphere|cylinder|speedshape|panels|seam --size N [--engine auto|gl|numpy|truth] --out FILE.png``
fits the lobe weights (``station.render.lobe_fit.fit_design``), prefilters the environment for the
basis (cached on disk under ``--cache-dir`` / ``$CACAD_CACHE_DIR`` / ``~/.cache/cacad``), renders, tone
maps and writes the PNG (and, with ``--linear-out FILE.exr``, the scene-linear image). ``--design2``
paints the right half (or right panel, or bumper) with a second design. The JSON names the engine,
the lobes and the timings (seconds).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.cli._common import add_json_flag
from station.errors import InputError

if TYPE_CHECKING:
    from station.render.environment import Environment

ENVS = ("booth", "sky", "overcast")
DESCRIPTION = (
    "Render a design on a shape in a lighting environment and save it as a PNG picture. "
    "Give the design file with --design (a second one with --design2 paints the right half, the "
    "right panel or the bumper), the lighting with --env (booth, sky, overcast or your own .hdr/.exr "
    "photo), the shape with --shape and the picture size with --size. The first render of an "
    "environment takes longer: it is prepared once and kept in the cache folder. With --json the "
    "result names the engine used and the time each step took."
)
EPILOG = (
    "example: station render --design silver.json --env sky --shape speedshape --size 512 --out silver.png"
)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station render``."""
    from station.render.shapes import SHAPES
    from station.render.tonemap import CURVES

    p = subparsers.add_parser(
        "render",
        help="render a design in an environment to a PNG",
        description=DESCRIPTION,
        epilog=EPILOG,
    )
    p.add_argument(
        "--design", required=True, help="design file (JSON, as the viewer and `station design` save)"
    )
    p.add_argument("--design2", help="second design for the other half / right panel / bumper")
    p.add_argument(
        "--env", default="booth", help="booth | sky | overcast | your own .hdr/.exr file (default booth)"
    )
    p.add_argument("--shape", default="sphere", choices=SHAPES, help="object to paint (default sphere)")
    p.add_argument("--size", type=int, default=512, help="image width and height in pixels (8..4096)")
    p.add_argument(
        "--engine",
        default="auto",
        choices=("auto", "gl", "numpy", "truth"),
        help="auto: the graphics card when there is one, else the CPU (numpy); truth: slow reference",
    )
    p.add_argument("--out", required=True, help="output PNG")
    p.add_argument("--linear-out", help="also write the scene-linear image (.exr or .npy)")
    p.add_argument("--exposure", type=float, default=0.0, help="exposure in EV (default 0)")
    p.add_argument(
        "--tone",
        default="aces",
        choices=CURVES,
        help="how bright light is fitted to the screen (default aces)",
    )
    p.add_argument("--misalignment", type=float, default=0.0, help="panels: right panel turn, degrees")
    p.add_argument("--cache-dir", help="prefilter cache folder (default $CACAD_CACHE_DIR or ~/.cache/cacad)")
    add_json_flag(p)
    p.set_defaults(handler=_render)


def _environment(name: str) -> Environment:
    from station.render.environment import load_environment
    from station.render.procedural import procedural_environment

    if name in ENVS:
        return procedural_environment(name)
    if not Path(name).is_file():
        raise InputError("env", "booth | sky | overcast | an existing .hdr/.exr file", name)
    return load_environment(name)


def _render(args: argparse.Namespace) -> dict[str, Any]:
    from station.model.design_io import load_design
    from station.render import lobe_fit, tonemap
    from station.render.envcache import PrefilterCache
    from station.render.gl_renderer import gl_available
    from station.render.numpy_renderer import BACKGROUND, gbuffer, render_linear
    from station.render.prefilter import prefilter_basis
    from station.render.shapes import Scene

    if not 8 <= args.size <= 4096:
        raise InputError("size", "8 <= size <= 4096", args.size)
    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise InputError("out", "a .png path", args.out)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    designs = [load_design(args.design)] + ([load_design(args.design2)] if args.design2 else [])
    timings["load"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    paints = [lobe_fit.fit_design(d) for d in designs]
    timings["fit"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    env = _environment(args.env)
    timings["environment"] = time.perf_counter() - t0
    scene = Scene(args.shape, misalignment_deg=args.misalignment)
    engine = args.engine
    if engine == "auto":
        engine = "gl" if gl_available() else "numpy"
    size = args.size
    exps = paints[0].exponents
    if engine == "truth":
        from station.render.truth import render_truth

        t0 = time.perf_counter()
        g = gbuffer(scene, size, size)
        img = np.full((size, size, 3), BACKGROUND, np.float64)
        pair = designs if len(designs) == 2 else designs * 2
        for k in (0, 1):
            m = g.mask & (g.paint == k)
            if m.any():
                img[m] = render_truth(pair[k], env, g.normal[m], g.view[m])
        linear = img.astype(np.float32)
        timings["render"] = time.perf_counter() - t0
    else:
        t0 = time.perf_counter()
        cache = PrefilterCache(args.cache_dir)
        basis = prefilter_basis(env, exps, engine="gl" if engine == "gl" else "numpy", cache=cache)
        timings["prefilter"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        if engine == "gl":
            from station.render.gl_renderer import GLRenderer

            with GLRenderer(basis, size, size) as gl:
                linear = gl.render_linear(scene, paints)
        else:
            linear = render_linear(scene, basis, paints, size, size)
        timings["render"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    image8 = tonemap.to_display(linear, args.exposure, args.tone)
    out.parent.mkdir(parents=True, exist_ok=True)
    tonemap.save_png(out, image8)
    if args.linear_out:
        lin_path = Path(args.linear_out)
        if lin_path.suffix.lower() == ".exr":
            from station.render.hdr_io import write_exr

            write_exr(lin_path, linear)
        else:
            np.save(lin_path, linear)
    timings["encode"] = time.perf_counter() - t0
    return {
        "engine": engine,
        "lobes": list(exps),
        "environment": env.name,
        "shape": args.shape,
        "size": size,
        "out": str(out),
        "linear_out": args.linear_out,
        "timings": {k: round(v, 4) for k, v in timings.items()},
    }
