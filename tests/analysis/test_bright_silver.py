"""The bright silver (L*15 = 125) through the misalignment analyses: gg-index, trompe l'oeil, seam QA.

Independent expectations: a silver that differs from the bright one only by a lower face L* (90)
changes less with angle at every geometry (X(θ) = flop + (face − flop)·s², same s), so its seams are
smaller and its index β_min no smaller; two panels of the same paint have no formulation ΔE.
"""

from __future__ import annotations

import numpy as np
import pytest

from station.analysis import goniogeometric_index, inverse_trompe_loeil, seam_qa
from station.model import FaceFlopTravelGloss
from station.model.domain import L_MAX


def _dimmer(design: FaceFlopTravelGloss) -> FaceFlopTravelGloss:
    return design.replace(face=(90.0, *design.face[1:]))


def test_gg_index(bright_silver: FaceFlopTravelGloss) -> None:
    bright = goniogeometric_index(bright_silver, 45.0)
    dim = goniogeometric_index(_dimmer(bright_silver), 45.0)
    assert bright.reached and bright.beta_min_deg is not None and bright.beta_min_deg > 0
    assert np.isfinite(bright.max_delta_e) and bright.max_delta_e >= bright.epsilon
    assert dim.beta_min_deg is None or bright.beta_min_deg <= dim.beta_min_deg + bright.resolution_deg
    assert bright.max_delta_e > dim.max_delta_e


def test_trompe_loeil(bright_silver: FaceFlopTravelGloss) -> None:
    r = inverse_trompe_loeil(bright_silver, [30.0, 45.0, 60.0], [0.0, 10.0, 20.0], beta_deg=3.0)
    assert max(r.seam_de_after) <= max(r.seam_de_before) + 1e-9
    assert np.all(np.isfinite(r.seam_de_after))
    assert 0.0 <= r.paint.face[0] <= L_MAX and r.paint.face[0] > 100.0  # stays a bright silver


def test_seam_qa(bright_silver: FaceFlopTravelGloss) -> None:
    same = seam_qa(bright_silver, bright_silver, 2.0)
    assert np.allclose(same.formulation_de, 0.0, atol=1e-9)
    assert np.all(np.isfinite(same.seam_de)) and len(same.seam_de) == len(same.geometries)
    dim = seam_qa(_dimmer(bright_silver), _dimmer(bright_silver), 2.0)  # the same default geometries
    assert dim.geometries == same.geometries
    assert max(same.geometric_de) >= max(dim.geometric_de) - 1e-9


def test_out_of_range_paint_is_refused(bright_silver: FaceFlopTravelGloss) -> None:
    with pytest.raises(ValueError, match=r"face\.L: expected 0 <= L\* <= 200"):
        seam_qa(bright_silver.replace(face=(250.0, 0.0, 0.0)), bright_silver, 2.0)
