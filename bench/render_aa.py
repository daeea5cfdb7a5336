"""Cost of the GL renderer's anti-aliasing at 1024×1024 on llvmpipe: frame time without and with it.

Run: ``.venv/bin/python -m bench.render_aa``. Scenes: the sphere and the speed shape (two paints) in the
sunny sky, and the speed shape on the stage (backdrop and ground), 8-bit frames read back
(``GLRenderer.render``). Each anti-aliasing setting (``aa`` samples per pixel, :mod:`station.render.gl_targets`)
gets its own renderer on one EGL context, interleaved round by round so the machine's load falls on every
setting alike; ``aa`` = 1 is the baseline of the same run, and the ratio is median / baseline median.
"""

from __future__ import annotations

import os
import time

import numpy as np

from bench._report import Case, write_section
from station.render import prefilter, procedural, shapes
from station.render.gl_renderer import GLRenderer, create_gl_context
from station.render.lobes import default_basis
from station.render.stage import Stage
from station.render.weights import LobeWeights

EXPONENTS = default_basis().exponents
SIZE = 1024
ROUNDS = 12
SETTINGS = (1, 4, 16)


def _paint(seed: int) -> LobeWeights:
    rng = np.random.default_rng(seed)
    m = len(EXPONENTS)
    return LobeWeights(EXPONENTS, rng.random(3) * 0.1, rng.random((m, 3)) * 0.2, rng.random(m))


def _scenes() -> dict[str, shapes.Scene]:
    return {
        "sphere": shapes.Scene("sphere"),
        "speedshape": shapes.Scene("speedshape"),
        "speedshape on the stage": shapes.Scene("speedshape", stage=Stage()),
    }


def _times(ctx, basis, scene: shapes.Scene, paints: list) -> dict[int, list[float]]:
    """Frame times (s) per aa setting, ROUNDS rounds after one warm-up frame each."""
    renderers = {aa: GLRenderer(basis, SIZE, SIZE, ctx=ctx, aa=aa) for aa in SETTINGS}
    try:
        for gl in renderers.values():
            gl.render(scene, paints)
        times: dict[int, list[float]] = {aa: [] for aa in SETTINGS}
        for _ in range(ROUNDS):
            for aa, gl in renderers.items():
                t0 = time.perf_counter()
                gl.render(scene, paints)
                times[aa].append(time.perf_counter() - t0)
        return times
    finally:
        for gl in renderers.values():
            gl.release()


def main() -> None:
    ctx = create_gl_context()
    basis = prefilter.prefilter_basis(procedural.sunny_sky(512), EXPONENTS, engine="gl", ctx=ctx)
    paints = [_paint(1), _paint(2)]
    cases = []
    for name, scene in _scenes().items():
        times = _times(ctx, basis, scene, paints)
        base = float(np.median(times[1]))
        for aa in SETTINGS:
            med = float(np.median(times[aa]))
            label = "no anti-aliasing (baseline)" if aa == 1 else f"aa {aa} ({int(aa**0.5)}x{int(aa**0.5)})"
            cases.append(
                Case(
                    f"{name}, {label}, median",
                    f"{SIZE}x{SIZE}",
                    med * 1e3,
                    "ms",
                    f"best {min(times[aa]) * 1e3:.1f} ms",
                )
            )
            if aa != 1:
                cases.append(Case(f"  {name}, aa {aa} / no aa", "", med / base, "ratio"))
    renderer = ctx.info.get("GL_RENDERER", "?")
    ctx.release()
    write_section(
        "render_aa",
        "GL renderer anti-aliasing: frame time without and with supersampling (station.render.gl_targets)",
        cases,
        f"GL renderer: {renderer} (EGL). {ROUNDS} interleaved rounds per setting. Machine shared with other "
        f"jobs: load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs at the end; the ratios, "
        "measured in the same rounds, are the figures to compare.",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "render_aa")
    main()
