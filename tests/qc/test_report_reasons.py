"""The report's one-line reason for a sample that did not pass names every failing check."""

from __future__ import annotations

import datetime as dt

from station.qc.illuminant_rows import IlluminantCheck, IlluminantRow
from station.qc.readings import Reading
from station.qc.report import _why
from station.qc.results import MeasurementRow, SampleResult
from station.qc.texture import TextureTolerance, TextureValue, judge_texture
from station.qc.tolerance import ToleranceSet, judge

_LAB = ((50.0, 10.0, 10.0),)


def _sample(illuminant_index: float, sparkle_delta: float) -> SampleResult:
    reading = Reading((15.0,), _LAB, sample="panel 7")
    row = MeasurementRow(1, 7, "J1", "door", "sim 1", "ann", dt.datetime(2026, 1, 1, tzinfo=dt.UTC), reading)
    colour = judge(_LAB, _LAB, [15.0], ToleranceSet.uniform([15.0], de=1.0))  # identical: ΔE 0, pass
    booth = IlluminantCheck(
        "cie2000", {"A": 1.0}, (IlluminantRow("A", "45as15", 15.0, illuminant_index, 1.0),)
    )
    std = (TextureValue("BYK", "sparkle_grade", "45as15", 2.0),)
    smp = (TextureValue("BYK", "sparkle_grade", "45as15", 2.0 + sparkle_delta),)
    tex = judge_texture(std, smp, TextureTolerance(ds=1.0))
    return SampleResult(row, colour, illuminants=booth, texture=tex)


def test_illuminant_fail_is_named_when_texture_also_warns() -> None:
    # colour passes, MI under A 1.50 > 1 fails, sparkle +0.90 is in the warn band (0.8 × 1 < 0.9 <= 1)
    s = _sample(illuminant_index=1.5, sparkle_delta=0.9)
    assert s.overall == "fail"
    line = _why(s)
    assert "A 45as15 MI 1.50 > 1" in line
    assert "sparkle_grade" in line


def test_texture_warn_is_named_when_illuminants_fail_only_there() -> None:
    # texture fails, illuminant rows pass: the texture row is the reason
    s = _sample(illuminant_index=0.5, sparkle_delta=-1.5)
    assert s.overall == "fail"
    line = _why(s)
    assert "sparkle_grade 45as15 ΔS -1.50" in line
    assert "MI" not in line


def test_texture_fail_is_named_when_colour_only_warns() -> None:
    # ΔL* 0.9 against ΔE limit 1 with the default warn band: colour warns; sparkle -1.5 fails
    s = _sample(illuminant_index=0.5, sparkle_delta=-1.5)
    lab_smp = ((50.9, 10.0, 10.0),)
    colour = judge(_LAB, lab_smp, [15.0], ToleranceSet.uniform([15.0], de=1.0, formula="cie76"))
    assert colour.verdict == "warn"
    s = SampleResult(s.row, colour, illuminants=s.illuminants, texture=s.texture)
    line = _why(s)
    assert line.startswith("panel 7, door, J1 fail:")
    assert "warn at 45as15" in line
    assert "sparkle_grade 45as15 ΔS -1.50" in line
