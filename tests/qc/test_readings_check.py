"""Readings from measure/import JSON and the verdict of a sample against its standard (check_pair)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from station.errors import InputError
from station.qc.check import check_pair
from station.qc.errors import QcInputError
from station.qc.readings import Reading, load_readings, reading_from_dict
from station.qc.tolerance import ToleranceSet
from tests.model.test_din6175 import _by_hand

STD = [[90.0, 1.0, -2.0], [50.0, 2.0, -3.0], [30.0, 3.0, -4.0]]
SMP = [[90.5, 1.0, -2.0], [50.0, 2.5, -3.2], [31.2, 3.0, -4.0]]
GEOMS = ["45as15", "45as45", "45as110"]


def _measure(lab: list[list[float]], geoms: list[str] = GEOMS, **kw: object) -> dict[str, object]:
    """An object shaped like `station measure --json` output (extra keys the reader ignores)."""
    return {
        "device": "sim:ma6",
        "model": "MA6",
        "serial": "600123",
        "geometries": geoms,
        "lab": lab,
        "temperature_c": 24.0,
        "time": "2026-12-01T08:00:00+00:00",
        "panel": None,
        **kw,
    }


def test_measure_and_import_shapes(tmp_path: Path) -> None:
    r = reading_from_dict(_measure(STD))
    assert r.aspecular_deg == (15.0, 45.0, 110.0) and r.geometries == tuple(GEOMS)
    assert r.instrument == "MA6 600123" and r.measured_at is not None and r.measured_at.hour == 8
    f = tmp_path / "import.json"
    f.write_text(
        json.dumps(
            {
                "measurements": [
                    {
                        "geometries": GEOMS,
                        "lab": STD,
                        "instrument": {"model": "BYK", "serial": "9"},
                        "sample": "A",
                    },
                    {"geometries": [15, 45, 110], "lab": SMP, "instrument": "X", "sample": "B"},
                ]
            }
        )
    )
    a, b = load_readings(f)
    assert (a.instrument, a.sample, b.sample) == ("BYK 9", "A", "B")
    assert b.aspecular_deg == (15.0, 45.0, 110.0)


@pytest.mark.parametrize(
    ("data", "field"),
    [
        (_measure(STD, ["45as15", "45as15", "45as110"]), "reading.geometries"),
        (_measure(STD, ["15as15", "15as45", "15as110"]), "reading.geometries"),
        (_measure(STD[:2]), "reading.lab"),
        (_measure([[90.0, 1.0], *STD[1:]]), "reading.lab"),
        (_measure([[250.0, 0.0, 0.0], *STD[1:]]), "reading.lab[0].L"),
        (_measure(STD, time="yesterday"), "reading.time"),
        ({"geometries": [], "lab": []}, "reading.geometries"),
    ],
    ids=["duplicate", "illumination", "count", "pair", "bound", "time", "gloss-only"],
)
def test_bad_readings_name_the_field(data: dict[str, object], field: str) -> None:
    with pytest.raises(QcInputError) as err:
        reading_from_dict(data)
    assert err.value.field == field
    assert isinstance(err.value, InputError)


def test_bad_files_name_the_file(tmp_path: Path) -> None:
    nan = tmp_path / "nan.json"
    nan.write_text('{"geometries": ["45as15"], "lab": [[NaN, 0, 0]]}')
    with pytest.raises(QcInputError, match="NaN"):
        load_readings(nan)
    junk = tmp_path / "junk.txt"
    junk.write_text("CGATS.17\n")
    with pytest.raises(InputError, match=r"junk\.txt"):  # not JSON: the importers' error, or ours
        load_readings(junk)
    with pytest.raises(QcInputError, match=r"missing\.json"):
        load_readings(tmp_path / "missing.json")


def test_other_illuminations_are_left_out_and_other_conditions_need_spectra() -> None:
    two_blocks = _measure(
        [STD[0], STD[1], [10.0, 0.0, 0.0], STD[2]], ["45as15", "45as45", "15as45", "45as110"]
    )
    r = reading_from_dict(two_blocks)
    assert r.geometries == tuple(GEOMS) and [list(x) for x in r.lab] == STD
    with pytest.raises(QcInputError, match="D50") as err:
        reading_from_dict(_measure(STD, illuminant="D50"))
    assert err.value.field == "reading.illuminant"
    flat = [[0.18] * 31] * 3
    d50 = reading_from_dict(
        _measure(STD, illuminant="D50", spectra=flat, wavelengths_nm=list(range(400, 701, 10)))
    )
    assert d50.lab[0][0] == pytest.approx(116 * 0.18 ** (1 / 3) - 16, abs=1e-3)  # D65 Lab of the spectra
    same = reading_from_dict(_measure(STD, illuminant="D65", observer="CIE 1964 10 Degree Standard Observer"))
    assert [list(x) for x in same.lab] == STD


def test_spectra_without_lab_give_the_lab_of_the_spectra() -> None:
    flat = [[0.18] * 31, [0.18] * 31]
    r = reading_from_dict(
        {"geometries": ["45as15", "45as45"], "spectra": flat, "wavelengths_nm": list(range(400, 701, 10))}
    )
    # a flat 18 % reflector: Y = 0.18, L* = 116·0.18^(1/3) − 16, a* = b* = 0 (any illuminant's white)
    expected_l = 116 * 0.18 ** (1 / 3) - 16
    assert r.lab[0][0] == pytest.approx(expected_l, abs=1e-3)
    assert abs(r.lab[0][1]) < 1e-3 and abs(r.lab[0][2]) < 1e-3
    assert r.has_product_spectra()


def test_check_pair_din_and_cie76_by_hand() -> None:
    std, smp = reading_from_dict(_measure(STD)), reading_from_dict(_measure(SMP))
    v = check_pair(std, smp, formula="din6175-2")
    hand = [_by_hand(r, s, a)[0] for r, s, a in zip(STD, SMP, (15, 45, 110), strict=True)]
    assert [g.de for g in v.per_geometry] == pytest.approx(hand, rel=1e-12)
    assert v.formula == "din6175" and v.worst_geometry == "45as110" and v.max_de == pytest.approx(max(hand))
    # 1.2 ΔL* at 110° on a grey: L̄ = √(30·31.2) = 30.594, S_L = 0.15·√30.594 + 31.5/110 = 1.1160,
    # ΔE = 1.2 / 1.1160 = 1.0753 > 1: fail
    assert max(hand) == pytest.approx(1.2 / (0.15 * math.sqrt(math.sqrt(30 * 31.2)) + 31.5 / 110), rel=1e-9)
    assert max(hand) == pytest.approx(1.0753, abs=1e-4) and v.verdict == "fail"
    v76 = check_pair(std, smp, formula="cie76")
    e76 = [math.dist(r, s) for r, s in zip(STD, SMP, strict=True)]
    assert [g.de for g in v76.per_geometry] == pytest.approx(e76, rel=1e-12)
    assert v76.per_geometry[2].verdict == "fail"  # ΔE*ab 1.2 > 1
    assert v76.per_geometry[1].verdict == "pass"  # √(0.25 + 0.04) = 0.539 <= 0.8


def test_check_pair_with_a_tolerance_set_judges_its_geometries_only() -> None:
    std = reading_from_dict(_measure(STD))
    smp = reading_from_dict(_measure(SMP))
    tol = ToleranceSet.uniform([15.0, 45.0], de=0.6, formula="cie76")
    v = check_pair(std, smp, tol)
    assert [g.geometry for g in v.per_geometry] == ["45as15", "45as45"]
    # 45as15: ΔE*ab 0.5 (warn, over 0.8 · 0.6 = 0.48); 45as45: 0.539 (warn)
    assert [g.verdict for g in v.per_geometry] == ["warn", "warn"] and v.verdict == "warn"
    # the formula option overrides the set's: CIEDE2000 of the same pair differs from ΔE*ab
    assert check_pair(std, smp, tol, "cie2000").formula == "cie2000"


def test_a_missing_geometry_is_an_error_not_a_pass() -> None:
    std = reading_from_dict(_measure(STD))
    smp = reading_from_dict(_measure(SMP[:2], GEOMS[:2]))
    with pytest.raises(QcInputError, match="missing 45as110") as err:
        check_pair(std, smp)
    assert err.value.field == "sample.geometries"
    with pytest.raises(InputError, match="formula"):
        check_pair(std, std, formula="cie1492")
    with pytest.raises(InputError, match="AUDI2000"):
        check_pair(std, std, formula="audi2000")


def test_reading_refuses_bad_states() -> None:
    with pytest.raises(QcInputError, match="spectra"):
        Reading(
            (15.0,), ((50.0, 0.0, 0.0),), spectra=((0.1,) * 30,), wavelengths_nm=tuple(range(400, 701, 10))
        )
    with pytest.raises(QcInputError, match="wavelengths_nm"):
        Reading((15.0,), ((50.0, 0.0, 0.0),), spectra=((0.1,) * 31,))
