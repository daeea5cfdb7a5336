"""Fig. 4.3 sweep, the seam QA workflow, its report picture and the ``station analysis`` CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.analysis import goniogeometric_index
from station.analysis.index import SeamModel
from station.analysis.picture import plot_seam_report, shade_pair
from station.analysis.qa import seam_qa
from station.analysis.sweep import plot_sweep, seam_sweep
from station.cli import main
from station.model import AspecularMeasurements, FaceFlopTravelGloss
from station.model.design_io import design_to_dict


def test_sweep_matches_seam_model(blue_metallic):
    r = seam_sweep(blue_metallic, (1.0, -2.0), (30.0, 45.0), (-10.0, 0.0, 20.0))
    assert r.delta_e.shape == (2, 2, 3)
    m = SeamModel([45.0], [20.0])
    assert r.delta_e[1, 1, 2] == pytest.approx(
        m.delta_e(blue_metallic, blue_metallic, np.array([-2.0]))[0, 0]
    )


def test_sweep_graphical_index_brackets_the_computed_index(blue_metallic):
    """Thesis §4.3.3: the index read off the curves is the largest β under ε everywhere."""
    lights, views = (45.0,), tuple(float(v) for v in range(-30, 66, 5))
    betas = np.arange(0.05, 3.0, 0.05).tolist()
    r = seam_sweep(blue_metallic, betas, lights, views)
    est = r.index_estimate()
    idx = goniogeometric_index(blue_metallic, 45.0, list(views), direction="+")
    assert est is not None and idx.beta_min_deg is not None
    assert est <= idx.beta_min_deg < est + 0.05 + 1e-9


def test_plot_sweep_writes_png(tmp_path, blue_metallic):
    path = plot_sweep(seam_sweep(blue_metallic), tmp_path / "fig43.png")
    assert path.stat().st_size > 10_000
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_seam_qa_geometric_mismatch(blue_metallic):
    r = seam_qa(blue_metallic, blue_metallic, -3.0)
    assert not r.passed
    assert r.diagnosis.startswith("geometric mismatch")
    assert max(r.formulation_de) == pytest.approx(0.0, abs=1e-9)
    assert r.correction.max_after < max(r.seam_de)
    assert any(a.startswith("1)") for a in r.advice) and any(a.startswith("4)") for a in r.advice)
    d = r.to_dict()
    json.dumps(d)
    assert d["corrected_paint"]["schema"] == "cacad.design/1"
    assert "corrected" in d["corrected_paint"]["name"]


def test_seam_qa_formulation_mismatch_from_measurements():
    """Aligned-looking seam (0.2°) but panel B measured 4 L* darker: a formulation error."""
    a = FaceFlopTravelGloss((60.0, 0.0, -20.0), (60.0, 0.0, -20.0), None)
    b = AspecularMeasurements((15.0, 45.0, 110.0), np.array([[56.0, 0.0, -20.0]] * 3))
    r = seam_qa(a, b, 0.2)
    assert not r.passed
    assert r.diagnosis.startswith("formulation mismatch")


def test_seam_qa_pass_for_small_seam_on_solid():
    a = FaceFlopTravelGloss((60.0, 0.0, -20.0), (60.0, 0.0, -20.0), None)
    r = seam_qa(a, a, 0.5)
    assert r.passed and "within tolerance" in r.diagnosis


def test_report_png_and_shaded_pair(tmp_path, blue_metallic):
    img = shade_pair(blue_metallic, blue_metallic, -5.0, 45.0, 0.0, size=(20, 40))
    assert img.shape == (20, 40, 3) and np.all(np.isfinite(img))
    assert np.abs(img[:, 19] - img[:, 20]).mean() > 0.01  # the seam is visible
    r = seam_qa(blue_metallic, blue_metallic, -3.0, lights_deg=(45.0,), aspecular_deg=(15.0, 45.0))
    path = plot_seam_report(r, tmp_path / "qa.png")
    assert path.stat().st_size > 10_000


def test_cli_gg_index_matches_function(capsys):
    rc = main(["analysis", "gg-index", "--face", "60,0,0", "--light", "45", "--view", "0", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    grey = FaceFlopTravelGloss((60.0, 0.0, 0.0), (60.0, 0.0, 0.0), None)
    assert out["beta_min_deg"] == pytest.approx(goniogeometric_index(grey, 45.0, 0.0).beta_min_deg)
    assert set(out) >= {"beta_min_deg", "direction", "geometry"}


def test_cli_gg_index_effect_paint_and_de(capsys):
    rc = main(
        [
            "analysis",
            "gg-index",
            "--face",
            "90,-2,-10",
            "--flop",
            "30,-1,-12",
            "--travel",
            "70",
            "--light",
            "45",
            "--de",
            "cie2000",
            "--epsilon",
            "1",
            "--json",
        ]
    )
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "cie2000" and out["reached"]


def test_cli_bad_input_exit_2(capsys):
    assert main(["analysis", "gg-index", "--face", "60,0,0", "--light", "95", "--json"]) == 2
    assert "light_deg" in capsys.readouterr().err
    assert main(["analysis", "gg-index", "--face", "60,0,0", "--flop", "30,0,0", "--light", "45"]) == 2
    capsys.readouterr()
    assert main(["analysis", "gg-index", "--face", "60,0,0", "--light", "45", "--beta-max", "1e-300"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "beta_max_deg" in err[0] and "1e-06 <= beta_max_deg <= 89" in err[0], err


def test_cli_trompe_loeil(capsys):
    rc = main(
        [
            "analysis",
            "trompe-loeil",
            "--face",
            "75,-5,-20",
            "--beta",
            "-3",
            "--lights",
            "0,15.5,29.1,39.8,45,52",
            "--objective",
            "rms",
            "--json",
        ]
    )
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert 0.5 < out["max_after"] < 1.5


def test_cli_seam_with_design_and_measurement_files(tmp_path, capsys, blue_metallic):
    a = tmp_path / "a.json"
    b = tmp_path / "b.json"
    a.write_text(json.dumps(design_to_dict(blue_metallic)))
    b.write_text(
        json.dumps(
            {"angles_deg": [15, 45, 110], "lab": blue_metallic.lab_at(np.array([15.0, 45.0, 110.0])).tolist()}
        )
    )
    png = tmp_path / "r.png"
    rc = main(
        ["analysis", "seam", str(a), str(b), "--beta", "-2", "--lights", "45", "--png", str(png), "--json"]
    )
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["passed"] is False and png.exists()
    # the corrected paint is checked against the colorants: the verdict follows the recipe's own ΔE00
    gamut = out["corrected_colorant_gamut"]
    assert gamut["inside_colorant_gamut"] == (gamut["mean_de"] <= gamut["tolerance"])
    assert set(gamut["nearest_achievable_paint"]) >= {"face", "flop", "travel_deg"} and gamut["recipe"]
    assert main(["analysis", "seam", str(tmp_path / "missing.json"), str(b), "--beta", "2"]) == 2


def test_cli_negative_view_list_with_equals_form(capsys):
    rc = main(
        [
            "analysis",
            "gg-index",
            "--face",
            "90,-2,-10",
            "--flop",
            "30,-1,-12",
            "--travel",
            "70",
            "--light",
            "45",
            "--view=-30,0",
            "--json",
        ]
    )
    assert rc == 0
    assert json.loads(capsys.readouterr().out)["geometry"]["view_deg"] == -30.0
