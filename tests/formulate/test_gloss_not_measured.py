"""A gloss nobody measured reaches QA and formulation as "not measured": the seam analysis's corrected paint
keeps the state, and formulation keeps the clear coat's full gloss instead of matting to the default."""

from __future__ import annotations

import numpy as np
import pytest

from station.model import AspecularMeasurements, fit_fftg

ANGLES = (15.0, 45.0, 110.0)
LAB = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])


def test_seam_qa_correction_keeps_not_measured():
    from station.analysis.qa import seam_qa
    from station.analysis.trompe import paint_to_dict

    a = fit_fftg(AspecularMeasurements(ANGLES, LAB, None)).design
    b = fit_fftg(AspecularMeasurements(ANGLES, LAB + [1.5, 0.0, 0.0], None)).design
    report = seam_qa(a, b, beta_deg=5.0)
    assert report.correction.paint.gloss_measured is False
    assert paint_to_dict(report.correction.paint)["gloss_gu"] is None


@pytest.mark.parametrize(("gloss", "matted"), [(None, False), (60.0, True)])
def test_formulation_adds_matting_only_for_a_measured_gloss(gloss, matted):
    from station.formulate.colorants import default_database
    from station.formulate.demo import demo_library
    from station.formulate.formulation import formulate_from_library

    design = fit_fftg(AspecularMeasurements(ANGLES, LAB, gloss)).design
    db = default_database()
    result, _ = formulate_from_library(
        design.lab_at(np.array(ANGLES)), demo_library(), gloss_gu=design.gloss_target_gu, db=db
    )
    matting = float(result.concentrations[db.matting_index])
    assert (matting > 0.0) is matted
    if not matted:
        assert result.gloss_gu > 85.0  # the clear coat's full gloss, not the 50 GU default
