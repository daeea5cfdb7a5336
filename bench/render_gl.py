"""Full GL re-render (new view every frame) at 1024×1024, frames per second.

Run: ``.venv/bin/python -m bench.render_gl``. Each frame moves the camera (orbit), ray-casts the shape,
shades default basis + diffuse for two paints, tone maps and encodes in the shader, and reads the 8-bit
frame back (``ctx.finish`` implied by the read). The default path pre-sums each paint's lobes into a
gloss and a directionally diffuse cube (rebuilt only when weights change), so a frame does three cube
lookups per pixel. Baseline in the same run: the per-lobe path (``combined=False``, 7 + 1 lookups per
pixel). When a GPU is present the 1920×1080 figure is recorded too.
"""

from __future__ import annotations

import os
import time

import numpy as np

from bench._report import Case, write_section
from station.render import prefilter, procedural, shapes
from station.render.camera import Camera
from station.render.gl_renderer import GLRenderer, create_gl_context
from station.render.lobes import default_basis
from station.render.weights import LobeWeights

EXPONENTS = default_basis().exponents


def _paints(exps) -> list[LobeWeights]:
    rng = np.random.default_rng(2)
    m = len(exps)
    return [LobeWeights(exps, rng.random(3) * 0.1, rng.random((m, 3)) * 0.2, rng.random(m)) for _ in range(2)]


def _fps(gl: GLRenderer, shape: str, exps, frames: int = 30) -> tuple[float, float]:
    """(frames per wall-clock second, frames per process-CPU second) over an orbit of *frames*."""
    paints = _paints(exps)
    base = shapes.Scene(shape).view_camera
    gl.render(shapes.Scene(shape), paints)  # compile + warm up
    t0, c0 = time.perf_counter(), time.process_time()
    for k in range(frames):
        a = 2 * np.pi * k / frames
        eye = np.array(base.eye)
        r = np.hypot(eye[0], eye[2])
        cam = Camera((r * np.sin(a), eye[1], r * np.cos(a)), base.target, fov_deg=base.fov_deg)
        gl.render(shapes.Scene(shape, camera=cam), paints)
    return frames / (time.perf_counter() - t0), frames / (time.process_time() - c0)


def main() -> None:
    env = procedural.sunny_sky(512)
    ctx = create_gl_context()
    renderer = ctx.info["GL_RENDERER"]
    basis = prefilter.prefilter_basis(env, EXPONENTS, ctx=ctx)
    cases = []
    sizes = [(1024, 1024)] + ([(1920, 1080)] if "llvmpipe" not in renderer else [])
    for w, h in sizes:
        with GLRenderer(basis, w, h, ctx=ctx) as gl:
            for shape in ("sphere", "speedshape"):
                wall, cpu = _fps(gl, shape, EXPONENTS)
                cases.append(
                    Case(
                        f"GL re-render {shape}, default basis",
                        f"{w}x{h}",
                        wall,
                        "fps",
                        "bar >= 20 fps (1024x1024, llvmpipe)",
                    )
                )
                cases.append(
                    Case(
                        "  same, per CPU-second of this process",
                        f"{w}x{h}",
                        cpu,
                        "fps",
                        "llvmpipe threads included: a lower bound for an idle machine",
                    )
                )
        with GLRenderer(basis, w, h, ctx=ctx, combined=False) as gl:
            base, _ = _fps(gl, "sphere", EXPONENTS)
        cases.append(Case("baseline: sphere, per-lobe lookups", f"{w}x{h}", base, "fps", "combined=False"))
        cases.append(Case("combined / per-lobe speed-up", f"{w}x{h}", cases[-5].figure / base, "ratio"))
    ctx.release()
    write_section(
        "render_gl",
        "Full GL re-render (station.render.gl_renderer)",
        cases,
        f"Renderer: `{renderer}`. Each frame: new camera, ray cast, shading, tone map, 8-bit read-back. "
        f"Load average at the end: {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs.",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "render_gl")
    main()
