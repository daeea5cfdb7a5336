"""The QA pictures agree with the verdict: beside the seam, the picture's colours are the seam model's,
so their ΔE is the seam ΔE ``seam_qa`` reports at that geometry; the caption names the geometry."""

from __future__ import annotations

import numpy as np
import pytest

from station.analysis.picture import display_exposure, geometry_caption, lab_picture, seam_pair_lab
from station.analysis.qa import seam_qa
from station.model import FaceFlopTravelGloss

METALLIC = FaceFlopTravelGloss((61.9, 15.2, 8.0), (5.0, 10.1, 4.2), 79.9, 90.0)


def test_the_same_paint_on_both_panels_pictures_the_seam_it_fails_by():
    r = seam_qa(METALLIC, METALLIC, 5.0)
    assert not r.passed and max(r.formulation_de) == 0.0
    for g, geo in enumerate(r.geometries):
        lab = seam_pair_lab(METALLIC, METALLIC, 5.0, geo.light_deg, geo.view_deg, size=(8, 2000))
        shown = float(np.linalg.norm(lab[4, 1000] - lab[4, 999]))
        assert shown == pytest.approx(r.seam_de[g], rel=0.01, abs=0.05)


def test_a_solid_at_normal_light_has_the_closed_form_seam():
    """A grey solid: panel B's L* is the shading ratio k = cos(θ_L − β)/cos θ_L applied to Y (eq 4.3.2)."""
    grey = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None)
    lab = seam_pair_lab(grey, grey, 10.0, 45.0, 0.0, size=(8, 2000))
    k = np.cos(np.radians(35.0)) / np.cos(np.radians(45.0))
    y = ((50.0 + 16.0) / 116.0) ** 3 * k
    assert lab[4, 999, 0] == pytest.approx(50.0, abs=0.05)
    assert lab[4, 1000, 0] == pytest.approx(116.0 * y ** (1 / 3) - 16.0, abs=0.05)


def test_exposure_keeps_a_brighter_than_white_seam_visible():
    r = seam_qa(METALLIC, METALLIC, 5.0, lights_deg=(45.0,), aspecular_deg=(15.0,))
    geo = r.geometries[0]
    lab = seam_pair_lab(METALLIC, METALLIC, 5.0, geo.light_deg, geo.view_deg)
    scale = display_exposure(lab)
    assert scale < 1.0  # panel B near specular is brighter than white
    img = lab_picture(lab, scale)
    h, w = img.shape[:2]
    assert np.abs(img[h // 2, w // 2] - img[h // 2, w // 2 - 1]).max() > 0.05
    cap = geometry_caption(r, 0)
    assert cap.startswith("light 45°, view -30° (aspecular 15° on A, 5° on B), β = +5°")
    assert f"seam ΔE {r.seam_de[0]:.2f}" in cap
