"""The booth comparison (station.qc.booth) against colour-science's own integration, per geometry."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.model.booth import metameric_pair
from station.model.illuminants import Illuminant
from station.model.spectra import reflectance_from_lab
from station.qc.booth import booth_compare, booth_compare_spectra
from station.qc.errors import QcInputError
from station.qc.readings import Reading, reading_from_dict

WL = list(range(400, 701, 10))
ANGLES = (15.0, 45.0, 110.0)
#: A green pearl per geometry, Lab D65 / 10°.
GREEN = [[70.0, -30.0, 12.0], [48.0, -22.0, 8.0], [30.0, -14.0, 5.0]]


def _lab(refl: np.ndarray, illuminant: str) -> np.ndarray:
    """colour-science's Lab (ASTM E308, 10°) relative to the illuminant's own integrated white."""
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11", "TL84": "FL11"}.get(illuminant, illuminant)]
    out = []
    for row in np.atleast_2d(refl):
        sd = colour.SpectralDistribution(dict(zip(WL, row, strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308") / 100
        white = colour.sd_to_XYZ(colour.sd_ones(sd.shape), cmfs, ill, method="ASTM E308") / 100
        out.append(colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white)))
    return np.asarray(out)


@pytest.fixture(scope="module")
def pair() -> tuple[np.ndarray, np.ndarray]:
    return metameric_pair(reflectance_from_lab(GREEN), strength=0.4)


def _reading(spectra: np.ndarray, where: str) -> Reading:
    return reading_from_dict(
        {"geometries": ["45as15", "45as45", "45as110"], "spectra": spectra.tolist(), "wavelengths_nm": WL},
        where,
    )


def test_metameric_pair_in_the_booth(pair: tuple[np.ndarray, np.ndarray]) -> None:
    std, smp = pair
    res = booth_compare(_reading(std, "std"), _reading(smp, "smp"), ("D65", "A", "TL84"))
    doc = res.to_dict()
    assert set(doc) == {"illuminants", "reference"} and doc["reference"] == "D65"
    assert [i["name"] for i in doc["illuminants"]] == ["D65", "A", "TL84"]
    assert set(doc["illuminants"][0]) == {"name", "per_geometry", "mean_de"}
    assert set(doc["illuminants"][0]["per_geometry"][0]) == {
        "geometry",
        "standard_lab",
        "sample_lab",
        "dE00",
        "metamerism_index",
    }
    d65 = res.under("D65")
    assert [g.geometry for g in d65.per_geometry] == ["45as15", "45as45", "45as110"]
    assert all(g.de00 < 1e-6 and g.metamerism_index == 0.0 for g in d65.per_geometry)
    for name in ("A", "TL84"):
        lab_std, lab_smp = _lab(std, name), _lab(smp, name)
        expected = colour.delta_E(lab_std, lab_smp, method="CIE 2000")
        rows = res.under(name).per_geometry
        assert [g.de00 for g in rows] == pytest.approx(expected, abs=1e-6)
        # no mismatch under D65, so the index (additive correction from D65) is the plain difference
        assert [g.metamerism_index for g in rows] == pytest.approx(expected, abs=1e-6)
        assert np.array([g.standard_lab for g in rows]) == pytest.approx(lab_std, abs=1e-6)
        assert np.array([g.sample_lab for g in rows]) == pytest.approx(lab_smp, abs=1e-6)
        assert res.under(name).mean_de == pytest.approx(float(np.mean(expected)), abs=1e-9)
    assert all(g.de00 > 0.5 for g in res.under("A").per_geometry)


def test_index_with_a_mismatch_under_the_reference(pair: tuple[np.ndarray, np.ndarray]) -> None:
    std, smp = pair
    off = np.clip(smp * 1.03, 0, 1)  # off under D65 too
    res = booth_compare_spectra(std, off, ANGLES, ("D65", "A"))
    lab_std_d, lab_smp_d = _lab(std, "D65"), _lab(off, "D65")
    corrected = _lab(off, "A") - (lab_smp_d - lab_std_d)
    expected = colour.delta_E(_lab(std, "A"), corrected, method="CIE 2000")
    assert [g.metamerism_index for g in res.under("A").per_geometry] == pytest.approx(expected, abs=1e-6)
    d65 = colour.delta_E(lab_std_d, lab_smp_d, method="CIE 2000")
    assert [g.de00 for g in res.under("D65").per_geometry] == pytest.approx(d65, abs=1e-6)


def test_user_illuminant_and_2_degree(pair: tuple[np.ndarray, np.ndarray]) -> None:
    std, smp = pair
    flat = Illuminant("flat", (380.0, 780.0), (1.0, 1.0))
    res = booth_compare_spectra(std, smp, ANGLES, ("D65", flat), observer="2")
    assert res.observer == "CIE 1931 2 Degree Standard Observer"
    assert res.under("flat").per_geometry[0].de00 > 0


def test_refusals(pair: tuple[np.ndarray, np.ndarray]) -> None:
    std, _ = pair
    lab_only = Reading(ANGLES, tuple((r[0], r[1], r[2]) for r in GREEN), where="lab_only.json")
    with pytest.raises(QcInputError, match=r"lab_only\.json") as err:
        booth_compare(lab_only, _reading(std, "s"))
    assert "spectra" in str(err.value)
    with pytest.raises(QcInputError, match="illuminant"):
        booth_compare_spectra(std, std, ANGLES, ("D65", "D93"))
    with pytest.raises(QcInputError, match="illuminants"):
        booth_compare_spectra(std, std, ANGLES, ("A", "a"))
    with pytest.raises(QcInputError, match="observer"):
        booth_compare_spectra(std, std, ANGLES, ("A",), observer="5")
    short = Reading(
        (15.0,),
        ((50.0, 0.0, 0.0),),
        (tuple(std[0, :20]),),
        tuple(float(w) for w in WL[:20]),
        where="short.json",
    )
    with pytest.raises(QcInputError, match="wavelengths_nm"):
        booth_compare(short, short)
