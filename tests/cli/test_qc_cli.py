"""``station qc`` as a real subprocess from a temporary folder: a verdict in JSON against the closed
form of ΔE*ab and the hand-computed DIN 6175-2, a tolerance file written and read back, readable text,
and bad input exiting 2 with one line naming the field."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import pytest

from tests.model.test_din6175 import _by_hand
from tests.user_cli import run_station

STD = "90,1,-2;50,2,-3;30,3,-4"
SMP = "90.5,1,-2;50,2.5,-3.2;31.2,3,-4"


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args)


def _triples(text: str) -> list[list[float]]:
    return [[float(v) for v in t.split(",")] for t in text.split(";")]


def test_verdict_json_din6175_and_cie76(tmp_path: Path) -> None:
    res = station(
        tmp_path, "qc", "verdict", "--standard", STD, "--sample", SMP, "--formula", "din6175", "--json"
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    hand = [_by_hand(r, s, a)[0] for r, s, a in zip(_triples(STD), _triples(SMP), (15, 45, 110), strict=True)]
    assert [g["dE"] for g in out["per_geometry"]] == pytest.approx(hand, rel=1e-12)
    assert [g["geometry"] for g in out["per_geometry"]] == ["45as15", "45as45", "45as110"]
    assert out["max_de"] == pytest.approx(max(hand)) and out["worst_geometry"] == "45as110"
    assert out["mean_de"] == pytest.approx(sum(hand) / 3)
    expected = (
        "fail" if max(hand) > 1.0 else "warn" if max(hand) > 0.8 else "pass"
    )  # default limit 1, band 0.8
    assert out["verdict"] == expected and out["formula"] == "din6175"

    res = station(
        tmp_path, "qc", "verdict", "--standard", STD, "--sample", SMP, "--formula", "cie76", "--limit", "1.3",
        "--dl", "1.0", "--json",
    )  # fmt: skip
    out = json.loads(res.stdout)
    assert out["per_geometry"][1]["dE"] == pytest.approx(math.hypot(0.5, 0.2))
    assert out["per_geometry"][2]["verdict"] == "fail" and "ΔL* 1.2 beyond ±1" in out["reason"]


def test_tolerance_file_round_trip_and_text_output(tmp_path: Path) -> None:
    res = station(
        tmp_path, "qc", "tolerance", "--formula", "cie2000", "--lc", "2:1", "--limit", "2", "--json"
    )
    assert res.returncode == 0, res.stderr
    (tmp_path / "tol.json").write_text(res.stdout)
    assert json.loads(res.stdout)["l_c"] == [2.0, 1.0]
    res = station(tmp_path, "qc", "verdict", "--standard", STD, "--sample", SMP, "--tolerance", "tol.json")
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert lines[0].startswith("verdict: pass") and "cie2000" in lines[0]
    assert any(line.strip().startswith("45as110") for line in lines)


@pytest.mark.parametrize(
    ("extra", "field"),
    [
        (["--formula", "audi2000"], "AUDI2000 coefficients"),
        (["--angles", "15,45"], "standard"),
        (["--warn", "2"], "tolerance.warn_fraction"),
        (["--da", "1", "--dh", "1"], "components"),
        (["--tolerance", "missing.json"], "tolerance"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path: Path, extra: list[str], field: str) -> None:
    res = station(tmp_path, "qc", "verdict", "--standard", STD, "--sample", SMP, *extra)
    assert res.returncode == 2
    assert len(res.stderr.strip().splitlines()) == 1 and field in res.stderr
