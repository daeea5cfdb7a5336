"""Seam QA under a chosen illuminant (station.analysis.qa): panels' Lab per geometry from their spectra
under that illuminant, relative to its own white; D65 unchanged.

Lab under A is checked against colour-science's own ASTM E308 integration of the same spectra; the
fitted designs against a fit of those Lab; a metameric pair of panels (equal under D65) shows no
formulation seam under D65 and one under A.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import colour
import numpy as np
import pytest
from numpy.typing import NDArray

from station.analysis import AnalysisInputError, measurements_under, seam_qa
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.spectra import WAVELENGTHS, reflectance_to_lab, weighting_factors
from tests.user_cli import run_station

ANGLES = [15.0, 25.0, 45.0, 75.0, 110.0]
WL = [float(w) for w in WAVELENGTHS]


def _lab_cs(rows: NDArray[np.float64], illuminant: str) -> NDArray[np.float64]:
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11"}.get(illuminant, illuminant)]
    shape = colour.SpectralShape(400, 700, 10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ones = colour.SpectralDistribution(dict(zip(WL, np.ones(31), strict=True)))
        white = colour.sd_to_XYZ(ones, cmfs, ill, method="ASTM E308", shape=shape)
        xyz = [
            colour.sd_to_XYZ(
                colour.SpectralDistribution(dict(zip(WL, r, strict=True))),
                cmfs,
                ill,
                method="ASTM E308",
                shape=shape,
            )
            for r in rows
        ]
    return np.asarray(colour.XYZ_to_Lab(np.asarray(xyz) / white[1], colour.XYZ_to_xy(white)))


def _panels() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A blue metallic-like panel (lightness falling with angle) and its D65 metamer."""
    base = 0.22 + 0.18 * np.exp(-(((WAVELENGTHS - 460.0) / 60.0) ** 2))
    scale = np.array([2.2, 1.6, 1.0, 0.55, 0.4])[:, None]
    a = scale * base
    q, _ = np.linalg.qr(weighting_factors("D65"))
    ripple = np.sin(WAVELENGTHS / 13.0)
    black = ripple - q @ (q.T @ ripple)
    black /= np.max(np.abs(black))
    return a, a + 0.8 * a.min(axis=1, keepdims=True) * black


def test_lab_under_a_is_colour_sciences_and_the_designs_are_fitted_from_it() -> None:
    a, b = _panels()
    under_a = measurements_under(ANGLES, a, "A")
    np.testing.assert_allclose(under_a.lab, _lab_cs(a, "A"), atol=1e-6)
    assert under_a.illuminant == "A"
    r = seam_qa(under_a, measurements_under(ANGLES, b, "A"), 5.0, illuminant="A")
    expected = fit_fftg(AspecularMeasurements(tuple(ANGLES), _lab_cs(a, "A"))).design
    np.testing.assert_allclose(r.paint_a.face, expected.face, atol=1e-6)
    np.testing.assert_allclose(r.paint_a.flop, expected.flop, atol=1e-6)
    assert r.to_dict()["illuminant"] == "A"


def test_a_metameric_pair_of_panels_seams_under_a_only() -> None:
    a, b = _panels()
    np.testing.assert_allclose(_lab_cs(a, "D65"), _lab_cs(b, "D65"), atol=1e-9)
    d65 = seam_qa(measurements_under(ANGLES, a, "D65"), measurements_under(ANGLES, b, "D65"), 5.0)
    under_a = seam_qa(
        measurements_under(ANGLES, a, "A"), measurements_under(ANGLES, b, "A"), 5.0, illuminant="A"
    )
    assert max(d65.formulation_de) < 1e-6
    assert max(under_a.formulation_de) > 0.5


def test_d65_is_the_current_default() -> None:
    a, b = _panels()
    pa = AspecularMeasurements(tuple(ANGLES), reflectance_to_lab(a))
    pb = AspecularMeasurements(tuple(ANGLES), reflectance_to_lab(b))
    default = seam_qa(pa, pb, 5.0).to_dict()
    assert default["illuminant"] == "D65"
    assert seam_qa(pa, pb, 5.0, illuminant="D65").to_dict() == default
    spectral = seam_qa(measurements_under(ANGLES, a, "D65"), measurements_under(ANGLES, b, "D65"), 5.0)
    assert spectral.to_dict() == default


def test_panels_without_spectra_under_a_are_refused_naming_the_panel() -> None:
    a, _ = _panels()
    lab_only = AspecularMeasurements(tuple(ANGLES), reflectance_to_lab(a))
    design = FaceFlopTravelGloss((60.0, -5.0, -30.0), (25.0, 0.0, -15.0), 70.0)
    for panel in (lab_only, design):
        with pytest.raises(AnalysisInputError) as err:
            seam_qa(panel, measurements_under(ANGLES, a, "A"), 5.0, illuminant="A")
        assert err.value.field == "panel_a"
    with pytest.raises(AnalysisInputError) as err:
        seam_qa(lab_only, lab_only, 5.0, illuminant="Z1")
    assert err.value.field == "illuminant"


def test_cli_seam_under_an_illuminant(tmp_path: Path) -> None:
    a, b = _panels()
    for name, spectra in (("a.json", a), ("b.json", b)):
        lab = reflectance_to_lab(spectra).tolist()
        body = {"angles_deg": ANGLES, "lab": lab, "spectra": spectra.tolist(), "wavelengths_nm": WL}
        (tmp_path / name).write_text(json.dumps(body))
    (tmp_path / "lab.json").write_text(
        json.dumps({"angles_deg": ANGLES, "lab": reflectance_to_lab(a).tolist()})
    )
    base = ("analysis", "seam", "a.json", "b.json", "--beta", "5", "--json")
    default = run_station(tmp_path, *base)
    assert default.returncode == 0, default.stderr
    same = run_station(tmp_path, *base, "--illuminant", "D65")
    # the corrected paint's colorant-gamut check is a time-budgeted formulation: not part of the seam
    seam_only = lambda text: {k: v for k, v in json.loads(text).items() if k != "corrected_colorant_gamut"}  # noqa: E731
    assert seam_only(same.stdout) == seam_only(default.stdout)
    under_a = run_station(tmp_path, *base, "--illuminant", "A")
    assert under_a.returncode == 0, under_a.stderr
    out = json.loads(under_a.stdout)
    expected = seam_qa(
        measurements_under(ANGLES, a, "A"), measurements_under(ANGLES, b, "A"), 5.0, illuminant="A"
    )
    assert out["illuminant"] == "A"
    assert out["formulation_de_max"] == pytest.approx(max(expected.formulation_de), abs=1e-9)
    assert json.loads(default.stdout)["formulation_de_max"] < 1e-6
    for args, field in ((("--illuminant", "Z1"), "illuminant"), (("--illuminant", "A"), "panel")):
        files = ("lab.json", "b.json") if field == "panel" else ("a.json", "b.json")
        bad = run_station(tmp_path, "analysis", "seam", *files, "--beta", "5", *args)
        assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
        assert bad.stderr.startswith(f"error: {field}")
