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
to the gloss (thesis model without it); the truth engine takes both, on a stage with the NumPy engine's
backdrop and ground and the point lights shadowed by the shape's ray cast (:func:`_render_truth`);
``--flakes`` draws the design file's flake layer (every engine, the truth's with
``truth_flakes.flake_sparkle_truth``; the JSON says what the level of detail chose); a design file's ``anisotropy`` (α_x, α_y,
direction; GL engine) is drawn with the level of detail's sample count, reported in the JSON;
``--flake-size UM``, ``--flake-density PER_MM2``, ``--flake-spread DEG`` set the flake layer's parameters
(the design file's, or the paint type's default, for the rest; they imply ``--flakes``).
``--view YAW,PITCH[,DISTANCE]`` frames the shape (or model) from that direction (degrees; yaw about the
vertical from +z, pitch above the horizon) at that distance (scene units; default the standard view's).
GL engine only: ``--mesh FILE`` renders a .glb/.gltf/.obj/.stl model instead of the shape (``--paint-part
NAME`` picks the part to paint; the other parts are drawn as tyre, glass or chrome by their names), and
``--mesh car`` the procedural car (body, glass, wheels).
``--aa N`` anti-aliases the GL engine's frame with N samples per pixel (1 off, 4, 9 or 16; default 4).
``--lod DE`` lets the level of detail (``station.render.scene_image.scene_lod``) pick the lobe count,
environment resolution and anisotropic samples for a CIEDE2000 tolerance: each candidate is rendered
small by the frame's own engine and judged against that engine's most accurate setting plus a declared
margin (``station.render.lod.FRAME_MARGIN_DE``); it reports the choice (gl | numpy engines).
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
    from station.model.anisotropy import Anisotropy
    from station.model.flakes import FlakeLayer
    from station.model.gloss import ClearCoat
    from station.render.camera import Camera
    from station.render.environment import Environment
    from station.render.meshes import Mesh
    from station.render.scene_image import FrameOptions
    from station.render.shapes import Scene

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
    from station.render.options import CURVES, FRAME_ENGINES
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
        choices=("auto", *FRAME_ENGINES),
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
    p.add_argument(
        "--mesh", help="GL engine: render this .glb/.gltf/.obj/.stl model (or 'car', the procedural car)"
    )
    p.add_argument("--paint-part", help="with --mesh: the mesh or material name of the part to paint")
    p.add_argument("--flakes", action="store_true", help="the design file's flake layer (metallic sparkle)")
    p.add_argument("--flake-size", type=float, help="flake diameter, micrometres (1..500; implies --flakes)")
    p.add_argument("--flake-density", type=float, help="flakes per mm² (1..100000; implies --flakes)")
    p.add_argument(
        "--flake-spread", type=float, help="flake tilt spread, degrees (0.5..45; implies --flakes)"
    )
    p.add_argument(
        "--view",
        help="YAW,PITCH[,DISTANCE]: look from yaw/pitch degrees at that distance (e.g. 30,15,0.8 close up)",
    )
    p.add_argument(
        "--aa",
        type=int,
        help="GL engine: anti-aliasing samples per pixel, 1 (off) | 4 | 9 | 16 (default 4)",
    )
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


def _view_camera(text: str | None, default: Camera) -> Camera:
    """The camera of ``--view YAW,PITCH[,DISTANCE]`` about *default*'s target (None: *default*)."""
    from station.render.camera import orbit_camera

    if text is None:
        return default
    parts = text.split(",")
    try:
        values = [float(x) for x in parts]
    except ValueError:
        values = []
    if len(values) not in (2, 3) or not all(np.isfinite(values)):
        raise InputError("view", "YAW,PITCH[,DISTANCE]: two or three numbers", text)
    distance = (
        values[2] if len(values) == 3 else float(np.linalg.norm(np.subtract(default.eye, default.target)))
    )
    return orbit_camera(default.target, values[0], values[1], distance, default.fov_deg)


def _flake_layer(args: argparse.Namespace) -> FlakeLayer | None:
    """The frame's flake layer: None without --flakes / --flake-*; the design file's (or the paint type's
    default) with the --flake-* values put in."""
    from station.model.design_io import load_design_flakes
    from station.model.flakes import METALLIC_FLAKES, FlakeLayer

    given = {
        k: v
        for k, v in (
            ("size_um", args.flake_size),
            ("density_per_mm2", args.flake_density),
            ("spread_deg", args.flake_spread),
        )
        if v is not None
    }
    if not (args.flakes or given):
        return None
    layer = load_design_flakes(args.design)[1]
    if not given:
        return layer
    return FlakeLayer(**{**(layer or METALLIC_FLAKES).to_dict(), **given})


def _scene(
    args: argparse.Namespace, engine: str, anisotropy: Anisotropy | None
) -> tuple[Scene, FrameOptions]:
    """The scene of the arguments (shape, camera, stage) and how *engine* draws its frame (coat, mesh,
    samples per pixel, the design's *anisotropy*)."""
    from station.model.gloss import ClearCoat
    from station.render.scene_image import FrameOptions
    from station.render.shapes import Scene
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
    mesh: Mesh | None = None
    if args.mesh:
        from station.render.meshes import MESH_CAMERA, load_mesh

        if args.mesh == "car":
            from station.render.car import car_body

            mesh = car_body()
        else:
            mesh = load_mesh(args.mesh, paint=args.paint_part)
        camera = _view_camera(args.view, MESH_CAMERA)
    else:
        camera = _view_camera(args.view, Scene(args.shape).view_camera)
    scene = Scene(args.shape, misalignment_deg=args.misalignment, camera=camera, stage=stage)
    frame = FrameOptions(
        engine,
        prefilter_engine="gl" if engine == "gl" else "numpy",
        max_size=None,
        coat=coat,
        mesh=mesh,
        aa=_aa(args) if engine == "gl" else 1,
        anisotropy=anisotropy,
    )
    return scene, frame


def _check(args: argparse.Namespace, engine: str, anisotropy: Anisotropy | None) -> None:
    """Refuse the combinations an engine does not draw (InputError naming ``engine``)."""
    if args.mesh and engine != "gl":
        raise InputError("engine", "gl (or auto with a GL stack) for --mesh", engine)
    if args.aa is not None and args.aa != 1 and engine != "gl":
        raise InputError("engine", "gl (or auto with a GL stack) for --aa above 1", engine)
    if anisotropy is not None and engine != "gl":
        raise InputError("engine", "gl (or auto with a GL stack) for a design with anisotropy", engine)


def _render_truth(
    designs: list,
    paints: list,
    env: Environment,
    scene: Scene,
    size: int,
    coat: ClearCoat | None,
    basis: Any,
    flakes: FlakeLayer | None = None,
) -> np.ndarray:
    """Linear image of the truth engine (``station.render.truth.render_truth``) drawing *scene* with *coat*.

    On a stage the normals and views are turned into the environment's frame as the NumPy renderer turns
    its lookups (``station.render.stage.lookup_matrix``), the point lights are shadowed by the shape's own
    ray cast, and the rays that miss the shape show the NumPy renderer's stage background
    (``numpy_renderer.stage_background``) from the prefiltered *basis* (None without a stage). *flakes*:
    the sparkle of ``truth_flakes.flake_sparkle_truth`` in each paint's flake tint (its fitted *paints*' directionally
    diffuse colour), added as the renderers add it where ``flake_lod`` keeps the layer on."""
    from station.render.flakes import clip_sparkle, flake_lod, flake_tint
    from station.render.numpy_renderer import BACKGROUND, gbuffer, stage_background
    from station.render.stage import lookup_matrix
    from station.render.truth import prepare_lighting, render_truth
    from station.render.truth_flakes import flake_sparkle_truth

    g = gbuffer(scene, size, size)
    img = np.full((size, size, 3), BACKGROUND, np.float64)
    if scene.stage is not None:
        origin, dirs = scene.view_camera.rays(size, size)
        img[~g.mask] = stage_background(scene, basis, origin, dirs[~g.mask])
    turn = lookup_matrix(scene.stage.rotation_deg if scene.stage is not None else 0.0)
    pair = list(zip(designs, paints, strict=True)) if len(designs) == 2 else [(designs[0], paints[0])] * 2
    sparkle = flakes is not None and flake_lod(flakes, scene.view_camera, size).on
    lighting = prepare_lighting(env) if sparkle else None
    camera = scene.view_camera
    for k in (0, 1):
        m = g.mask & (g.paint == k)
        if m.any():
            n_env, v_env = g.normal[m] @ turn.T, g.view[m] @ turn.T
            shadows = {"positions": g.position[m], "scene": scene} if scene.stage is not None else {}
            img[m] = render_truth(pair[k][0], env, n_env, v_env, coat=coat, **shadows)
            if flakes is not None and sparkle:
                glint = flake_sparkle_truth(
                    env,
                    flakes,
                    flake_tint(pair[k][1].map_weights()[1]),
                    g.position[m],
                    n_env,
                    v_env,
                    np.linalg.norm(g.position[m] - np.asarray(camera.eye, dtype=float), axis=-1),
                    float(np.tan(np.radians(camera.fov_deg) / 2.0)),
                    size,
                    lighting=lighting,
                )
                img[m] = img[m] + clip_sparkle(glint, img[m], flakes)
    return img.astype(np.float32)


def _render_gl(
    basis: Any,
    paints: list,
    scene: Scene,
    frame: FrameOptions,
    flakes: FlakeLayer | None,
    size: int,
    anisotropic_samples: int | None = None,
) -> tuple[np.ndarray, str | None, dict[str, Any] | None]:
    """(linear image, flake report, anisotropy report) of the GL engine drawing *scene* (its stage) as
    *frame* says (coat, mesh, samples per pixel, anisotropy) with *flakes*, *anisotropic_samples*
    off-specular samples (None: the renderer's own choice)."""
    from station.render.gl_renderer import GLRenderer
    from station.render.scene_image import gl_frame

    with GLRenderer(basis, size, size, aa=frame.aa) as gl:
        linear = gl_frame(gl, scene, paints, frame, flakes=flakes, anisotropic_samples=anisotropic_samples)
        flake_report = gl.last_flakes.reason if gl.last_flakes is not None else None
        aniso_report = None
        if gl.last_anisotropy is not None:
            aniso_report = {
                "samples": gl.last_anisotropy.samples,
                "error_de": (
                    round(gl.last_anisotropy.error_de, 4)
                    if np.isfinite(gl.last_anisotropy.error_de)
                    else None
                ),
                "reason": gl.last_anisotropy.reason,
            }
    return linear, flake_report, aniso_report


def _write(args: argparse.Namespace, out: Path, linear: np.ndarray) -> None:
    from station.render import tonemap

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


def _draw(
    args: argparse.Namespace,
    engine: str,
    designs: list,
    paints: list,
    env: Environment,
    scene: Scene,
    frame: FrameOptions,
    flakes: FlakeLayer | None,
    timings: dict[str, float],
    lod_report: dict[str, Any] | None = None,
) -> tuple[np.ndarray, str | None, dict[str, Any] | None]:
    """The linear frame of *engine* with *flakes*, the flake layer's and the anisotropy's reports (None
    when the frame has none); the prefilter's and the draw's seconds into *timings*."""
    from station.render.envcache import PrefilterCache
    from station.render.flakes import flake_lod
    from station.render.numpy_renderer import render_linear
    from station.render.prefilter import prefilter_basis

    size, exps = args.size, paints[0].exponents
    flake_report = None if flakes is None else flake_lod(flakes, scene.view_camera, size).reason
    aniso_report = None
    t0 = time.perf_counter()
    if engine == "truth":
        basis = None
        if scene.stage is not None:  # the backdrop and ground, as the NumPy engine draws them
            basis = prefilter_basis(env, exps, engine="numpy", cache=PrefilterCache(args.cache_dir))
            timings["prefilter"] = time.perf_counter() - t0
            t0 = time.perf_counter()
        linear = _render_truth(designs, paints, env, scene, size, frame.coat, basis, flakes)
    else:
        basis = prefilter_basis(
            env, exps, engine=frame.prefilter_engine, cache=PrefilterCache(args.cache_dir)
        )
        timings["prefilter"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        if engine == "gl":
            samples = None if lod_report is None else lod_report["anisotropic_samples"]
            linear, flake_report, aniso_report = _render_gl(
                basis, paints, scene, frame, flakes, size, samples
            )
        else:
            linear = render_linear(scene, basis, paints, size, size, coat=frame.coat, flakes=flakes)
    timings["render"] = time.perf_counter() - t0
    return linear, flake_report, aniso_report


def _render(args: argparse.Namespace) -> dict[str, Any]:
    from station.model.design_io import load_design, load_design_anisotropy
    from station.render import lobe_fit
    from station.render.gl_renderer import gl_available

    if not 8 <= args.size <= 4096:
        raise InputError("size", "8 <= size <= 4096", args.size)
    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise InputError("out", "a .png path", args.out)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    designs = [load_design(args.design)] + ([load_design(args.design2)] if args.design2 else [])
    flakes = _flake_layer(args)
    engine = args.engine if args.engine != "auto" else ("gl" if gl_available() else "numpy")
    anisotropy = load_design_anisotropy(args.design)[1]
    _check(args, engine, anisotropy)
    scene, frame = _scene(args, engine, anisotropy)
    timings["load"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    paints = [lobe_fit.fit_design(d) for d in designs]
    timings["fit"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    env = _environment(args.env)
    timings["environment"] = time.perf_counter() - t0
    lod_report = None
    if args.lod is not None:
        t0 = time.perf_counter()
        paints, env, lod_report = _lod(args, designs, env, scene, frame)
        timings["lod"] = time.perf_counter() - t0
    size = args.size
    exps = paints[0].exponents
    linear, flake_report, aniso_report = _draw(
        args, engine, designs, paints, env, scene, frame, flakes, timings, lod_report
    )
    if args.flakes and flakes is None:
        flake_report = "no flake layer"
    t0 = time.perf_counter()
    _write(args, out, linear)
    timings["encode"] = time.perf_counter() - t0
    return {
        "engine": engine,
        "lobes": list(exps),
        "environment": env.name,
        "shape": args.shape if frame.mesh is None else frame.mesh.name,
        "size": size,
        "stage": scene.stage is not None,
        "coat_index": args.coat,
        "flakes": flake_report,
        "flake_layer": flakes.to_dict() if flakes is not None else None,
        "view": _view_report(scene.view_camera),
        "anisotropy": aniso_report,
        "lod": lod_report,
        "aa": frame.aa,
        "out": str(out),
        "linear_out": args.linear_out,
        "timings": {k: round(v, 4) for k, v in timings.items()},
    }


def _lod(
    args: argparse.Namespace, designs: list, env: Environment, scene: Scene, frame: FrameOptions
) -> tuple[list, Environment, dict[str, Any]]:
    """``--lod``: the paints, environment and report of the level of detail judged on the frame's own
    engine as *frame* draws it (``station.render.scene_image.scene_lod``); refused for the truth engine,
    naming ``lod``."""
    from station.render.envcache import PrefilterCache
    from station.render.scene_image import scene_lod

    if frame.engine == "truth":
        raise InputError(
            "lod", "a tolerance for the gl | numpy engine (truth has no level of detail)", args.lod
        )
    return scene_lod(
        designs, env, scene, args.lod, frame, cache=PrefilterCache(args.cache_dir), size=args.size
    )


def _aa(args: argparse.Namespace) -> int:
    """Samples per pixel of the GL engine: ``--aa``, else :data:`station.render.gl_targets.DEFAULT_AA`."""
    from station.render.gl_targets import DEFAULT_AA

    return int(args.aa) if args.aa is not None else DEFAULT_AA


def _view_report(camera: Camera) -> dict[str, Any]:
    return {
        "eye": [round(float(x), 4) for x in camera.eye],
        "target": [round(float(x), 4) for x in camera.target],
    }
