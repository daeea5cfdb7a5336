"""Quantity verdicts, the reason rule, and the 30 % rule over every fast experiment's tolerances."""

from __future__ import annotations

import math

import pytest

from station.reproduce import Quantity, ReproduceError, ReproduceInputError
from station.reproduce.registry import EXPERIMENTS, select


def test_verdict_within_tolerance_by_mode() -> None:
    assert Quantity("x", "q", "1", 2.0, 2.4, 0.5).verdict == "agrees"
    assert Quantity("x", "q", "1", 2.0, 2.6, 0.5, reason="r").verdict == "differs"
    assert Quantity("x", "q", "ms", 33.3, 0.5, 0.0, mode="at_most").verdict == "agrees"
    assert Quantity("x", "q", "ms", 33.3, 40.0, 0.0, mode="at_most", reason="slow").verdict == "differs"
    assert Quantity("x", "q", "%", 96.0, 99.2, 0.0, mode="at_least").verdict == "agrees"
    assert Quantity("x", "q", "%", 96.0, 90.0, 0.0, mode="at_least", reason="r").verdict == "differs"
    q = Quantity("x", "q", "1", 2.0, 1.5, 1.0)
    assert q.difference == pytest.approx(-0.5)
    assert q.to_dict()["reason"] is None


def test_a_difference_without_a_reason_is_refused() -> None:
    with pytest.raises(ReproduceError, match="no reason is documented"):
        Quantity("4.5", "Δ travel", "deg", 2.0, 4.2, 0.5)


def test_bad_numbers_are_refused_naming_the_field() -> None:
    with pytest.raises(ReproduceError, match="not a finite number"):
        Quantity("x", "q", "1", math.nan, 1.0, 0.1)
    with pytest.raises(ReproduceInputError, match="tolerance"):
        Quantity("x", "q", "1", 1.0, 1.0, -0.1)
    with pytest.raises(ReproduceInputError, match="mode"):
        Quantity("x", "q", "1", 1.0, 1.0, 0.1, mode="near")  # type: ignore[arg-type]


def test_unknown_figure_names_the_accepted_ids() -> None:
    with pytest.raises(ReproduceInputError, match=r"figure: expected one of .*4\.4"):
        select("9.99")
    assert [e.key for e in select("4.4")] == ["ch4-fig4.4"]
    assert all(not e.slow for e in select(None, include_slow=False))
    assert any(e.slow for e in EXPERIMENTS)


def test_every_tolerance_fails_a_30_percent_miss() -> None:
    """A stated tolerance must not let a 30 % miss of a non-zero thesis value pass as agreement."""
    from station.reproduce import ch3, ch4, gloss

    results = [
        f(None) for f in (ch3.representations, ch4.lambertian_index, ch4.figs45_47, gloss.meter_geometries)
    ]
    checked = 0
    for r in results:
        for q in r.quantities:
            if q.mode != "within" or q.thesis == 0:
                continue
            checked += 1
            assert q.tolerance < 0.3 * abs(q.thesis), (q.figure, q.quantity)
    assert checked >= 10


def test_selection_names_and_quick_variants() -> None:
    assert select("Fig. 4.4") == select("4.4") == select("ch4-fig4.4")
    assert [e.key for e in select("§2.4")] == ["ch2-fit-methods"]
    full = [e.key for e in select("2.4")]
    assert full == ["ch2-basis"]  # the quick variant is left out when the full search runs
    assert [e.key for e in select("2.4", include_slow=False)] == ["ch2-basis-quick"]
    with pytest.raises(ReproduceInputError):
        select("3.20", include_slow=False)  # only a slow experiment reproduces it
