"""Calibration of the frame level of detail's margin (``station.render.lod.FRAME_MARGIN_DE``).

Run: ``.venv/bin/python -m bench.lod_margin``. Training scenes only: design-database paints
(``station.render.design_db``, every fifth design) on the procedural booth, overcast and sky, the sphere
in its standard view, drawn by the GL engine (4 samples per pixel, the CLI's default) and by the NumPy
engine (the service's: map at ``ENV_WIDTH``, faces capped at ``PREFILTER_SIZE``). For each scene and each
setting the level of detail may pick (the default and every candidate), the estimate is the p95 CIEDE2000
of a ``PROBE_SIZE`` probe against the renderer's most accurate setting, and the measured error is the p95
CIEDE2000 of the frame at ``FRAME`` pixels against the truth engine over the shape's interior pixels.
The margin is the largest (measured − estimate), rounded up to 0.05 ΔE00; it is declared, not fitted to
the held-out check (tests/render/test_lod_frame.py: demo-library paints, an HDR sunrise, close-ups,
near-mirror gloss, anisotropic paints).
"""

from __future__ import annotations

import math
import tempfile

import numpy as np

from station.render import lod
from station.render.design_db import design_database
from station.render.envcache import PrefilterCache
from station.render.numpy_renderer import gbuffer
from station.render.procedural import procedural_environment
from station.render.scene_image import ENV_WIDTH, PREFILTER_SIZE, FrameOptions, FrameProbe, interior_mask
from station.render.shapes import Scene
from station.render.truth import render_truth

#: Frame size of the calibration (pixels, square).
FRAME = 48
ENVIRONMENTS = ("booth", "overcast", "sky")


def truth_frame(design, env, scene: Scene, size: int) -> np.ndarray:
    """The truth engine's linear frame of *design* (the shape's pixels; 0 elsewhere)."""
    g = gbuffer(scene, size, size)
    img = np.zeros((size, size, 3))
    img[g.mask] = render_truth(design, env, g.normal[g.mask], g.view[g.mask])
    return img


def gaps(cache_dir: str, every: int = 5) -> list[tuple[str, float, float]]:
    """(label, estimate, measured) for every training scene and setting."""
    rows = []
    cache = PrefilterCache(cache_dir)
    scene = Scene("sphere")
    inner = interior_mask(scene, FRAME)
    designs = design_database()[::every]
    for env_name in ENVIRONMENTS:
        for engine in ("gl", "numpy"):
            env = procedural_environment(env_name)
            if engine == "numpy":
                env = env.downsampled(ENV_WIDTH)
            white = lod.scene_white(env)
            for k, design in enumerate(designs):
                truth = truth_frame(design, env, scene, FRAME)
                options = (
                    FrameOptions("gl", "gl", max_size=None, aa=4)
                    if engine == "gl"
                    else FrameOptions("numpy", "numpy", max_size=PREFILTER_SIZE)
                )
                with FrameProbe([design], env, scene, options, cache=cache) as probe:
                    mask = probe.mask(lod.PROBE_SIZE)
                    ref = probe.draw(lod.FrameSetting(lod.MAX_LOBES), lod.PROBE_SIZE)
                    settings = [lod.DEFAULT_SETTING, *lod.frame_candidates(env.equirect.shape[1])]
                    for s in settings:
                        est = lod.frame_error(ref, probe.draw(s, lod.PROBE_SIZE), white, mask)
                        meas = lod.frame_error(truth, probe.draw(s, FRAME), white, inner)
                        rows.append((f"{env_name} {engine} design {k * every} {s.label()}", est, meas))
    return rows


def main() -> None:
    from bench._report import bench_parser

    parser = bench_parser(__doc__, "lod_margin")
    parser.epilog = "prints the gaps and the margin; it rewrites no section of docs/benchmarks.md"
    parser.add_argument("cache_dir", nargs="?", help="prefilter cache folder (default: a temporary one)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows = gaps(args.cache_dir or tmp)
    worst = max(rows, key=lambda r: r[2] - r[1])
    for label, est, meas in rows:
        print(f"{label}: estimate {est:.3f} measured {meas:.3f} gap {meas - est:+.3f}")
    margin = math.ceil(max(0.0, worst[2] - worst[1]) / 0.05) * 0.05
    print(f"{len(rows)} settings; largest gap {worst[2] - worst[1]:.3f} ({worst[0]}); margin {margin:.2f}")


if __name__ == "__main__":
    main()
