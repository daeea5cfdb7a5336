"""Candidate recipes ranked by metamerism index (station.formulate.metamerism).

The index is checked against colour-science's own computation from the same spectra (ASTM E308
tristimulus, CIELAB relative to each illuminant's white, CIEDE2000, additive correction from D65),
and the ranking against a constructed metameric pair: a candidate equal to the standard under D65
but not under A ranks below a non-metameric candidate that matches D65 less well.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import colour
import numpy as np
import pytest
from numpy.typing import NDArray

from station.formulate.demo import demo_library
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import formulate_from_library
from station.formulate.metamerism import Candidate, rank_candidates, rank_formulation
from station.model.spectra import WAVELENGTHS, weighting_factors
from tests.user_cli import run_station

ANGLES = (15.0, 45.0, 110.0)
_CS = {"D65": "D65", "A": "A", "F11": "FL11"}
_CMFS = "CIE 1964 10 Degree Standard Observer"


def _lab_cs(r: NDArray[np.float64], illuminant: str) -> NDArray[np.float64]:
    """Lab of reflectance rows under *illuminant* computed by colour-science alone (white Y = 1)."""
    shape = colour.SpectralShape(400, 700, 10)
    cmfs = colour.MSDS_CMFS[_CMFS]
    ill = colour.SDS_ILLUMINANTS[_CS[illuminant]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        white = colour.sd_to_XYZ(
            colour.SpectralDistribution(dict(zip(WAVELENGTHS, np.ones(31), strict=True))),
            cmfs,
            ill,
            method="ASTM E308",
            shape=shape,
        )
        out = []
        for row in np.atleast_2d(r):
            sd = colour.SpectralDistribution(dict(zip(WAVELENGTHS, row, strict=True)))
            xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308", shape=shape)
            out.append(colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xy(white)))
    return np.asarray(out)


def _mi_cs(ref: NDArray[np.float64], smp: NDArray[np.float64], ill: str) -> NDArray[np.float64]:
    """CIE special metamerism index by colour-science: additive Lab correction from D65, then ΔE00."""
    corr = _lab_cs(smp, "D65") - _lab_cs(ref, "D65")
    return np.asarray(colour.delta_E(_lab_cs(ref, ill), _lab_cs(smp, ill) - corr, method="CIE 2000"))


def _standard() -> NDArray[np.float64]:
    """A smooth blue-ish reflectance per geometry (face brighter than flop)."""
    base = 0.25 + 0.15 * np.cos((WAVELENGTHS - 450.0) / 60.0)
    return np.stack([1.4 * base, base, 0.5 * base])


def _metameric_black() -> NDArray[np.float64]:
    """A spectrum with zero XYZ under D65 (null space of the D65 weights), rippling across the range."""
    w = weighting_factors("D65")
    ripple = np.sin(WAVELENGTHS / 12.0)
    q, _ = np.linalg.qr(w)
    black = ripple - q @ (q.T @ ripple)
    return black / np.max(np.abs(black))


def test_a_metameric_pair_ranks_below_a_non_metameric_candidate() -> None:
    ref = _standard()
    metameric = ref + 0.9 * ref.min(axis=1, keepdims=True) * _metameric_black()  # equal under D65, not A
    near = ref * 1.01  # slightly lighter at every wavelength: little metamerism
    assert np.all(metameric >= 0)
    de_d65 = colour.delta_E(_lab_cs(ref, "D65"), _lab_cs(metameric, "D65"), method="CIE 2000")
    assert np.max(de_d65) < 1e-6
    assert np.min(_mi_cs(ref, metameric, "A")) > 0.5
    de_near = colour.delta_E(_lab_cs(ref, "D65"), _lab_cs(near, "D65"), method="CIE 2000")
    cands = [
        Candidate("metameric", {"x": 1.0}, metameric, tuple(float(v) for v in de_d65), True),
        Candidate("near", {"y": 1.0}, near, tuple(float(v) for v in de_near), True),
    ]
    ranking = rank_candidates(ref, cands, ANGLES, ["A", "F11"])
    assert [r.candidate.label for r in ranking.ranked] == ["near", "metameric"]
    for r in ranking.ranked:
        smp = r.candidate.reflectance
        for ill in ("A", "F11"):
            np.testing.assert_allclose(r.index[ill], _mi_cs(ref, smp, ill), atol=1e-6)
        worst = max(max(_mi_cs(ref, smp, ill)) for ill in ("A", "F11"))
        assert r.worst_index == pytest.approx(worst, abs=1e-6)
    # the same pair without the illuminant rule: the metameric candidate matches D65 better
    assert ranking.ranked[1].candidate.mean_de < ranking.ranked[0].candidate.mean_de


def test_ties_in_the_index_fall_back_to_the_d65_match_and_unformulable_ranks_last() -> None:
    ref = _standard()
    a = Candidate("a", {}, ref * 1.02, (0.5, 0.5, 0.5), True)
    b = Candidate("b", {}, ref * 1.02, (0.2, 0.2, 0.2), True)  # same spectra: same index, better ΔE
    c = Candidate("c", {}, ref, (0.0, 0.0, 0.0), False)  # index 0 but not formulable
    ranked = rank_candidates(ref, [a, b, c], ANGLES, ["A"]).ranked
    assert [r.candidate.label for r in ranked] == ["b", "a", "c"]
    assert [r.rank for r in ranked] == [1, 2, 3]


@pytest.mark.parametrize("names", [["D65"], ["Z9"], []])
def test_bad_illuminant_lists_are_refused_naming_the_field(names: list[str]) -> None:
    ref = _standard()
    with pytest.raises(FormulateInputError, match=r"^illuminants"):
        rank_candidates(ref, [Candidate("a", {}, ref, (0.0,) * 3, True)], ANGLES, names)


def test_a_formulation_ranks_its_distinct_candidates() -> None:
    lab = np.array([[60.0, 10.0, -30.0], [45.0, 8.0, -25.0], [30.0, 5.0, -18.0]])
    result, _ = formulate_from_library(lab, demo_library(), candidates=3)
    assert len(result.candidates) >= 3
    assert np.array_equal(result.candidates[0][1], result.concentrations)  # the winner first
    ranking = rank_formulation(result, ["A", "F11"])
    assert len(ranking.ranked) == len(result.candidates)
    keys = [(not r.candidate.formulable, round(r.worst_index, 2)) for r in ranking.ranked]
    assert keys == sorted(keys)
    ref = np.asarray(ranking.ranked[0].candidate.reflectance)
    assert ref.shape == (3, 31)


def test_cli_ranks_by_illuminants_and_refuses_an_unknown_one(tmp_path: Path) -> None:
    design = "60,10,-30;45,8,-25;30,5,-18"
    r = run_station(tmp_path, "formulate", design, "--illuminants", "A,F11", "--candidates", "3", "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    ranking = out["metamerism_ranking"]
    assert ranking["illuminants"] == ["A", "F11"] and ranking["reference_illuminant"] == "D65"
    ranks = ranking["candidates"]
    assert [c["rank"] for c in ranks] == list(range(1, len(ranks) + 1)) and len(ranks) >= 3
    for c in ranks:
        assert set(c["metamerism_index"]) == {"A", "F11"}
        assert c["worst_index"] == pytest.approx(max(c["max_index"].values()))
    formulable = [c["worst_index"] for c in ranks if c["formulable"]]
    assert [round(v, 2) for v in formulable] == sorted(round(v, 2) for v in formulable)
    bad = run_station(tmp_path, "formulate", design, "--illuminants", "A,Q7")
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == [bad.stderr.strip()]
    assert "illuminants[1]" in bad.stderr and "Q7" in bad.stderr


def _write_lamp(path: Path) -> None:
    """Illuminant A's SPD (colour-science's table, 400–700 nm) as a lab's lamp file."""
    sd = colour.SDS_ILLUMINANTS["A"]
    rows = [f"{w:g},{sd[w]:.6f}" for w in range(380, 781, 5)]
    path.write_text("wavelength_nm,value\n" + "\n".join(rows) + "\n")


