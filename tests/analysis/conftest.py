"""Fixtures of the misalignment-analysis tests: a few paints with known character."""

from __future__ import annotations

import numpy as np
import pytest

from station.analysis.index import SeamModel
from station.model import FaceFlopTravelGloss


@pytest.fixture
def grey() -> FaceFlopTravelGloss:
    """A neutral solid grey, L* = 60."""
    return FaceFlopTravelGloss((60.0, 0.0, 0.0), (60.0, 0.0, 0.0), None)


@pytest.fixture
def blue_metallic() -> FaceFlopTravelGloss:
    """A light blue metallic with a dark flop (high travel)."""
    return FaceFlopTravelGloss((90.0, -2.0, -10.0), (30.0, -1.0, -12.0), 70.0)


def brute_force_first_crossing(
    paint, light, view, sign, eps, beta_max=30.0, step=1e-3, hinge="in-plane", method="cie76"
) -> float | None:
    """First β on a fine grid where ΔE ≥ ε (independent of the bracketing code: plain scan)."""
    model = SeamModel([light], [view], hinge=hinge, method=method)
    betas = np.arange(0.0, beta_max + step / 2, step)
    de = model.delta_e(paint, paint, sign * betas)[0]
    vis = np.cumprod(model.visible(sign * betas)[0]).astype(bool)
    hit = np.nonzero((de >= eps) & vis)[0]
    return float(betas[hit[0]]) if hit.size else None
