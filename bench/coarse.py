"""Calibration of the coarse smooth terms (``station.render.gl_passes.coarse_factor``): how far the sphere's
frame moves when the wide lobes and their exact lights are shaded once per k × k pixels and read back
bilinearly, against the same renderer shading them at every pixel.

The calibration set: the sky (a sun, the sharpest smooth term: an exact light through a wide lobe) and the
booth; a sphere in its default view at 256², 512² and 1024²; bases of exponents (3, E, 400, 1500) with the
wide lobe E in 8, 25, 80 and 190 (the wide lobes are those under 200); a red paint with gloss and
directionally diffuse weights on every lobe; k = 2 and 4. Per case: x = k √E / R (R the sphere's radius on
screen in pixels) and the largest CIEDE2000 over the frame (Lab relative to its brightest pixel).
``COARSE_SCALE`` is the largest x below which every case stays within 0.1 ΔE00, rounded down. The
held-out check is tests/render/test_coarse_smooth.py (other exponents, sizes and cameras).

Run: ``.venv/bin/python -m bench.coarse`` (EGL; about a minute on llvmpipe). Writes docs/benchmarks.md's
``coarse`` section.
"""

from __future__ import annotations

from unittest import mock

import numpy as np

from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.render import prefilter, procedural, shapes
from station.render.footprint import sphere_radius_px
from station.render.gl_passes import COARSE_SCALE
from station.render.gl_renderer import GLRenderer, create_gl_context
from station.render.weights import LobeWeights

SIZES = (256, 512, 1024)
WIDE = (8.0, 25.0, 80.0, 190.0)
FACTORS = (2, 4)
#: The largest ΔE00 a coarse frame may move from the per-pixel frame.
TOLERANCE_DE = 0.1


def paint(exps: tuple[float, ...], gloss: float = 0.1) -> LobeWeights:
    """A red paint with directionally diffuse weight on every lobe of *exps* (four lobes) and gloss weight on
    every lobe, *gloss* on the widest."""
    k_dd = np.array([[0.2, 0.05, 0.03], [0.15, 0.04, 0.02], [0.1, 0.03, 0.02], [0.05, 0.02, 0.01]])
    return LobeWeights(exps, np.array([0.25, 0.05, 0.03]), k_dd, np.array([gloss, 0.2, 0.1, 0.3]))


def max_de(a: np.ndarray, b: np.ndarray) -> float:
    """Largest CIEDE2000 between linear frames *a* and *b*, Lab relative to *a*'s brightest pixel."""
    white = max(float(a.max()), 1e-6)
    lab_a = linear_srgb_to_lab(np.clip(a.reshape(-1, 3), 0.0, None) / white)
    lab_b = linear_srgb_to_lab(np.clip(b.reshape(-1, 3), 0.0, None) / white)
    return float(delta_e(lab_a, lab_b, "cie2000").max())


def cases() -> list[tuple[str, int, float, int, float, float]]:
    """(environment, size, E, k, x = k √E / R, max ΔE00) of the calibration set."""
    ctx = create_gl_context()
    out = []
    try:
        for env in ("sky", "booth"):
            env_map = procedural.procedural_environment(env, 256)
            for e in WIDE:
                exps = (3.0, e, 400.0, 1500.0)
                basis = prefilter.prefilter_basis(env_map, exps, ctx=ctx)
                w = paint(exps)
                for size in SIZES:
                    with GLRenderer(basis, size, size, ctx=ctx) as gl:
                        scene = shapes.Scene("sphere")
                        gl.coarse_smooth = False
                        full = gl.render_linear(scene, [w, w]).astype(np.float64)
                        gl.coarse_smooth = True
                        radius = sphere_radius_px(scene.view_camera, size)
                        for k in FACTORS:
                            with mock.patch("station.render.gl_passes.coarse_factor", return_value=k):
                                frame = gl.render_linear(scene, [w, w]).astype(np.float64)
                            assert gl.last_coarse == k
                            out.append((env, size, e, k, k * np.sqrt(e) / radius, max_de(full, frame)))
    finally:
        ctx.release()
    return out


def main() -> None:
    from bench._report import Case, write_section

    rows = cases()
    fails = sorted(x for *_, x, de in rows if de > TOLERANCE_DE)
    scale = fails[0] if fails else max(x for *_, x, _ in rows)
    report = [
        Case(
            f"{env} {size}², E {e:g}, k {k}",
            f"x {x:.3f}",
            de,
            "max dE00",
            "" if de <= TOLERANCE_DE else "over",
        )
        for env, size, e, k, x, de in sorted(rows, key=lambda r: r[4])
    ]
    report.append(
        Case(
            "largest x within tolerance (calibration)",
            "",
            scale,
            "x",
            f"every case with x below it within {TOLERANCE_DE} dE00; COARSE_SCALE in use: {COARSE_SCALE}",
        )
    )
    write_section(
        "coarse",
        "Coarse smooth terms: the frame against the per-pixel frame (calibration of COARSE_SCALE)",
        report,
        "x = k √E / R: k the coarse factor, E the sharpest wide lobe, R the sphere's radius on screen (px). "
        "GL renderer (llvmpipe) on EGL, render_linear, the sphere's default view.",
    )


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "coarse")
    main()
