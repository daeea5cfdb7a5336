"""Shadow maps and ground ambient occlusion (``station.render.gl_shadows``): what they cost per orbit frame
and what they look like.

Orbit of the procedural car at 1024² in the stylist's scene (stage, clear coat, flakes) on the GL renderer,
shadows on against off, and against on with the sun kept in the narrow lobes and glints (the renderer
before ``station.render.gl_light_maps``), in the same run: three renderers on one context, frames interleaved in blocks, the
camera turning 1° a frame (the maps are drawn once, on the first frame, and reused: an orbit moves the
camera, not the light). CPU time per frame (the process's, llvmpipe's threads included) beside wall time,
and the one-off cost of drawing the maps (first frame with shadows less the mean frame). Writes
``docs/render/car-shadows.png``: sky and booth rows; the procedural car and a CC0 car (when ``--shared``
holds one), shadows off | on; and ``docs/render/shadowed-highlight.png``: the CC0 sport car's shadowed
side up close under the sky, the sun kept in its narrow lobes and glints | taken out in the shadow.

``--model speedshape``: the same orbit of the ray-cast speed shape (its maps ray cast from the light) about
its default view's target, into a section of its own, and ``docs/render/speedshape-shadows.png``: sky and
booth rows; the speed shape and the panels turned −30° (open sheets), shadows off | on.

Run: ``.venv/bin/python -m bench.render_shadows [--model car|speedshape|all] [--shared DIR] [--frames N]``.
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np

from bench._report import Case, bench_parser, write_section
from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render.camera import Camera, orbit_camera
from station.render.car import car_body
from station.render.envcache import PrefilterCache
from station.render.gl_context import create_gl_context
from station.render.gl_renderer import GLRenderer
from station.render.lobe_fit import fit_design
from station.render.meshes import MESH_CAMERA, load_mesh
from station.render.prefilter import prefilter_basis
from station.render.procedural import procedural_environment
from station.render.shapes import DEFAULT_CAMERAS, Scene
from station.render.stage import Stage
from station.render.tonemap import save_png

from .render_scene import SHARED, SILVER

OUT = Path(__file__).resolve().parents[1] / "docs" / "render"
#: Orbit frame size (the viewer benchmark's) and the screenshot's tile size.
SIZE = 1024
TILE = (480, 300)
#: A view from the front left and above, where the sky's sun throws the car's shadow towards the camera side.
SHOT_CAMERA = Camera((-2.5, 1.6, 2.3), (-0.3, -0.3, -0.15), fov_deg=40.0)


def _orbit_camera(yaw_deg: float) -> Camera:
    target = np.asarray(MESH_CAMERA.target, float)
    off = np.asarray(MESH_CAMERA.eye, float) - target
    a = math.radians(yaw_deg)
    rot = np.array([[math.cos(a), 0.0, math.sin(a)], [0.0, 1.0, 0.0], [-math.sin(a), 0.0, math.cos(a)]])
    x, y, z = (float(v) for v in target + rot @ off)
    return Camera((x, y, z), MESH_CAMERA.target, MESH_CAMERA.up, MESH_CAMERA.fov_deg)


def _car_frame(gl: GLRenderer, ctx, mesh, w, yaw: float) -> tuple[float, float]:
    scene = Scene("sphere", camera=_orbit_camera(yaw), stage=Stage())
    t0, c0 = time.perf_counter(), time.process_time()
    gl.draw(scene, [w], coat=ClearCoat(), flakes=METALLIC_FLAKES, mesh=mesh)
    ctx.finish()
    return time.perf_counter() - t0, time.process_time() - c0


#: The speed shape's orbit: about its default view's target, at that view's distance and a 15° pitch.
SPEED_TARGET = DEFAULT_CAMERAS["speedshape"].target
SPEED_DISTANCE = float(
    np.linalg.norm(np.subtract(DEFAULT_CAMERAS["speedshape"].eye, DEFAULT_CAMERAS["speedshape"].target))
)
#: The speed-shape screenshot's view: from above the side the sky's sun throws the shadow to.
SPEED_SHOT = orbit_camera((0.4, -0.2, 0.0), 200.0, 30.0, 5.0, fov_deg=36.0)


def _shape_frame(gl: GLRenderer, ctx, shape: str, w, yaw: float) -> tuple[float, float]:
    scene = Scene(
        shape, camera=orbit_camera(SPEED_TARGET, yaw, 15.0, SPEED_DISTANCE, fov_deg=34.0), stage=Stage()
    )
    t0, c0 = time.perf_counter(), time.process_time()
    gl.draw(scene, [w, w], coat=ClearCoat(), flakes=METALLIC_FLAKES)
    ctx.finish()
    return time.perf_counter() - t0, time.process_time() - c0


def orbit(env_name: str, frames: int, blocks: int = 3, model: str = "car") -> list[Case]:
    """Cases of one environment: frame wall and CPU time, shadows on and off, and the maps' one-off cost;
    *model* "car" (the procedural car) or "speedshape" (the ray-cast shape)."""
    w = fit_design(SILVER)
    basis = prefilter_basis(
        procedural_environment(env_name, 512), w.exponents, engine="gl", cache=PrefilterCache()
    )
    car = car_body()

    def _frame(gl: GLRenderer, ctx, mesh, w, yaw: float) -> tuple[float, float]:
        if model == "speedshape":
            return _shape_frame(gl, ctx, "speedshape", w, yaw)
        return _car_frame(gl, ctx, mesh, w, yaw)

    ctx = create_gl_context()
    modes = ("on", "off", "before")  # before: shadows on, the narrow lobes and glints keeping the light
    times: dict[str, list[tuple[float, float]]] = {m: [] for m in modes}
    first: dict[str, tuple[float, float]] = {}
    try:
        gls = {m: GLRenderer(basis, SIZE, SIZE, ctx=ctx, shadowed_maps=m == "on") for m in modes}
        for mode, gl in gls.items():
            gl.shadows = mode != "off"
            first[mode] = _frame(gl, ctx, car, w, 0.0)  # programs, maps, ground bake
            _frame(gl, ctx, car, w, 0.5)
        yaw = 1.0
        for _ in range(blocks):
            for mode in modes:
                for _ in range(frames):
                    times[mode].append(_frame(gls[mode], ctx, car, w, yaw))
                    yaw += 1.0
        redraws = gls["on"].shadow_redraws
        for gl in gls.values():
            gl.release()
    finally:
        ctx.release()
    lights = basis.lights.count if basis.lights is not None else 0
    size = f"{SIZE}²"
    env_name = env_name if model == "car" else f"{model} {env_name}"
    labels = {"on": "on", "off": "off", "before": "on, the sun kept in the narrow lobes and glints (before)"}
    out = []
    for mode in modes:
        wall = float(np.mean([t[0] for t in times[mode]])) * 1e3
        cpu = float(np.mean([t[1] for t in times[mode]])) * 1e3
        out.append(
            Case(f"{env_name} orbit, shadows {labels[mode]}: CPU", size, cpu, "ms/frame", f"lights: {lights}")
        )
        out.append(
            Case(
                f"{env_name} orbit, shadows {labels[mode]}: wall",
                size,
                wall,
                "ms/frame",
                f"{wall and 1e3 / wall:.1f} fps",
            )
        )
    cpu_of = {m: float(np.mean([t[1] for t in times[m]])) for m in modes}
    out.append(Case(f"{env_name} orbit: CPU on / off", size, cpu_of["on"] / cpu_of["off"], "×", "same run"))
    out.append(
        Case(
            f"{env_name} orbit: CPU on / before",
            size,
            cpu_of["on"] / cpu_of["before"],
            "×",
            "same run: the maps without the shadowed lights (station.render.gl_light_maps)",
        )
    )
    build = (first["on"][1] - cpu_of["on"]) - (first["off"][1] - cpu_of["off"])
    out.append(
        Case(
            f"{env_name} maps drawn (once): CPU",
            size,
            build * 1e3,
            "ms",
            f"first frame on less off, each less its mean frame; map draws in the whole orbit: {redraws} "
            "(the light maps and the ground occlusion, once each; the maps without the lights included)",
        )
    )
    return out


def screenshot(shared: Path) -> Path:
    """docs/render/car-shadows.png: rows sky, booth; columns procedural car off | on, CC0 car off | on."""
    w = fit_design(SILVER)
    models: list[tuple[str, object]] = [("procedural", car_body())]
    cars = sorted((shared / "meshes").glob("*.glb"))
    if cars:
        models.append((cars[-1].stem, load_mesh(cars[-1])))
    rows = []
    for env_name in ("sky", "booth"):
        basis = prefilter_basis(
            procedural_environment(env_name, 512), w.exponents, engine="gl", cache=PrefilterCache()
        )
        with GLRenderer(basis, *TILE, aa=4) as gl:
            row = []
            for _, mesh in models:
                for on in (False, True):
                    gl.shadows = on
                    img = gl.render_mesh(mesh, [w], camera=SHOT_CAMERA, stage=Stage(), coat=ClearCoat())
                    row.append(np.ascontiguousarray(img))
            rows.append(np.concatenate(row, axis=1))
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "car-shadows.png"
    save_png(path, np.concatenate(rows, axis=0))
    return path


#: The close view of highlight_screenshot: the sport car's side away from the sky's sun, its rocker panel in
#: the car's own shadow where it mirrors the sun.
HIGHLIGHT_VIEW = (210.0, 20.0, 2.0)


def highlight_screenshot(shared: Path) -> Path:
    """docs/render/shadowed-highlight.png: the CC0 car (the procedural one without ``--shared``) under the sky,
    the default design with its flakes and the clear coat, a close view of its shadowed side: the narrow
    lobes and glints keeping the sun (before) | read without it where the shadow map hides it."""
    from station.model.design_io import default_flakes
    from ui.models.document import DEFAULT_DESIGN
    from ui.models.view import paint_weights

    cars = sorted((shared / "meshes").glob("*sport*.glb")) or sorted((shared / "meshes").glob("*.glb"))
    mesh = load_mesh(cars[-1]) if cars else car_body()
    w = paint_weights(DEFAULT_DESIGN)
    basis = prefilter_basis(
        procedural_environment("sky", 1024), w.exponents, engine="gl", cache=PrefilterCache()
    )
    camera = orbit_camera(MESH_CAMERA.target, *HIGHLIGHT_VIEW, MESH_CAMERA.fov_deg)
    tiles = []
    for after in (False, True):
        with GLRenderer(basis, 480, 480, aa=4, shadowed_maps=after) as gl:
            img = gl.render_mesh(
                mesh, [w, w], camera, Stage(), coat=ClearCoat(), flakes=default_flakes(DEFAULT_DESIGN)
            )
            tiles.append(np.ascontiguousarray(img))
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "shadowed-highlight.png"
    save_png(path, np.concatenate(tiles, axis=1))
    return path


def shape_screenshot() -> Path:
    """docs/render/speedshape-shadows.png: rows sky, booth; columns speed shape off | on, panels turned −30°
    off | on (the ray-cast shapes' shadow maps against the sphere proxies)."""
    w = fit_design(SILVER)
    scenes = [
        Scene("speedshape", camera=SPEED_SHOT, stage=Stage()),
        Scene("panels", -30.0, camera=orbit_camera((0.0, -0.1, 0.0), -30.0, 20.0, 4.2, 36.0), stage=Stage()),
    ]
    rows = []
    for env_name in ("sky", "booth"):
        basis = prefilter_basis(
            procedural_environment(env_name, 512), w.exponents, engine="gl", cache=PrefilterCache()
        )
        with GLRenderer(basis, *TILE, aa=4) as gl:
            row = []
            for scene in scenes:
                for on in (False, True):
                    gl.shadows = on
                    row.append(np.ascontiguousarray(gl.render(scene, [w, w], coat=ClearCoat())))
            rows.append(np.concatenate(row, axis=1))
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "speedshape-shadows.png"
    save_png(path, np.concatenate(rows, axis=0))
    return path


def main(argv: list[str] | None = None) -> None:
    parser = bench_parser(__doc__, "render_shadows")
    parser.add_argument("--shared", type=Path, default=SHARED, help="folder with meshes/")
    parser.add_argument("--frames", type=int, default=6, help="frames per block (3 blocks per mode)")
    parser.add_argument("--model", choices=("car", "speedshape", "all"), default="all", help="what orbits")
    args = parser.parse_args(argv)
    if args.model in ("speedshape", "all"):
        cases = [c for env in ("sky", "booth") for c in orbit(env, args.frames, model="speedshape")]
        load = os.getloadavg()[0]
        print(f"wrote {shape_screenshot()}")
        write_section(
            "render_shadows_shapes",
            "Shadow maps of the ray-cast shapes: orbit frame cost",
            cases,
            "Speed shape (ray cast, two paints), stage + clear coat + flakes, GL renderer on llvmpipe, "
            "footprint passes; shadows on (maps ray cast from the light, ground occlusion from ray-cast "
            "height maps) against off (sphere proxies) in the same run, frames interleaved in blocks "
            "(`python -m bench.render_shadows --model speedshape`). CPU time is the process's, llvmpipe's "
            f"threads included. Load average {load:.1f} on {os.cpu_count()} CPUs at the end (a shared, "
            "loaded machine: compare on / off within the run only).",
        )
    if args.model == "speedshape":
        return
    cases = [c for env in ("sky", "booth") for c in orbit(env, args.frames)]
    load = os.getloadavg()[0]
    print(f"wrote {screenshot(args.shared)}")
    print(f"wrote {highlight_screenshot(args.shared)}")
    write_section(
        "render_shadows",
        "Shadow maps and ground occlusion: orbit frame cost",
        cases,
        "Procedural car, stage + clear coat + flakes, GL renderer on llvmpipe; shadows on against off in "
        "the same run, frames interleaved in blocks (`python -m bench.render_shadows`). CPU time is the "
        f"process's, llvmpipe's threads included. Load average {load:.1f} on {os.cpu_count()} CPUs at the end.",
    )


if __name__ == "__main__":
    main()
