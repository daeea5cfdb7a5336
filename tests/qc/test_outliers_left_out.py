"""Averaging repeat readings leaves the flagged outliers out (``qc check`` and ``qc summary``), names them,
and keeps them only with ``--keep-outliers``; a standard read several times is their mean.

The expected ΔE00 is computed independently with colour-science on the hand-averaged Lab."""

from __future__ import annotations

import datetime as dt
import json
import uuid
from pathlib import Path

import colour
import numpy as np
import pytest

from db.engine import make_engine, make_sessionmaker
from db.migrate import ensure_at_head
from db.models import Instrument, Measurement, Panel
from tests.qc.test_cli import _refused, inproc, set_standard

ANGLES = [15.0, 45.0, 110.0]
GEOMS = ["45as15", "45as45", "45as110"]
STD = np.array([[92.0, -1.0, 2.0], [60.0, -0.5, 1.0], [35.0, 0.0, 0.5]])
#: ΔL* of the good panel's repeat readings; the fourth was taken over a speck of dirt.
GOOD_DL = (0.10, 0.12, 0.08, 4.0, 0.11)
DIRTY = 3
T0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.UTC)


def _de00_max(sample: np.ndarray) -> float:
    return float(np.max(colour.delta_E(STD, sample, method="CIE 2000")))


def _panel(dls: tuple[float, ...]) -> list[np.ndarray]:
    return [STD + np.array([d, 0.0, 0.0]) for d in dls]


def _expected() -> tuple[float, float]:
    kept = [r for i, r in enumerate(_panel(GOOD_DL)) if i != DIRTY]
    return _de00_max(np.mean(kept, axis=0)), _de00_max(np.mean(_panel(GOOD_DL), axis=0))


def _tolerance(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    res = inproc(capsys, tmp_path, "qc", "tolerance", "--formula", "cie2000", "--limit", "0.6", "--json")
    assert res.returncode == 0, res.stderr
    (tmp_path / "tol.json").write_text(res.stdout)


def _file(path: Path, labs: list[np.ndarray]) -> None:
    body = {"measurements": [{"geometries": GEOMS, "lab": lab.tolist(), "sample": "P1"} for lab in labs]}
    path.write_text(json.dumps(body))


def test_check_leaves_the_dirty_repeat_out(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    kept_de, all_de = _expected()
    assert kept_de < 0.6 < all_de  # the case of the report: the dirty reading flips pass to fail
    _tolerance(capsys, tmp_path)
    _file(tmp_path / "std.json", [STD])
    _file(tmp_path / "panel.json", _panel(GOOD_DL))
    base = ("qc", "check", "--standard", "std.json", "--sample", "panel.json", "--tolerance", "tol.json")
    res = inproc(capsys, tmp_path, *base, "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["verdict"] == "pass" and out["max_de"] == pytest.approx(kept_de, abs=1e-9)
    rep = out["sample"]["repeats"]
    assert rep["outliers"] == [DIRTY] and rep["left_out"] == [DIRTY] and rep["outliers_kept"] is False
    res = inproc(capsys, tmp_path, *base, "--keep-outliers", "--json")
    out = json.loads(res.stdout)
    assert out["verdict"] == "fail" and out["max_de"] == pytest.approx(all_de, abs=1e-9)
    assert out["sample"]["repeats"]["left_out"] == []
    res = inproc(capsys, tmp_path, *base)
    assert "mean of 4 of 5 readings; outliers: reading 3, left out of the mean" in res.stdout


def _store(url: str) -> dict[str, int]:
    """Job J-7: a standard panel read three times (one dirty) and the good panel read five times."""
    ensure_at_head(url)
    engine = make_engine(url)
    ids: dict[str, int] = {}
    with make_sessionmaker(engine)() as s:
        inst = Instrument(serial="600123", model="MA6", kind="spectrophotometer")
        s.add(inst)
        s.flush()
        for name, labs in (("std", _panel((0.0, 0.02, -5.0, -0.01))), ("good", _panel(GOOD_DL))):
            p = Panel(job="J-7", part="fender")
            s.add(p)
            s.flush()
            for i, lab in enumerate(labs):
                m = Measurement(
                    client_id=uuid.uuid4(),
                    instrument_id=inst.id,
                    panel_id=p.id,
                    operator="ana",
                    measured_at=T0 + dt.timedelta(hours=len(ids)),
                    geometries_deg=ANGLES,
                    lab=lab.tolist(),
                    payload_sha256="0" * 64,
                )
                s.add(m)
                s.flush()
                ids[f"{name}{i}"] = m.id
        s.commit()
    engine.dispose()
    return ids


def test_summary_averages_panels_and_the_standard_without_outliers(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'qc.sqlite3'}"
    ids = _store(url)
    _tolerance(capsys, tmp_path)
    db = ("--db", url)
    res = set_standard(capsys, tmp_path, "J-7", str(ids["std0"]), url)
    assert res.returncode == 0, res.stderr
    args = ("qc", "summary", "--job", "J-7", "--tolerance", "tol.json", "--average-panels", *db)
    out = json.loads(inproc(capsys, tmp_path, *args, "--json").stdout)
    (part,) = out["parts"]
    std = part["standard"]
    # the standard is the mean of its three clean readings: ΔL* (0 + 0.02 − 0.01) / 3 from STD
    assert std["left_out"] == [ids["std2"]] and len(std["measurement_ids"]) == 4
    assert np.allclose(std["lab"], STD + [0.01 / 3, 0, 0])
    (sample,) = part["samples"]  # the standard's repeats are not samples
    assert sample["left_out"] == [ids[f"good{DIRTY}"]]
    kept = np.mean([r for i, r in enumerate(_panel(GOOD_DL)) if i != DIRTY], axis=0)
    expected = float(np.max(colour.delta_E(STD + [0.01 / 3, 0, 0], kept, method="CIE 2000")))
    assert sample["qc"]["verdict"] == "pass" and sample["qc"]["max_de"] == pytest.approx(expected, abs=1e-9)
    kept_all = json.loads(inproc(capsys, tmp_path, *args, "--keep-outliers", "--json").stdout)
    assert kept_all["parts"][0]["samples"][0]["qc"]["verdict"] == "fail"
    text = inproc(capsys, tmp_path, *args).stdout
    assert "left out" in text and str(ids[f"good{DIRTY}"]) in text


def test_a_misspelt_sqlite_path_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    url = f"sqlite:///{tmp_path / 'qc.sqlite3x'}"
    for cmd in (("jobs",), ("search", "--job", "J-7"), ("summary", "--job", "J-7")):
        _refused(inproc(capsys, tmp_path, "qc", *cmd, "--db", url), "db")
    assert not (tmp_path / "qc.sqlite3x").exists()