def test_a_lamp_file_ranks_as_its_spd(tmp_path: Path) -> None:
    from station.formulate.metamerism import chosen_illuminants

    _write_lamp(tmp_path / "lamp.csv")
    (lamp,) = chosen_illuminants([str(tmp_path / "lamp.csv")], allow_files=True)
    ref = _standard()
    cands = [
        Candidate("m", {}, ref + 0.9 * ref.min(axis=1, keepdims=True) * _metameric_black(), (0.0,) * 3, True)
    ]
    by_file = rank_candidates(ref, cands, ANGLES, [lamp]).best
    by_name = rank_candidates(ref, cands, ANGLES, ["A"]).best
    assert by_file.index["lamp"] == pytest.approx(by_name.index["A"], abs=1e-4)  # the file: 6 decimals
    with pytest.raises(FormulateInputError, match=r"^illuminants\[0\]"):
        chosen_illuminants([str(tmp_path / "lamp.csv")])  # files only where allowed (the CLI)


def test_cli_takes_a_lamp_file_and_refuses_a_bad_one(tmp_path: Path) -> None:
    _write_lamp(tmp_path / "lamp.csv")
    (tmp_path / "bad.csv").write_text("wavelength_nm,value\n500,1\n")
    design = "60,10,-30;45,8,-25;30,5,-18"
    r = run_station(
        tmp_path, "formulate", design, "--illuminants", "lamp.csv,F11", "--candidates", "2", "--json"
    )
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["metamerism_ranking"]["illuminants"] == ["lamp", "F11"]
    bad = run_station(tmp_path, "formulate", design, "--illuminants", "bad.csv")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "bad.csv" in bad.stderr
