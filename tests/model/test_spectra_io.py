"""Spectra ⇄ Lab (ASTM E308 via colour-science), recovery, metamerism, design files."""

from __future__ import annotations

import json

import colour
import numpy as np
import pytest

from station.model import FaceFlopTravelGloss, ModelInputError
from station.model.colorimetry import OBSERVER_10, lab_to_linear_srgb, linear_srgb_to_lab
from station.model.design_io import design_from_dict, design_to_dict, load_design, save_design
from station.model.spectra import WAVELENGTHS, metamerism_index, reflectance_from_lab, reflectance_to_lab


def test_white_and_grey() -> None:
    assert reflectance_to_lab(np.ones(31)) == pytest.approx([100, 0, 0], abs=1e-9)
    # Y = 0.18 → L* = 116·0.18^(1/3) − 16 = 49.496
    assert reflectance_to_lab(np.full(31, 0.18)) == pytest.approx([49.4961, 0, 0], abs=1e-3)


def test_colourchecker_against_colour_full_range() -> None:
    """Our 400–700 nm ASTM E308 weights against colour's integration of the full-range spectrum."""
    cmfs = colour.MSDS_CMFS[OBSERVER_10]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    white = colour.CCS_ILLUMINANTS[OBSERVER_10]["D65"]
    for name, sd in list(colour.SDS_COLOURCHECKERS["BabelColor Average"].items())[:12]:
        r = sd.copy().align(colour.SpectralShape(400, 700, 10)).values
        ours = reflectance_to_lab(r)
        ref = colour.XYZ_to_Lab(colour.sd_to_XYZ(sd, cmfs, d65) / 100, white)
        assert colour.delta_E(ours, ref, method="CIE 2000") < 0.1, name


@pytest.mark.parametrize("lab", [[50, 20, -30], [80, -10, 60], [30, 40, 20], [95, 0, 0], [10, 5, 5]])
def test_recovery_round_trip(lab) -> None:
    r = reflectance_from_lab(lab)
    assert r.shape == (31,) and np.all((r >= 0) & (r <= 1))
    assert reflectance_to_lab(r) == pytest.approx(lab, abs=1e-5)


def test_recovery_out_of_solid_refused() -> None:
    with pytest.raises(ModelInputError, match="object-colour solid"):
        reflectance_from_lab([95, 120, 0])


def test_metamerism_index() -> None:
    r1 = reflectance_from_lab([50, 10, 10])
    # a metamer: add a spectral perturbation orthogonal to the D65 weights (invisible under D65)
    from station.model.spectra import weighting_factors

    w = weighting_factors("D65")
    p = np.sin(2 * np.pi * (WAVELENGTHS - 400) / 75.0)
    p -= w @ np.linalg.lstsq(w, p, rcond=None)[0]  # remove what D65 sees: a metameric black
    r2 = r1 + 0.08 * p / np.abs(p).max()
    assert np.all((r2 > 0) & (r2 < 1))
    mi = metamerism_index(r1, r2)
    assert mi["reference"] < 1e-9  # a match under D65 by construction
    # the ripple's period (75 nm) puts energy where F11's narrow lines sit: a strong mismatch there
    assert mi["F11"] > 1.0 and mi["A"] > 0.1
    same = metamerism_index(r1, r1)
    assert same["A"] == pytest.approx(0.0, abs=1e-9)


def test_srgb_white_and_inverse() -> None:
    assert lab_to_linear_srgb([100, 0, 0]) == pytest.approx([1, 1, 1], abs=1e-12)
    lab = np.array([[40, 20, -30], [70, -20, 30]])
    assert linear_srgb_to_lab(lab_to_linear_srgb(lab)) == pytest.approx(lab, abs=1e-9)


def test_wavelengths() -> None:
    assert WAVELENGTHS[0] == 400 and WAVELENGTHS[-1] == 700 and WAVELENGTHS.size == 31


def test_design_round_trip(tmp_path) -> None:
    d = FaceFlopTravelGloss((90, 2, -5), (30, 1, -2), 75.5, 85, name="Silver")
    p = save_design(d, tmp_path / "d.json", residual_de=[0, 0, 0])
    assert load_design(p) == d
    assert design_from_dict(design_to_dict(d)) == d
    solid = FaceFlopTravelGloss((50, 20, 10), (50, 20, 10), None, 10)
    assert design_from_dict(json.loads(json.dumps(design_to_dict(solid)))) == solid


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"flop": [1, 0, 0], "travel_deg": 50}, "face"),
        ({"face": [1, 0, 0], "flop": [1, 0, 0]}, "travel_deg"),
        ({"schema": "other/9", "face": [1, 0, 0], "flop": [1, 0, 0], "travel_deg": None}, "schema"),
        ({"face": [1, 0], "flop": [1, 0, 0], "travel_deg": None}, "face"),
        ([], "design"),
    ],
)
def test_bad_design(data, field) -> None:
    with pytest.raises(ModelInputError) as err:
        design_from_dict(data)
    assert err.value.field == field


def test_bad_design_file(tmp_path) -> None:
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(ModelInputError, match="design"):
        load_design(tmp_path / "x.json")
    with pytest.raises(ModelInputError, match="readable"):
        load_design(tmp_path / "missing.json")
