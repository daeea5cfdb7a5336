"""Gloss as data: "not measured" travels from the fit through the design file and the seam QA to the
formulation input, where it means full gloss (no matting agent for a gloss nobody measured)."""

from __future__ import annotations

import numpy as np

from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.design_io import design_from_dict, design_to_dict
from station.model.domain import DEFAULT_GLOSS_GU
from station.model.fit import fit_fftg_batch

ANGLES = (15.0, 45.0, 110.0)
LAB = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])


def test_fit_without_gloss_says_not_measured():
    r = fit_fftg(AspecularMeasurements(ANGLES, LAB, None))
    assert r.design.gloss_measured is False
    assert r.design.gloss_gu == DEFAULT_GLOSS_GU  # rendering still has a gloss
    assert r.design.gloss_target_gu is None  # ... but nothing to formulate to
    assert any("gloss not measured" in w for w in r.warnings)


def test_fit_with_gloss_is_measured_even_at_the_default_value():
    r = fit_fftg(AspecularMeasurements(ANGLES, LAB, DEFAULT_GLOSS_GU))
    assert r.design.gloss_measured is True
    assert r.design.gloss_target_gu == DEFAULT_GLOSS_GU
    assert not any("gloss" in w for w in r.warnings)


def test_batch_fit_carries_the_state_to_every_paint():
    lab = np.stack([LAB, LAB + [0.0, 1.0, 1.0]])
    unmeasured = fit_fftg_batch(ANGLES, lab)
    measured = fit_fftg_batch(ANGLES, lab, [88.0, 20.0])
    assert [unmeasured.result(i).design.gloss_target_gu for i in range(2)] == [None, None]
    assert [measured.result(i).design.gloss_target_gu for i in range(2)] == [88.0, 20.0]


def test_design_file_writes_null_for_not_measured_and_reads_it_back():
    d = fit_fftg(AspecularMeasurements(ANGLES, LAB, None)).design
    data = design_to_dict(d)
    assert data["gloss_gu"] is None
    back = design_from_dict(data)
    assert back.gloss_measured is False and back.gloss_gu == DEFAULT_GLOSS_GU
    typed = design_from_dict({**data, "gloss_gu": 88.0})
    assert typed.gloss_measured is True and typed.gloss_target_gu == 88.0


def test_replace_keeps_the_state_until_a_gloss_is_typed():
    d = FaceFlopTravelGloss((90, 2, -5), (30, 0.5, -1), 75.0, gloss_measured=False)
    assert d.replace(name="B'").gloss_measured is False
    assert d.replace(gloss_gu=88.0, gloss_measured=True).gloss_target_gu == 88.0
