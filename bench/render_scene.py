"""Figures of docs/render.md: one paint on the speed shape, the procedural car and a CC0 car, in the booth,
the sunny sky and a photographed HDR, on the stage (backdrop, ground, contact shadow) with the clear coat;
and a close-up with flakes off and on.

Run: ``.venv/bin/python -m bench.render_scene`` (GL renderer on EGL). The CC0 car and HDR come from
``../shared/data`` (meshes/*.glb, hdri/*.hdr); without them their row / column is left out. Writes
``docs/render-scene.png`` and ``docs/render-flakes.png`` and prints the frame times.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render.camera import Camera
from station.render.design_db import design_database
from station.render.envcache import PrefilterCache
from station.render.environment import load_environment
from station.render.gl_renderer import GLRenderer
from station.render.lobe_fit import fit_design
from station.render.meshes import car_body, load_mesh
from station.render.prefilter import prefilter_basis
from station.render.procedural import procedural_environment
from station.render.shapes import Scene
from station.render.stage import Stage
from station.render.tonemap import save_png

DOCS = Path(__file__).resolve().parents[1] / "docs"
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
W, H = 384, 240
PAINT = "red-metallic"


def main() -> None:
    design = {d.name: d for d in design_database()}[PAINT]
    w = fit_design(design)
    envs = [("booth", procedural_environment("booth", 512)), ("sky", procedural_environment("sky", 512))]
    hdrs = sorted((SHARED / "hdri").glob("studio*.hdr")) or sorted((SHARED / "hdri").glob("*.hdr"))
    if hdrs:
        envs.append((hdrs[0].stem, load_environment(hdrs[0]).downsampled(512)))
    models: list[tuple[str, object]] = [("speed shape", None), ("procedural car", car_body())]
    cars = sorted((SHARED / "meshes").glob("*.glb"))
    if cars:
        models.append((cars[-1].stem + " (CC0)", load_mesh(cars[-1])))
    rows = []
    coat = ClearCoat()
    for env_name, env in envs:
        t0 = time.perf_counter()
        basis = prefilter_basis(env, w.exponents, engine="gl", cache=PrefilterCache())
        print(f"{env_name}: prefilter {time.perf_counter() - t0:.2f} s")
        with GLRenderer(basis, W, H) as gl:
            row = []
            for name, mesh in models:
                t0 = time.perf_counter()
                if mesh is None:
                    img = gl.render(Scene("speedshape", stage=Stage()), [w], coat=coat)
                else:
                    img = gl.render_mesh(mesh, [w], stage=Stage(), coat=coat)
                print(f"  {name}: {1e3 * (time.perf_counter() - t0):.1f} ms")
                row.append(np.ascontiguousarray(img))
            rows.append(np.concatenate(row, axis=1))
    save_png(DOCS / "render-scene.png", np.concatenate(rows, axis=0))
    # Flakes off / on: a close-up of the speed shape's tail in the sky (sun glints) and the booth.
    close = Camera((0.6, 0.35, 1.2), (0.3, 0.0, 0.0), fov_deg=30.0)
    tiles = []
    for env_name, env in envs[:2]:
        basis = prefilter_basis(env, w.exponents, engine="gl", cache=PrefilterCache())
        with GLRenderer(basis, W, H) as gl:
            for flakes in (None, METALLIC_FLAKES):
                tiles.append(
                    np.ascontiguousarray(
                        gl.render(
                            Scene("speedshape", camera=close, stage=Stage()), [w], coat=coat, flakes=flakes
                        )
                    )
                )
                print(f"  flakes {env_name}: {gl.last_flakes.reason}")
    save_png(
        DOCS / "render-flakes.png",
        np.concatenate([np.concatenate(tiles[:2], axis=1), np.concatenate(tiles[2:], axis=1)], axis=0),
    )


if __name__ == "__main__":
    main()
