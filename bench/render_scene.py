"""Figures of docs/render.md: one paint (the issue's silver, L* 90 → 30) on the speed shape, the procedural
car and a CC0 car, in the booth, the sunny sky and a photographed HDR, on the stage (backdrop, ground with
contact and sun shadows) with the clear coat, flakes off and on; and close-ups where the flakes sparkle.

Run: ``.venv/bin/python -m bench.render_scene [--shared DIR]`` (GL renderer on EGL). The CC0 car and the HDR
come from ``DIR/meshes/*.glb`` and ``DIR/hdri/*.hdr`` (default: the ``shared/data`` folder beside the
checkout); without them their column / row is left out. Writes ``docs/render/sheet-flakes-off.png``,
``docs/render/sheet-flakes-on.png`` and ``docs/render/closeup-flakes.png`` and prints the frame times and
what the flakes' level of detail chose per tile. Not a benchmark: it is never run by the test suite.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from bench._report import bench_parser
from station.model import FaceFlopTravelGloss
from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render.camera import Camera
from station.render.car import car_body
from station.render.envcache import PrefilterCache
from station.render.environment import Environment, load_environment
from station.render.gl_renderer import GLRenderer
from station.render.lobe_fit import fit_design
from station.render.meshes import load_mesh
from station.render.prefilter import prefilter_basis
from station.render.procedural import procedural_environment
from station.render.shapes import Scene
from station.render.stage import Stage
from station.render.tonemap import save_png

OUT = Path(__file__).resolve().parents[1] / "docs" / "render"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
#: Tile size of the contact sheets (3 × 3 tiles: 720 × 450).
W, H = 240, 150
#: The issue's silver: L* 90 at the face, 30 at the flop, travel 60°, 88 GU.
SILVER = FaceFlopTravelGloss((90.0, 0.0, -1.0), (30.0, 0.0, -2.0), 60.0, 88.0, "silver")
#: Three-quarter front view, closer than the default cameras (flakes still above a pixel's worth).
MODEL_CAMERA = Camera((1.55, 0.55, 2.55), (0.0, -0.25, 0.0), fov_deg=34.0)
SHAPE_CAMERA = Camera((1.45, 0.75, 2.9), (0.45, -0.1, 0.0), fov_deg=34.0)
#: Close-ups (1/4 of the sheet's distance): the sparkle a stylist sees leaning over the panel.
MODEL_CLOSE = Camera((0.75, 0.15, 1.05), (0.2, -0.2, 0.35), fov_deg=34.0)
SHAPE_CLOSE = Camera((0.6, 0.35, 1.2), (0.3, 0.0, 0.0), fov_deg=30.0)


def _environments(shared: Path) -> list[tuple[str, Environment]]:
    envs: list[tuple[str, Environment]] = [
        ("booth", procedural_environment("booth", 512)),
        ("sky", procedural_environment("sky", 512)),
    ]
    hdrs = sorted((shared / "hdri").glob("spruit*.hdr")) or sorted((shared / "hdri").glob("*.hdr"))
    if hdrs:
        envs.append((hdrs[0].stem, load_environment(hdrs[0]).downsampled(512)))
    return envs


def _models(shared: Path) -> list[tuple[str, object]]:
    models: list[tuple[str, object]] = [("speed shape", None), ("procedural car", car_body())]
    cars = sorted((shared / "meshes").glob("*.glb"))
    if cars:
        models.append((cars[-1].stem + " (CC0)", load_mesh(cars[-1])))
    return models


def _tile(gl: GLRenderer, mesh: object, w, flakes, close: bool) -> np.ndarray:
    coat = ClearCoat()
    if mesh is None:
        scene = Scene("speedshape", camera=SHAPE_CLOSE if close else SHAPE_CAMERA, stage=Stage())
        return np.ascontiguousarray(gl.render(scene, [w], coat=coat, flakes=flakes))
    camera = MODEL_CLOSE if close else MODEL_CAMERA
    return np.ascontiguousarray(
        gl.render_mesh(mesh, [w], camera=camera, stage=Stage(), coat=coat, flakes=flakes)
    )


def main(argv: list[str] | None = None) -> None:
    parser = bench_parser(__doc__, "render_scene")
    parser.add_argument("--shared", type=Path, default=SHARED, help="folder with meshes/ and hdri/")
    args = parser.parse_args(argv)
    w = fit_design(SILVER)
    envs, models = _environments(args.shared), _models(args.shared)
    OUT.mkdir(parents=True, exist_ok=True)
    sheets: dict[str, list[np.ndarray]] = {"off": [], "on": []}
    close_rows = []
    for env_name, env in envs:
        t0 = time.perf_counter()
        basis = prefilter_basis(env, w.exponents, engine="gl", cache=PrefilterCache())
        print(f"{env_name}: prefilter {time.perf_counter() - t0:.2f} s")
        with GLRenderer(basis, W, H) as gl:
            for state, flakes in (("off", None), ("on", METALLIC_FLAKES)):
                row = []
                for name, mesh in models:
                    t0 = time.perf_counter()
                    row.append(_tile(gl, mesh, w, flakes, close=False))
                    why = gl.last_flakes.reason if gl.last_flakes is not None else ""
                    print(f"  {name}, flakes {state}: {1e3 * (time.perf_counter() - t0):.0f} ms; {why}")
                sheets[state].append(np.concatenate(row, axis=1))
            pair = []  # close-ups: the speed shape's tail and the last model's side, flakes off | on
            for name, mesh in [models[0], models[-1]]:
                for flakes in (None, METALLIC_FLAKES):
                    pair.append(_tile(gl, mesh, w, flakes, close=True))
                    if flakes is not None and gl.last_flakes is not None:
                        print(f"  close-up {name}: {gl.last_flakes.reason}")
            close_rows.append(np.concatenate(pair, axis=1))
    for state, rows in sheets.items():
        save_png(OUT / f"sheet-flakes-{state}.png", np.concatenate(rows, axis=0))
    save_png(OUT / "closeup-flakes.png", np.concatenate(close_rows, axis=0))


if __name__ == "__main__":
    main()
