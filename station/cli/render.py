"""``station render``: a design rendered in an environment to an sRGB PNG (issue 3).

``station render --design FILE [--design2 FILE] --env booth|sky|overcast|PATH
--shape sphere|cylinder|speedshape|panels|seam --size N [--engine auto|gl|numpy|truth] --out FILE.png``
fits the lobe weights (``station.render.lobe_fit.fit_design``), prefilters the environment for the
basis (cached on disk under ``--cache-dir`` / ``$CACAD_CACHE_DIR`` / ``~/.cache/cacad``), renders, tone
maps and writes the PNG (and, with ``--linear-out FILE.exr``, the scene-linear image). ``--design2``
paints the right half (or right panel, or bumper) with a second design. The JSON names the engine,
the lobes and the timings (seconds).

Scene options: ``--stage`` shows the environment as backdrop over a ground with contact shadow
(``--blur DEG``, ``--rotate DEG``, ``--no-ground``); ``--coat N`` adds the clear coat's Fresnel of index N
to the gloss (thesis model without it); ``--flakes`` draws the design file's flake layer (GL and NumPy
engines; the JSON says what the level of detail chose); a design file's ``anisotropy`` (α_x, α_y,
direction; GL engine) is drawn with the level of detail's sample count, reported in the JSON; GL engine only: ``--mesh FILE`` renders a
.glb/.gltf/.obj/.stl model instead of the shape (``--paint-part NAME`` picks the part to paint).
``--lod DE`` lets the level of detail (``station.render.scene_image.scene_lod``, against the ground truth
on a 16 × 16 sample of the view) pick the lobe count and environment resolution for a CIEDE2000
tolerance and reports the choice.
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
    from station.render.options import CURVES
    from station.render.shapes import SHAPES

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
    p.add_argument("--stage", action="store_true", help="environment backdrop and ground with contact shadow")
    p.add_argument("--blur", type=float, default=0.0, help="backdrop blur, degrees (with --stage)")
    p.add_argument("--rotate", type=float, default=0.0, help="environment turn about the vertical, degrees")
    p.add_argument("--no-ground", action="store_true", help="with --stage: backdrop only")
    p.add_argument("--coat", type=float, help="clear coat index for Schlick Fresnel on the gloss (e.g. 1.5)")
    p.add_argument("--mesh", help="GL engine: render this .glb/.gltf/.obj/.stl model instead of the shape")
    p.add_argument("--paint-part", help="with --mesh: the mesh or material name of the part to paint")
    p.add_argument("--flakes", action="store_true", help="the design file's flake layer (metallic sparkle)")
    p.add_argument("--lod", type=float, help="CIEDE2000 tolerance: level of detail picks lobes and map size")
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
    from station.render.flakes import flake_lod
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
    from station.model.gloss import ClearCoat
    from station.render.stage import Stage

    stage = None
    if args.stage or args.rotate:
        stage = Stage(
            backdrop=bool(args.stage),
            backdrop_blur_deg=args.blur,
            rotation_deg=args.rotate,
            ground=bool(args.stage) and not args.no_ground,
        )
    coat = ClearCoat(args.coat) if args.coat is not None else None
    scene = Scene(args.shape, misalignment_deg=args.misalignment, stage=stage)
    lod_report = None
    if args.lod is not None:
        from station.render.scene_image import scene_lod

        t0 = time.perf_counter()
        paints, env, lod_report = scene_lod(designs, env, scene, args.lod)
        timings["lod"] = time.perf_counter() - t0
    engine = args.engine
    if engine == "auto":
        engine = "gl" if gl_available() else "numpy"
    if args.mesh and engine != "gl":
        raise InputError("engine", "gl (or auto with a GL stack) for --mesh", engine)
    if engine == "truth" and (stage is not None or coat is not None or args.flakes):
        raise InputError("engine", "gl | numpy with --stage / --rotate / --coat / --flakes", engine)
    mesh = None
    if args.mesh:
        from station.render.meshes import load_mesh

        mesh = load_mesh(args.mesh, paint=args.paint_part)
    flakes = None
    if args.flakes:
        from station.model.design_io import load_design_flakes

        flakes = load_design_flakes(args.design)[1]
    flake_report = "no flake layer" if args.flakes and flakes is None else None
    from station.model.design_io import load_design_anisotropy

    anisotropy = load_design_anisotropy(args.design)[1]
    if anisotropy is not None and engine != "gl":
        raise InputError("engine", "gl (or auto with a GL stack) for a design with anisotropy", engine)
    aniso_report = None
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
                if mesh is not None:
                    linear = gl.render_mesh(
                        mesh,
                        paints,
                        stage=stage,
                        coat=coat,
                        linear=True,
                        flakes=flakes,
                        anisotropy=anisotropy,
                    )
                else:
                    linear = gl.render_linear(scene, paints, coat=coat, flakes=flakes, anisotropy=anisotropy)
                flake_report = gl.last_flakes.reason if gl.last_flakes is not None else None
                if gl.last_anisotropy is not None:
                    aniso_report = {
                        "samples": gl.last_anisotropy.samples,
                        "error_de": round(gl.last_anisotropy.error_de, 4),
                        "reason": gl.last_anisotropy.reason,
                    }
        else:
            linear = render_linear(scene, basis, paints, size, size, coat=coat, flakes=flakes)
            if flakes is not None:
                flake_report = flake_lod(flakes, scene.view_camera, size).reason
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
        "shape": args.shape if mesh is None else mesh.name,
        "size": size,
        "stage": stage is not None,
        "coat_index": args.coat,
        "flakes": flake_report,
        "anisotropy": aniso_report,
        "lod": lod_report,
        "out": str(out),
        "linear_out": args.linear_out,
        "timings": {k: round(v, 4) for k, v in timings.items()},
    }
