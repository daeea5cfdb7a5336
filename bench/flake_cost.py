"""What the flakes cost a frame: the stylist's scene (sphere on the stage, booth, clear coat) at 1024² on
the GL renderer, flakes off against on (the surface-fixed multiscale cells of ``station.render.flakes``),
interleaved in one run over the same 3°-step orbit.

Run: ``.venv/bin/python -m bench.flake_cost`` (EGL; llvmpipe on a CPU-only machine). Median and best wall
time and median process CPU per frame (llvmpipe's threads included): other jobs share the CPUs, so the CPU
figure and the ratio are the honest ones. Writes the ``flake-cost`` section of docs/benchmarks.md.
"""

from __future__ import annotations

import os
import resource
import statistics
import time

import numpy as np

from bench._report import Case, write_section
from station.model import FaceFlopTravelGloss
from station.model.flakes import METALLIC_FLAKES
from station.model.gloss import ClearCoat
from station.render import prefilter, procedural
from station.render.camera import Camera
from station.render.gl_renderer import GLRenderer
from station.render.lobe_fit import fit_design
from station.render.shapes import Scene
from station.render.stage import Stage

SIZE = 1024
FRAMES = 20
SILVER = FaceFlopTravelGloss((90.0, 0.0, -1.0), (30.0, 0.0, -2.0), 60.0, 88.0, "silver")


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _scene(i: int) -> Scene:
    cam = Scene("sphere").view_camera
    a = np.radians(3.0 * i)
    rot = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    eye = np.asarray(cam.target) + rot @ np.subtract(cam.eye, cam.target)
    x, y, z = (float(v) for v in eye)
    return Scene("sphere", camera=Camera((x, y, z), cam.target, fov_deg=cam.fov_deg), stage=Stage())


def main() -> None:
    w = fit_design(SILVER)
    basis = prefilter.prefilter_basis(procedural.light_booth(256), w.exponents, max_size=128)
    times: dict[bool, tuple[list[float], list[float]]] = {False: ([], []), True: ([], [])}
    with GLRenderer(basis, SIZE, SIZE) as gl:
        for on in (False, True):  # compile both programs first
            gl.render(_scene(0), [w], coat=ClearCoat(), flakes=METALLIC_FLAKES if on else None)
        choice = gl.last_flakes
        for i in range(FRAMES):
            for on in (False, True):
                t, c = time.perf_counter(), _cpu()
                gl.render(_scene(i), [w], coat=ClearCoat(), flakes=METALLIC_FLAKES if on else None)
                gl.ctx.finish()
                times[on][0].append(time.perf_counter() - t)
                times[on][1].append(_cpu() - c)
    size = f"{SIZE}x{SIZE}"
    med = {on: statistics.median(times[on][0]) * 1e3 for on in times}
    cpu = {on: statistics.median(times[on][1]) * 1e3 for on in times}
    cases = [
        Case(
            "stylist's scene, flakes off (baseline), median",
            size,
            med[False],
            "ms",
            f"best {min(times[False][0]) * 1e3:.1f} ms; CPU {cpu[False]:.1f} ms/frame",
        ),
        Case(
            "stylist's scene, flakes on, median",
            size,
            med[True],
            "ms",
            f"best {min(times[True][0]) * 1e3:.1f} ms; CPU {cpu[True]:.1f} ms/frame; "
            f"{choice.reason if choice else ''}",
        ),
        Case("  on / off, CPU per frame", "", cpu[True] / cpu[False], "ratio"),
        Case("  on / off, median wall", "", med[True] / med[False], "ratio"),
    ]
    load = os.getloadavg()[0]
    write_section(
        "flake-cost",
        "Flakes: the cost of the surface-fixed multiscale sparkle per frame (core GL renderer)",
        cases,
        f"Sphere on the stage in the booth, clear coat, silver with the aluminium defaults, {FRAMES} frames "
        f"each, interleaved. 1-minute load average at the end: {load:.1f}.",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "flake_cost")
    main()
