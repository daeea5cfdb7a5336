"""The bright silver (L*15 = 125) through ColorSnap, formulation and the XML / CxF exchange files.

Snap is checked against a brute-force sum of ΔE over every paint; the formulation's reported ΔE
against the colorant model's own prediction of the recipe; the exports by reading them back.
"""

from __future__ import annotations

import numpy as np
import pytest

from station.formulate.color_xml import colors_to_xml, read_color_xml, spec_from_design
from station.formulate.colorants import predict_lab
from station.formulate.cxf import read_cxf_specs, specs_to_cxf
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import formulate_from_library
from station.formulate.library import Library
from station.formulate.snap import color_snap, validate_design_lab
from station.model import ANGLES_3, ANGLES_3_ALT, FaceFlopTravelGloss
from station.model.difference import delta_e


def test_snap_equals_brute_force(bright_silver: FaceFlopTravelGloss, small_library: Library) -> None:
    lab = bright_silver.lab_at(np.array(ANGLES_3))
    result = color_snap(small_library, lab, k=3, method="cie2000")
    paints = small_library.angle_columns(ANGLES_3)
    sums = delta_e(lab[None], paints, "cie2000").sum(-1)
    order = np.argsort(sums, kind="stable")[:3]
    assert [m.index for m in result.matches] == order.tolist()
    assert [m.sum_de for m in result.matches] == pytest.approx(sums[order].tolist(), rel=1e-9)


def test_formulation_request(bright_silver: FaceFlopTravelGloss, small_library: Library) -> None:
    lab = bright_silver.lab_at(np.array(ANGLES_3))
    result, snap = formulate_from_library(lab, small_library, gloss_gu=bright_silver.gloss_gu)
    assert result.design_lab[0, 0] == 125.0  # the L* above 100 reaches the formulator unclipped
    recomputed = delta_e(lab, predict_lab(result.concentrations, ANGLES_3), "cie2000")
    np.testing.assert_allclose(result.de_per_angle, recomputed, atol=1e-9)
    assert result.formulable == (result.mean_de <= result.tolerance)
    assert result.start in {m.code for m in snap.matches} | {"generic"}


def test_xml_and_cxf_round_trip(bright_silver: FaceFlopTravelGloss) -> None:
    spec = spec_from_design(bright_silver, five_angles=True)
    for back in (read_color_xml(colors_to_xml([spec]))[0], read_cxf_specs(specs_to_cxf([spec]))[0]):
        assert back.gloss_gu == 90.0
        by_angles = {s.angles_deg: s for s in back.sets}
        assert set(by_angles) >= {ANGLES_3, ANGLES_3_ALT}
        for angles, s in by_angles.items():
            np.testing.assert_allclose(s.lab, bright_silver.lab_at(np.array(angles)), atol=1e-4)
        assert by_angles[ANGLES_3].lab[0, 0] == pytest.approx(125.0, abs=1e-4)


def test_out_of_range_names_field_and_range() -> None:
    with pytest.raises(FormulateInputError) as err:
        validate_design_lab([[250.0, 0.0, 0.0], [50.0, 0.0, 0.0], [38.0, 0.0, 0.0]])
    assert err.value.field == "lab.L" and "0 <= L* <= 200" in err.value.accepted
