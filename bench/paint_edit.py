"""Paint edit at 1024×1024 from cached basis images, against the memory-bandwidth floor.

Run: ``.venv/bin/python -m bench.paint_edit``. Scene: the sphere (two paints) in the sunny sky with a
default-basis basis. A paint edit = new weights for both paints → weighted sum of the cached images (BLAS),
tone map + sRGB encode (LUT), scatter into the RGBA frame. The floor is the time to read the cached
images once at the bandwidth of a large ``numpy.copyto`` measured in the same run (copy bandwidth
counts the bytes read; the copy also writes as many, so this floor is generous to the benchmark).
"""

from __future__ import annotations

import os
import time

import numpy as np

from bench._report import Case, write_section
from station.render import basis_images, prefilter, procedural, shapes
from station.render.gl_renderer import GLRenderer
from station.render.lobes import default_basis
from station.render.weights import LobeWeights

EXPONENTS = default_basis().exponents
SIZE = 1024


def _paint(rng: np.random.Generator) -> LobeWeights:
    m = len(EXPONENTS)
    return LobeWeights(EXPONENTS, rng.random(3) * 0.1, rng.random((m, 3)) * 0.2, rng.random(m))


def _copy_bandwidth(nbytes: int = 256 << 20) -> float:
    a = np.ones(nbytes // 4, np.float32)
    b = np.empty_like(a)
    best = min(_timed(lambda: np.copyto(b, a)) for _ in range(7))
    return a.nbytes / best


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> None:
    rng = np.random.default_rng(1)
    basis = prefilter.prefilter_basis(procedural.sunny_sky(512), EXPONENTS)
    scene = shapes.Scene("sphere")
    t_build = time.perf_counter()
    with GLRenderer(basis, SIZE, SIZE) as gl:
        cache = basis_images.build_basis_images(scene, basis, SIZE, SIZE, gl_renderer=gl)
    t_build = time.perf_counter() - t_build
    frame = cache.edit_rgba([_paint(rng), _paint(rng)])
    times = []
    for _ in range(60):
        paints = [_paint(rng), _paint(rng)]
        times.append(_timed(lambda p=paints: cache.edit_rgba(p, out=frame)))
    times_ms = np.array(times) * 1e3
    bw = _copy_bandwidth()
    floor_ms = cache.nbytes / bw * 1e3
    med = float(np.median(times_ms))
    cases = [
        Case(
            "paint edit, median",
            f"{SIZE}x{SIZE}",
            med,
            "ms",
            f"bar <= 16 ms; {len(EXPONENTS)} lobes, 2 paints",
        ),
        Case("paint edit, best", f"{SIZE}x{SIZE}", float(times_ms.min()), "ms"),
        Case("paint edit, 90th percentile", f"{SIZE}x{SIZE}", float(np.percentile(times_ms, 90)), "ms"),
        Case(
            "basis images read per edit",
            f"{cache.pixels.size} px",
            cache.nbytes / 1e6,
            "MB",
            f"float32, {len(EXPONENTS) + 1} images x RGB + N.V",
        ),
        Case("numpy copy bandwidth", "256 MiB", bw / 1e9, "GB/s", "bytes read per second"),
        Case("bandwidth floor", "", floor_ms, "ms", "images read once at copy bandwidth"),
        Case("median / floor", "", med / floor_ms, "ratio"),
        Case("build basis images (GL)", f"{SIZE}x{SIZE}", t_build, "s", "once per view"),
    ]
    write_section(
        "paint_edit",
        "Paint edit from cached basis images (station.render.basis_images)",
        cases,
        "Machine shared with other jobs: the median includes their interference; the best "
        f"run is the unloaded figure. Load average at the end: {os.getloadavg()[0]:.1f} on "
        f"{os.cpu_count()} CPUs.",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "paint_edit")
    main()
