"""A number a parameter of ours was set to meet is reported as "calibrated to the thesis", never "agrees"."""

from __future__ import annotations

from pathlib import Path

from station.reproduce import Quantity
from station.reproduce.core import CALIBRATED, ExperimentResult
from station.reproduce.report import markdown, text_table


def test_calibration_overrides_agreement_and_is_stated() -> None:
    q = Quantity("5.4", "mean", "1", 11.38, 11.38, 1.5, calibration="alpha set to meet it")
    assert q.verdict == CALIBRATED == "calibrated to the thesis"
    assert q.to_dict()["calibration"] == "alpha set to meet it" and q.to_dict()["reason"] is None
    far = Quantity("5.4", "mean", "1", 11.38, 20.0, 1.5, calibration="alpha")  # no reason needed either
    assert far.verdict == CALIBRATED
    assert Quantity("5.4", "mean", "1", 11.38, 11.38, 1.5).to_dict()["calibration"] is None


def test_reports_count_calibrated_rows_apart() -> None:
    rows = (
        Quantity("a", "one", "1", 1.0, 1.0, 0.1),
        Quantity("b", "two", "1", 1.0, 1.0, 0.1, calibration="set to meet it"),
    )
    result = ExperimentResult("x", rows)
    text = text_table([result])
    assert "1 of 2 quantities agree" in text and "1 calibrated to the thesis" in text
    assert "→ calibrated to the thesis" in text and "calibration: set to meet it" in text
    md = markdown([], [result], Path("."))
    assert "*calibrated to the thesis*: set to meet it" in md and "1 of 2 quantities agree" in md


def test_the_demo_flop_index_row_says_calibrated() -> None:
    from station.formulate.demo import FLAKE_BLEND_ALPHA, FLOP_INDEX_CALIBRATION
    from station.reproduce import ch5

    q = {x.quantity: x for x in ch5.library_statistics(None).quantities}
    row = q["mean Flop Index, solids excluded"]
    assert row.verdict == CALIBRATED and row.calibration == FLOP_INDEX_CALIBRATION
    assert f"= {FLAKE_BLEND_ALPHA[0]:g}" in FLOP_INDEX_CALIBRATION and "11.38" in FLOP_INDEX_CALIBRATION
    assert q["effect paints with Flop Index in [0, 20]"].verdict != CALIBRATED  # only the tuned row
