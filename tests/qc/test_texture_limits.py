"""Texture limits are refused at the boundary by the same rules as the colour tolerance's."""

from __future__ import annotations

import pytest

from station.model.domain import QC_WARN_FRACTION_RANGE
from station.qc.errors import QcInputError
from station.qc.texture import TextureTolerance
from station.qc.tolerance import ToleranceSet


@pytest.mark.parametrize("fraction", [True, float("nan"), 0.0, 1.5])
def test_warn_fraction_refused_like_the_colour_tolerance(fraction: float) -> None:
    with pytest.raises(QcInputError) as info:
        TextureTolerance(ds=1.0, warn_fraction=fraction)
    assert info.value.field == "texture_limits.warn_fraction"
    with pytest.raises(ValueError):  # the colour tolerance refuses the same value
        ToleranceSet.uniform([15.0], warn_fraction=fraction)


@pytest.mark.parametrize("name", ["ds", "dg"])
def test_a_boolean_limit_is_refused(name: str) -> None:
    with pytest.raises(QcInputError) as info:
        TextureTolerance(**{name: True})
    assert info.value.field == f"texture_limits.{name}"


def test_the_whole_warn_range_is_accepted() -> None:
    lo, hi = QC_WARN_FRACTION_RANGE
    assert TextureTolerance(ds=1.0, warn_fraction=hi).warn_fraction == hi
    assert TextureTolerance(ds=1.0, warn_fraction=(lo + hi) / 2).warn_fraction == (lo + hi) / 2


def test_rows_of_names_differing_in_case_come_in_one_order() -> None:
    # "Sparkle_k" (a CxF spelling) and "sparkle_k" (a CGATS one) never pair; their rows are listed by
    # name, case-insensitively, then exactly (upper case first), whatever the string hashes of the run
    from station.qc.texture import TextureValue, judge_texture

    std = tuple(TextureValue("BYK", f"Sparkle_{k}", "45as15", 1.0) for k in range(12))
    smp = tuple(TextureValue("BYK", f"sparkle_{k}", "45as15", 1.0) for k in range(12))
    rows = judge_texture(std, smp, TextureTolerance(ds=1.0)).rows
    expected = sorted([v.name for v in std + smp], key=lambda n: (n.lower(), n))
    assert [r.name for r in rows] == expected
