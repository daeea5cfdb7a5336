"""Renderer accuracy against ground truth per environment type (issue bar, downsized environments).

Environment types: the light booth (extended overhead panels), the sunny sky (a small sun) and the
overcast sky at 128 × 64, and every photographed HDR of the optional data folder beside the checkout
(``../shared/data/hdri``: a studio, a sunrise, a sunset) at 256 × 128. Every design of the design
database is fitted and shaded by ``numpy_renderer.shade_pixels`` on a 16² sphere and compared with
:class:`station.render.truth.TruthScene`'s integral of the designed BRDF itself (CIEDE2000, Lab relative
to the brightest white-Lambertian pixel)"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.render import lobe_fit as lf
from station.render import numpy_renderer as nr
from station.render import procedural
from station.render import truth as tr
from station.render.design_db import design_classes, design_database
from station.render.environment import Environment, load_environment
from station.render.errors import GLUnavailableError
from station.render.gl_context import create_gl_context
from station.render.lobes import default_basis
from station.render.prefilter import prefilter_basis

MEAN_BAR, P95_BAR = 1.0, 2.3
WIDTH = 128  # procedural environments
HDR_WIDTH = 256  # photographed ones: at 128 the sunset's glow shrinks to a few pixels
HDRI = Path(__file__).resolve().parents[3] / "shared" / "data" / "hdri"
HDR_FILES = sorted(HDRI.glob("*.hdr")) if HDRI.is_dir() else []


def _environment(name: str) -> Environment:
    if name in procedural.NAMES:
        return procedural.procedural_environment(name, WIDTH)
    return load_environment(HDRI / name).downsampled(HDR_WIDTH)


@pytest.fixture(scope="module")
def fitted() -> tuple[list[lf.DesignedBRDF], lf.FitReport]:
    brdfs = [lf.designed_brdf(d) for d in design_database()]
    return brdfs, lf.fit_targets(lf.targets_from_brdfs(brdfs), default_basis())


@pytest.fixture(scope="module")
def prefilter_ctx():
    """A GL context for the prefilter when one can be made (fast), else None (NumPy, faces ≤ 16)."""
    try:
        ctx = create_gl_context()
    except GLUnavailableError:
        yield None
        return
    yield ctx
    ctx.release()


def _errors(env_name: str, horizons: tuple[str, ...], fitted, ctx) -> dict[str, np.ndarray]:
    """ΔE00 (designs, pixels) of the renderer's equation against the truth in one environment."""
    brdfs, rep = fitted
    env = _environment(env_name)
    n, v = tr.sphere_pixels(16)
    ndv = n[:, 2]
    r = 2.0 * ndv[:, None] * n - v
    scene = tr.TruthScene(env, n, v, samples=64, quadrature_width=64)
    white = float(scene.white()[..., 1].max())
    refs = [linear_srgb_to_lab(scene.truth(b) / white) for b in brdfs]
    kw = {"engine": "gl", "ctx": ctx} if ctx is not None else {"engine": "numpy", "max_size": 16}
    basis = prefilter_basis(env, default_basis().exponents, **kw)
    return {
        hz: np.stack(
            [
                delta_e(
                    ref,
                    linear_srgb_to_lab(nr.shade_pixels(basis, rep.weights(i), n, r, ndv, horizon=hz) / white),
                    "cie2000",
                )
                for i, ref in enumerate(refs)
            ]
        )
        for hz in horizons
    }


@pytest.mark.parametrize("env_name", [*procedural.NAMES, *(p.name for p in HDR_FILES)])
def test_the_design_database_meets_the_bar(env_name: str, fitted, prefilter_ctx) -> None:
    errors = _errors(env_name, ("lut", "lut-r"), fitted, prefilter_ctx)
    after, before = errors["lut"], errors["lut-r"]
    assert after.mean() <= MEAN_BAR
    assert np.percentile(after, 95) <= P95_BAR
    # every design class within the mean bar but the extremes (lobe-fit limited, docs/benchmarks.md)
    for cls, idx in design_classes().items():
        if cls != "extreme":
            assert after[list(idx)].mean() <= MEAN_BAR, cls
    # bending the directionally diffuse lookups never costs more than noise, and is what makes the
    # photographed sunrise / sunset meet the bar (lookups at R miss it there)
    assert after.mean() <= before.mean() + 0.02
    if env_name.startswith(("venice", "spruit")):
        assert before.mean() > MEAN_BAR or np.percentile(before, 95) > P95_BAR
