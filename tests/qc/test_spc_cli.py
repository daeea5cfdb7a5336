"""``station qc spc`` on a stored job whose panels drift: the drift flagged before the fail, in the
table, the JSON and the chart; Cp/Cpk against the tolerance by hand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.qc._stored import DL, STD, store_job
from tests.qc.test_cli import _refused, inproc, set_standard


@pytest.fixture
def url(tmp_path: Path) -> str:
    url = f"sqlite:///{tmp_path / 'qc.sqlite3'}"
    store_job(url, "J-9", [[[r[0] + dl, r[1], r[2]] for r in STD] for dl in [0.0, *DL]])
    return url


def test_spc_flags_the_drift_before_the_fail(
    url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = ("--db", url)
    res = inproc(capsys, tmp_path, "qc", "search", "--job", "J-9", "--limit", "1", "--json", *db)
    std_id = json.loads(res.stdout)["measurements"][0]["measurement_id"]
    res = set_standard(capsys, tmp_path, "J-9", str(std_id), url)
    assert res.returncode == 0, res.stderr
    args = ("qc", "spc", "--job", "J-9", "--part", "fender", "--formula", "cie76", "--baseline", "10", *db)
    res = inproc(capsys, tmp_path, *args, "--out", "spc.png", "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["samples"] == len(DL) and (tmp_path / "spc.png").stat().st_size > 10_000
    g = out["geometries"][0]
    assert g["first_fail"] == DL.index(1.03) and g["drift_before_fail"] is True
    assert min(p for h in g["drift"] for p in h["points"]) < g["first_fail"]
    sigma = np.abs(np.diff(DL[:10])).mean() / 1.128
    assert g["chart"]["centre"] == pytest.approx(np.mean(DL[:10])) and g["chart"]["sigma"] == pytest.approx(
        sigma
    )
    cap = g["capability"]  # the product default limit ΔE 1, over the baseline
    assert cap["usl"] == 1.0 and cap["cpk"] == pytest.approx((1.0 - np.mean(DL[:10])) / (3 * sigma))
    text = inproc(capsys, tmp_path, *args).stdout
    assert "before the first fail" in text and "N3" in text and "Cpk" in text
    _refused(inproc(capsys, tmp_path, *args, "--subgroup", "12"), "subgroup")
    _refused(inproc(capsys, tmp_path, *args, "--baseline", "40"), "baseline")
