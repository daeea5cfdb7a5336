"""The QC metamerism index against an independent computation with colour-science's own integration."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.qc.errors import QcInputError
from station.qc.metamerism import metamerism
from station.qc.readings import Reading, reading_from_dict

WL = list(range(400, 701, 10))


def _lab(refl: np.ndarray, illuminant: str) -> np.ndarray:
    """CIELAB of a 400–700/10 nm reflectance under *illuminant*, 10° observer, by ASTM E308 integration."""
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11"}.get(illuminant, illuminant)]
    sd = colour.SpectralDistribution(dict(zip(WL, refl, strict=True)))
    xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308") / 100
    white = colour.sd_to_XYZ(colour.sd_ones(sd.shape), cmfs, ill, method="ASTM E308") / 100
    return colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white))


def test_metameric_pair_against_colour_science() -> None:
    x = np.linspace(0, 1, 31)
    std = 0.35 + 0.2 * np.sin(2 * np.pi * x)  # two spectra crossing several times: a metamer-like pair
    smp = 0.35 + 0.2 * np.sin(2 * np.pi * x + 0.6) + 0.05 * np.cos(6 * np.pi * x)
    a = reading_from_dict({"geometries": ["45as45"], "spectra": [std.tolist()], "wavelengths_nm": WL})
    b = reading_from_dict({"geometries": ["45as45"], "spectra": [smp.tolist()], "wavelengths_nm": WL})
    res = metamerism(a, b, "cie76")
    d65_r, d65_s = _lab(std, "D65"), _lab(smp, "D65")
    assert res.reference[0] == pytest.approx(np.linalg.norm(d65_s - d65_r), abs=0.05)
    for ill in ("A", "F11"):
        expected = np.linalg.norm(_lab(smp, ill) - (d65_s - d65_r) - _lab(std, ill))
        assert res.index[ill][0] == pytest.approx(expected, abs=0.05)
        assert res.index[ill][0] > 0.5  # a real change with the illuminant
    same = metamerism(a, a)
    assert same.index == {"A": (0.0,), "F11": (0.0,)}


def test_metamerism_needs_spectra() -> None:
    lab_only = Reading((45.0,), ((50.0, 0.0, 0.0),))
    with pytest.raises(QcInputError, match="spectra") as err:
        metamerism(lab_only, lab_only)
    assert err.value.field == "standard.spectra"
