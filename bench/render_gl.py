"""Full GL re-render (new view every frame) at 1024×1024, frames per second.

Run: ``.venv/bin/python -m bench.render_gl``. Each frame moves the camera (orbit), ray-casts the shape,
shades 7 lobes + diffuse for two paints, tone maps and encodes in the shader, and reads the 8-bit
frame back (``ctx.finish`` implied by the read). Baseline in the same run: the same pipeline with a
single lobe, i.e. the cost of one cube lookup per pixel plus ray cast and read-back. When a GPU is
present the 1920×1080 figure is recorded too.
"""

from __future__ import annotations

import time

import numpy as np

from bench._report import Case, write_section
from station.render import prefilter, procedural, shapes
from station.render.camera import Camera
from station.render.gl_renderer import GLRenderer, create_gl_context
from station.render.weights import LobeWeights

EXPONENTS = (1.0, 4.0, 16.0, 64.0, 256.0, 1024.0, 4096.0)


def _paints(exps) -> list[LobeWeights]:
    rng = np.random.default_rng(2)
    m = len(exps)
    return [LobeWeights(exps, rng.random(3) * 0.1, rng.random((m, 3)) * 0.2, rng.random(m)) for _ in range(2)]


def _fps(gl: GLRenderer, shape: str, exps, frames: int = 30) -> float:
    paints = _paints(exps)
    base = shapes.Scene(shape).camera
    gl.render(shapes.Scene(shape), paints)  # compile + warm up
    t0 = time.perf_counter()
    for k in range(frames):
        a = 2 * np.pi * k / frames
        eye = np.array(base.eye)
        r = np.hypot(eye[0], eye[2])
        cam = Camera((r * np.sin(a), eye[1], r * np.cos(a)), base.target, fov_deg=base.fov_deg)
        gl.render(shapes.Scene(shape, camera=cam), paints)
    return frames / (time.perf_counter() - t0)


def main() -> None:
    env = procedural.sunny_sky(512)
    ctx = create_gl_context()
    renderer = ctx.info["GL_RENDERER"]
    basis = prefilter.prefilter_basis(env, EXPONENTS, ctx=ctx)
    single = prefilter.prefilter_basis(env, (64.0,), ctx=ctx)
    cases = []
    sizes = [(1024, 1024)] + ([(1920, 1080)] if "llvmpipe" not in renderer else [])
    for w, h in sizes:
        with GLRenderer(basis, w, h, ctx=ctx) as gl:
            for shape in ("sphere", "speedshape"):
                cases.append(Case(f"GL re-render {shape}, 7 lobes", f"{w}x{h}", _fps(gl, shape, EXPONENTS),
                                  "fps", "bar >= 20 fps (1024x1024, llvmpipe)"))
        with GLRenderer(single, w, h, ctx=ctx) as gl:
            base = _fps(gl, "sphere", (64.0,))
        cases.append(Case("baseline: sphere, 1 lobe", f"{w}x{h}", base, "fps", "same pipeline, one lookup"))
        cases.append(Case("7 lobes / 1 lobe frame time", f"{w}x{h}", base / cases[-3].figure, "ratio"))
    ctx.release()
    write_section("render_gl", "Full GL re-render (station.render.gl_renderer)", cases,
                  f"Renderer: `{renderer}`. Each frame: new camera, ray cast, shading, tone map, 8-bit read-back.")


if __name__ == "__main__":
    main()
