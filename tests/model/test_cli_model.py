"""The ``station model`` CLI contract, run as a real subprocess."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from station.model import FaceFlopTravelGloss
from tests.processes import run


def station(*args: str) -> subprocess.CompletedProcess[str]:
    return run([sys.executable, "-m", "station.cli", *args], timeout=120)


def test_from_angles_contract_and_design_file(tmp_path) -> None:
    d = FaceFlopTravelGloss((90, 2, -5), (30, 1, -2), 75.0, 85.0)
    lab = d.lab_at(np.array([15.0, 45.0, 110.0]))
    lab_arg = ";".join(",".join(f"{v:.12f}" for v in row) for row in lab)
    res = station(
        "model", "from-angles", "--angles", "15,45,110", "--lab", lab_arg, "--gloss", "85", "--json"
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert set(out) >= {"face", "flop", "travel_deg", "gloss_gu", "residual_de"}
    assert out["travel_deg"] == pytest.approx(75.0, abs=1e-8)
    assert out["face"] == pytest.approx([90, 2, -5], abs=1e-8)
    assert out["gloss_gu"] == 85.0 and len(out["residual_de"]) == 3
    # the printed JSON is a valid design file for every --design option
    path = tmp_path / "design.json"
    path.write_text(res.stdout)
    ev = station("model", "eval", "--design", str(path), "--angles", "25,75", "--json")
    assert ev.returncode == 0, ev.stderr
    np.testing.assert_allclose(json.loads(ev.stdout)["lab"], d.lab_at(np.array([25.0, 75.0])), atol=1e-7)


def test_eval_contract() -> None:
    res = station(
        "model",
        "eval",
        "--face",
        "90,2,-5",
        "--flop",
        "30,0,-1",
        "--travel",
        "75",
        "--angles",
        "15,25,45,75,110",
        "--json",
    )
    out = json.loads(res.stdout)
    assert out["angles"] == [15, 25, 45, 75, 110]
    # by hand: L(45) = 30 + 60·((75 − 45)/60)² = 45; L(110) = flop
    assert out["lab"][2][0] == pytest.approx(45.0)
    assert out["lab"][4] == pytest.approx([30, 0, -1])


def test_indices_contract() -> None:
    res = station("model", "indices", "--angles", "15,45,110", "--lab", "100,0,0;60,0,0;30,0,0", "--json")
    out = json.loads(res.stdout)
    assert out["flop_index"] == pytest.approx(2.69 * 70**1.11 / 60**0.86)
    assert out["hue_shift_index"] is None and out["warnings"]


def test_gloss_contract() -> None:
    out = json.loads(station("model", "gloss", "--gu", "60", "--json").stdout)
    assert set(out) >= {"phong_exponent", "specular_albedo", "ward_alpha", "simulated_gu"}
    assert out["simulated_gu"] == pytest.approx(60.0, abs=0.5)


def test_text_output_is_readable() -> None:
    res = station("model", "gloss", "--gu", "30")
    assert res.returncode == 0 and "phong_exponent:" in res.stdout


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["model", "eval", "--face", "90,2,-5", "--flop", "30,0,-1", "--travel", "10"], "travel_deg"),
        (["model", "from-angles", "--angles", "15,45,45", "--lab", "1,2,3;1,2,3;1,2,3"], "angles_deg"),
        (["model", "from-angles", "--angles", "15,45,110", "--lab", "1,2,3;1,2,3"], "lab"),
        (["model", "from-angles", "--angles", "15,45,110", "--lab", "1,2,x;1,2,3;1,2,3"], "lab[0]"),
        (["model", "gloss", "--gu", "150"], "gloss_gu"),
        (["model", "eval", "--design", "/nonexistent.json"], "design"),
    ],
)
def test_errors_exit_2_one_line(args, field) -> None:
    res = station(*args, "--json")
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0] and "expected" in lines[0]
    assert res.stdout == ""
