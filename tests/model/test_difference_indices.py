"""ΔE methods (published values) and library indices (hand values, failure regions)."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.difference import delta_e, delta_e_aggregate, validate_method
from station.model.errors import ModelInputError
from station.model.indices import library_indices

# Sharma, Wu & Dalal (2005), Table 1: pairs 1, 7, 17 with their published ΔE00.
SHARMA = [
    ((50.0000, 2.6772, -79.7751), (50.0000, 0.0000, -82.7485), 2.0425),
    ((50.0000, 0.0000, 0.0000), (50.0000, -1.0000, 2.0000), 2.3669),
    ((50.0000, 2.5000, 0.0000), (73.0000, 25.0000, -18.0000), 27.1492),
]


@pytest.mark.parametrize(("a", "b", "expected"), SHARMA)
def test_ciede2000_sharma(a, b, expected) -> None:
    assert delta_e(a, b, "cie2000") == pytest.approx(expected, abs=1e-4)


def test_cie76_closed_form() -> None:
    assert delta_e([50, 0, 0], [53, 4, 0], "cie76") == pytest.approx(5.0)


def test_vectorised_per_angle_and_aggregates() -> None:
    ref = np.array([[90, 1, 1], [50, 1, 1], [30, 1, 1]], float)
    smp = ref + [[3, 4, 0], [0, 0, 0], [0, 0, 1]]
    per = delta_e(ref, smp, "cie76")
    assert per == pytest.approx([5, 0, 1])
    assert delta_e_aggregate(ref, smp, "cie76", "mean") == pytest.approx(2.0)
    assert delta_e_aggregate(ref, smp, "cie76", "max") == pytest.approx(5.0)
    assert delta_e_aggregate(ref, smp, "cie76", "rms") == pytest.approx(np.sqrt(26 / 3))
    tiled = delta_e(np.tile(ref, (2, 1, 1)), np.tile(smp, (2, 1, 1)), "cie2000")
    assert tiled.shape == (2, 3) and tiled[0] == pytest.approx(tiled[1])


def test_method_validation() -> None:
    assert validate_method("CIEDE2000") == "cie2000"
    with pytest.raises(ModelInputError, match="one of"):
        delta_e([50, 0, 0], [50, 0, 0], "cmc9")
    with pytest.raises(ModelInputError, match="finite"):
        delta_e([50, 0, np.nan], [50, 0, 0])


def test_flop_index_hand_value() -> None:
    # 2.69 · (70)^1.11 / 60^0.86 = 8.8838… by hand (70^1.11 = 111.58, 60^0.86 = 33.79)
    r = library_indices([100, 0, 0], [60, 0, 0], [30, 0, 0])
    assert r.flop_index == pytest.approx(2.69 * 70**1.11 / 60**0.86, rel=1e-12)
    assert r.flop_index == pytest.approx(8.884, abs=1e-3)


def test_solid_flop_index_zero() -> None:
    r = library_indices([50, 20, 10], [50, 20, 10], [50, 20, 10])
    assert r.flop_index == 0.0 and r.chroma_index == 0.0 and r.hue_shift_index == 0.0


def test_chroma_and_hue_shift_hand_values() -> None:
    # face ab (30, 40): C = 50; flop ab (0, 10): C = 10 → chroma index 40;
    # distance of (0, 10) to the line through (30, 40): |0·40 − 30·10| / 50 = 6
    r = library_indices([80, 30, 40], [50, 10, 20], [30, 0, 10])
    assert r.chroma_index == pytest.approx(40.0)
    assert r.hue_shift_index == pytest.approx(6.0)


def test_failure_regions_detected() -> None:
    inverted = library_indices([30, 0, 0], [40, 0, 0], [50, 0, 0])
    assert inverted.flop_index is None and any("L*15 < L*110" in w for w in inverted.warnings)
    dark = library_indices([15, 0, 0], [5, 0, 0], [2, 0, 0])
    assert dark.flop_index is not None and any("dark colour" in w for w in dark.warnings)
    achromatic = library_indices([80, 0.5, 0.5], [50, 10, 0], [30, 20, 0])
    assert achromatic.hue_shift_index is None and any("achromatic" in w for w in achromatic.warnings)
    rotating = library_indices([80, 30, 0], [50, 0, 0], [30, -30, 5])
    assert any("90°" in w for w in rotating.warnings)


def test_the_formula_table_has_exactly_the_domain_names() -> None:
    """DELTA_E_METHODS implements every name the fronts accept and no other; the computed ones compute."""
    from typing import get_args

    from station.model.difference import DELTA_E_METHODS
    from station.model.domain import DELTA_E_COMPUTED, DELTA_E_METHOD_NAMES, DeltaEComputed

    assert tuple(DELTA_E_METHODS) == DELTA_E_METHOD_NAMES
    assert DELTA_E_COMPUTED == get_args(DeltaEComputed)
    assert set(DELTA_E_COMPUTED) < set(DELTA_E_METHOD_NAMES)
    ref, sample = np.array([[50.0, 10.0, -5.0]]), np.array([[51.0, 9.0, -4.0]])
    for name in DELTA_E_COMPUTED:  # CIE76 of this pair is √3; the others are within a factor 3 of it
        value = float(delta_e(ref, sample, method=name, aspecular_deg=np.array([45.0]))[0])
        assert np.sqrt(3.0) / 3.0 < value < 3.0 * np.sqrt(3.0), name
