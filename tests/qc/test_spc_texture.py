"""``station qc spc --texture-limits``: sparkle and graininess charted per geometry within one vendor,
with the same rules as ΔE: a constructed series whose sparkle creeps after a stable baseline is flagged
before its first ΔS fail, its chart's centre and σ equal to the hand computation (x̄ and MR̄ / d₂), and a
reading of another vendor is never charted against the standard."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.qc._stored import DL, STD, store_job
from tests.qc.test_cli import inproc, set_standard

SPARKLE_STD, GRAIN_STD = 5.0, 3.0
#: Sparkle intensity at 45as15 of each sample minus the standard's: the ΔE test's series, ten stable then
#: eight creeping up to 1.03.
D_SPARKLE = DL
#: Graininess minus the standard's: stable throughout (alternating so no trend or run forms).
D_GRAIN = [0.10 + 0.02 * (i % 2) for i in range(len(D_SPARKLE))]
DS, DG = 1.0, 0.5


def _texture(vendor: str, sparkle: float, grain: float) -> list[dict[str, object]]:
    return [
        {"vendor": vendor, "name": "sparkle intensity", "geometry": "45as15", "value": sparkle},
        {"vendor": vendor, "name": "graininess", "geometry": "", "value": grain},
    ]


@pytest.fixture
def url(tmp_path: Path) -> str:
    """Job J-T: the standard panel, 18 sample panels of one vendor, one more measured by another vendor."""
    url = f"sqlite:///{tmp_path / 'qc.sqlite3'}"
    rows = [("BYK", 0.0, 0.0)] + [("BYK", s, g) for s, g in zip(D_SPARKLE, D_GRAIN, strict=True)]
    rows.append(("X-Rite", 9.0, 9.0))
    labs = [[[r[0] + 0.1 * (i % 2), r[1], r[2]] for r in STD] for i in range(len(rows))]
    store_job(
        url, "J-T", labs, [_texture(vendor, SPARKLE_STD + ds, GRAIN_STD + dg) for vendor, ds, dg in rows]
    )
    return url


def _standard_first(url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[str, str]:
    """Make the oldest measurement the standard; the ``--db`` arguments."""
    db = ("--db", url)
    res = inproc(capsys, tmp_path, "qc", "search", "--job", "J-T", "--json", *db)
    first = min(json.loads(res.stdout)["measurements"], key=lambda m: m["measured_at"])
    assert set_standard(capsys, tmp_path, "J-T", first["measurement_id"], url).returncode == 0
    return db


def test_texture_charts_flag_the_sparkle_drift_before_its_fail(
    url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = _standard_first(url, tmp_path, capsys)
    args = (
        "qc",
        "spc",
        "--job",
        "J-T",
        "--part",
        "fender",
        "--baseline",
        "10",
        "--texture-limits",
        f"ds={DS},dg={DG}",
    )
    res = inproc(capsys, tmp_path, *args, *db, "--out", "spc.png", "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["samples"] == len(D_SPARKLE)  # the other vendor's reading is unjudged, never charted
    charts = {(g["quantity"], g["geometry"]): g for g in out["texture"]}
    assert set(charts) == {("ΔS sparkle intensity", "45as15"), ("ΔG graininess", "")}
    sparkle = charts[("ΔS sparkle intensity", "45as15")]
    assert sparkle["vendor"] == "BYK"
    assert sparkle["chart"]["points"] == pytest.approx(D_SPARKLE)
    sigma = np.abs(np.diff(D_SPARKLE[:10])).mean() / 1.128
    assert sparkle["chart"]["centre"] == pytest.approx(np.mean(D_SPARKLE[:10]))
    assert sparkle["chart"]["sigma"] == pytest.approx(sigma)
    assert sparkle["capability"]["usl"] == DS
    assert sparkle["first_fail"] == D_SPARKLE.index(1.03) and sparkle["drift_before_fail"] is True
    rules = {h["rule"] for h in sparkle["drift"]}
    assert "N3" in rules  # six rising in a row: 0.36 … 0.80
    grain = charts[("ΔG graininess", "")]
    assert grain["drift"] == [] and grain["first_fail"] is None
    assert grain["capability"]["usl"] == DG
    assert any(line.startswith("ΔS sparkle intensity 45as15: drift from sample") for line in out["drift"])
    text = inproc(capsys, tmp_path, *args, *db).stdout
    assert "ΔS sparkle intensity 45as15" in text and "ΔG graininess sample" in text
    assert (tmp_path / "spc.png").stat().st_size > 10_000


def test_without_texture_limits_no_texture_chart(
    url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = _standard_first(url, tmp_path, capsys)
    res = inproc(capsys, tmp_path, "qc", "spc", "--job", "J-T", "--part", "fender", *db, "--json")
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["texture"] == []
