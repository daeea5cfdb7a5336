"""``station.formulate.export``: what every front exports for a design, checked against a brute-force scan."""

from __future__ import annotations

import numpy as np
import pytest

from station.formulate.export import export_specs, spec_from_library
from station.formulate.library import Library
from station.formulate.snap import SnapIndex
from station.model import ANGLES_3, ANGLES_3_ALT, FaceFlopTravelGloss

SILVER = FaceFlopTravelGloss((125.0, 0.0, 2.0), (40.0, 0.0, 1.0), 38.0, 90.0, "bright silver")


def _nearest(library: Library, design: FaceFlopTravelGloss, method: str) -> int:
    """Row of the smallest ΔE summed over 15°/45°/110°, by a plain loop over every paint."""
    from station.model.difference import delta_e

    target = np.asarray(design.lab_at(np.asarray(ANGLES_3)))
    cols = library.angle_columns(ANGLES_3)
    sums = [float(delta_e(target, cols[i], method).sum()) for i in range(len(library))]
    return int(np.argmin(sums))


def test_design_only_without_a_library() -> None:
    specs, code = export_specs(SILVER)
    assert code is None
    assert [s.role for s in specs] == ["design"]
    assert [s.angles_deg for s in specs[0].sets] == [ANGLES_3, ANGLES_3_ALT]
    assert specs[0].name == "bright silver"


@pytest.mark.parametrize("method", ["cie76", "cie2000"])
def test_match_is_the_brute_force_nearest_paint(small_library: Library, method: str) -> None:
    row = _nearest(small_library, SILVER, method)
    specs, code = export_specs(SILVER, small_library, method=method, five_angles=True)
    assert code == str(small_library.codes[row])
    design, match = specs
    assert design.role == "design" and match.role == "match"
    assert match.code == code and match.name == code
    assert match.synthetic == small_library.synthetic
    assert match.gloss_gu == pytest.approx(float(small_library.gloss_gu[row]))
    first = match.sets[0]
    assert first.angles_deg == ANGLES_3
    np.testing.assert_array_equal(first.lab, small_library.angle_columns(ANGLES_3)[row])


def test_prebuilt_index_gives_the_same_match(small_library: Library) -> None:
    plain = export_specs(SILVER, small_library)[1]
    indexed = export_specs(SILVER, small_library, index=SnapIndex(small_library))[1]
    assert plain == indexed


def test_spec_from_library_carries_every_standard_set_present(small_library: Library) -> None:
    spec = spec_from_library(small_library, 0)
    present = set(small_library.angles_deg)
    expected = [s for s in (ANGLES_3, ANGLES_3_ALT) if set(s) <= present]
    assert [s.angles_deg for s in spec.sets] == expected
    assert spec.paint_type == str(small_library.types[0])
