"""The bright silver through the command line: ``station model``, ``station design variations`` and
``station snap``, each a real subprocess run from a temporary folder; L* 250 exits 2 with one line."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from station.model import ANGLES_3, FaceFlopTravelGloss
from station.model.design_io import save_design
from tests.user_cli import run_station


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args)


def _lab_arg(lab: np.ndarray) -> str:
    return ";".join(",".join(f"{v:.12f}" for v in row) for row in lab)


def test_station_model(bright_silver: FaceFlopTravelGloss, tmp_path: Path) -> None:
    lab = bright_silver.lab_at(np.array(ANGLES_3))
    res = station(
        tmp_path,
        "model",
        "from-angles",
        "--angles",
        "15,45,110",
        "--lab",
        _lab_arg(lab),
        "--gloss",
        "90",
        "--json",
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["face"] == pytest.approx([125.0, -0.6, -1.8], abs=1e-8)
    assert out["flop"] == pytest.approx([38.0, -0.3, -3.2], abs=1e-8)
    assert out["travel_deg"] == pytest.approx(65.0, abs=1e-8)
    (tmp_path / "silver.json").write_text(res.stdout)
    ev = station(tmp_path, "model", "eval", "--design", "silver.json", "--angles", "45", "--json")
    assert ev.returncode == 0, ev.stderr
    assert json.loads(ev.stdout)["lab"][0][0] == pytest.approx(38.0 + 87.0 * 0.4**2, abs=1e-7)  # s(45°) = 0.4


def test_station_design_variations(bright_silver: FaceFlopTravelGloss, tmp_path: Path) -> None:
    save_design(bright_silver, tmp_path / "silver.json")
    res = station(tmp_path, "design", "variations", "--design", "silver.json", "--degree", "5", "--json")
    assert res.returncode == 0, res.stderr
    ring = {v["label"]: v for v in json.loads(res.stdout)["variations"]}
    assert ring["lighter"]["design"]["face"] == pytest.approx([130.0, -0.6, -1.8])
    assert ring["darker"]["design"]["face"] == pytest.approx([120.0, -0.6, -1.8])


def test_station_snap_against_the_demo_library(
    bright_silver: FaceFlopTravelGloss, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    lab = bright_silver.lab_at(np.array(ANGLES_3))
    res = station(tmp_path, "snap", "--library", "demo", "--lab", _lab_arg(lab), "--k", "1", "--json")
    assert res.returncode == 0, res.stderr
    match = json.loads(res.stdout)["matches"][0]
    # brute force over the same (cached) demo library: summed ΔE*ab over 15/45/110°
    from station.formulate.demo import demo_library

    monkeypatch.setenv("STATION_CACHE_DIR", str(tmp_path / "cache"))
    paints = demo_library().angle_columns(ANGLES_3)
    sums = np.linalg.norm(paints - lab[None], axis=-1).sum(-1)
    assert match["sum_de"] == pytest.approx(float(sums.min()), rel=1e-9)


@pytest.mark.parametrize(
    "args",
    [
        ("model", "eval", "--face", "250,0,0", "--flop", "38,0,0", "--travel", "65"),
        ("design", "variations", "--face", "250,0,0", "--flop", "38,0,0", "--travel", "65"),
        ("snap", "--library", "demo", "--lab", "250,0,0;50,0,0;38,0,0"),
        ("formulate", "250,0,0;50,0,0;38,0,0"),
    ],
)
def test_out_of_range_exits_2_with_one_line(tmp_path: Path, args: tuple[str, ...]) -> None:
    res = station(tmp_path, *args)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and res.stdout == ""
    assert "L" in lines[0] and "0 <= L* <= 200" in lines[0] and "250" in lines[0]
