"""The lab's QC day through the command line, every step a real ``station`` subprocess run from a
temporary folder (not the repository):

simulator reading → vendor files (CxF3, CGATS.17, an MA-T12-style workbook) → a watch folder served by
the real watcher → the SQLite database → the standard set from its repeat readings → ``qc check`` and
``qc summary`` with ``--average-panels`` leaving a dirty repeat out (and the verdict flipping with
``--keep-outliers``) → ``qc spc`` flagging a planted drift before the first fail → ``qc report`` (PDF).

The simulator is read once and its reading is the base: the repeat scatter, the dirty reading (ΔL* +4,
a speck of dirt) and the drift are planted as ΔL* offsets on it (not left to the simulator's own noise),
written through the product's file writers; every expected ΔE00 is computed independently with colour-science from those Lab values.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import colour
import numpy as np
import pytest

from station.ingest.formats import read_measurement_file, write_measurement_file
from station.ingest.formats.measurement import ImportedMeasurement
from tests.pdf_text import pdf_text
from tests.processes import Child
from tests.user_cli import REPO, run_station
from tests.waiting import wait_until

JOB, PART = "J-26", "door"
LIMIT = 0.6  # CIEDE2000 limit of the customer's tolerance set
#: ΔL* of the standard panel's three repeat readings against the simulator's reading.
STD_DL = (0.0, 0.02, -0.02)
#: ΔL* of the trial panel T1's five repeats; the fourth was read over a speck of dirt.
GOOD_DL = (0.10, 0.12, 0.08, 4.0, 0.11)
DIRTY = 3
#: ΔL* of the next panels S1…S10, one reading each: stable, then creeping up to a fail.
SERIES_DL = (0.13, 0.09, 0.12, 0.10, 0.11, 0.20, 0.30, 0.40, 0.52, 0.70)
BASELINE = 6  # T1 and S1…S5 set the control limits
T0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.UTC)


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    res = run_station(cwd, *args, timeout=120)
    assert res.returncode == 0, f"station {' '.join(args)}: {res.stderr}"
    return res


def _de00(std: np.ndarray, lab: np.ndarray) -> np.ndarray:
    """ΔE00 per geometry (colour-science, k_L = k_C = k_H = 1)."""
    return np.asarray(colour.delta_E(std, lab, method="CIE 2000"), dtype=float)


def _planted(base: ImportedMeasurement, sample: str, dl: float, when: dt.datetime) -> ImportedMeasurement:
    """*base* as panel *sample* read at *when* with ΔL* *dl* at every geometry (Lab only)."""
    assert base.lab is not None
    lab = tuple((round(v[0] + dl, 4), v[1], v[2]) for v in base.lab)
    return dataclasses.replace(
        base, sample=sample, lab=lab, wavelengths_nm=None, spectra=None, measured_at=when
    )


def _vendor_files(work: Path, inbox: Path) -> np.ndarray:
    """Measure the simulator's panel once (written as CGATS.17 and CxF3), plant the repeats and the
    series, and write the files to be dropped; returns the simulator's Lab (geometries × 3)."""
    res = station(
        work, "measure", "sim:ma6", "--sample", "STD", "--out", "sim.cxf", "--out", "std.cgats", "--json"
    )
    lab = np.array(json.loads(res.stdout)["lab"])
    (base,) = read_measurement_file(work / "sim.cxf").measurements
    assert base.lab is not None and np.array_equal(np.array(base.lab), lab)  # the two formats agree
    when = [T0 + dt.timedelta(minutes=i) for i in range(len(GOOD_DL))]
    write_measurement_file([_planted(base, "STD", d, T0) for d in STD_DL[1:]], work / "std-repeats.cxf")
    write_measurement_file(
        [_planted(base, "T1", d, w) for d, w in zip(GOOD_DL, when, strict=True)], work / "t1.cgats"
    )
    series = [_planted(base, f"S{i + 1}", d, T0 + dt.timedelta(hours=i + 1)) for i, d in enumerate(SERIES_DL)]
    write_measurement_file(series, work / "series.xlsx")
    for name in ("std.cgats", "std-repeats.cxf", "t1.cgats", "series.xlsx"):
        (work / name).rename(inbox / name)
    return lab


def _watch(work: Path, inbox: Path, url: str) -> None:
    """The watcher (``station import watch``) running while the files are dropped; ended once all four
    are in ``done/``."""
    argv = [sys.executable, "-m", "station.cli", "import", "watch", str(inbox), "--store", url]
    argv += ["--job", JOB, "--part", PART, "--settle", "0.2", "--interval", "0.1"]
    env = {k: v for k, v in os.environ.items() if k != "CACAD_DATABASE_URL"}
    env.update(PYTHONPATH=str(REPO), STATION_CACHE_DIR=str(work / "cache"))
    with Child(argv, cwd=work, env=env) as watcher:
        assert watcher.err is not None
        watcher.err.wait_for("watching", timeout=60)
        _vendor_files(work, inbox)
        done = inbox / "done"
        wait_until(lambda: done.is_dir() and len(list(done.iterdir())) == 4, timeout=60, what="4 files done")
        assert not list((inbox / "rejected").glob("*"))


@pytest.fixture
def journey(tmp_path: Path) -> dict[str, Any]:
    work = tmp_path / "lab"
    inbox = work / "inbox"
    inbox.mkdir(parents=True)
    url = f"sqlite:///{work / 'qc.sqlite3'}"
    station(work, "db", "upgrade", "--database", url)
    _watch(work, inbox, url)
    tol = station(work, "qc", "tolerance", "--formula", "cie2000", "--limit", str(LIMIT), "--json").stdout
    (work / "tol.json").write_text(tol)
    return {"work": work, "done": inbox / "done", "db": ("--db", url)}


@pytest.mark.slow
def test_the_qc_day_from_the_simulator_to_the_report(journey: dict[str, Any]) -> None:
    work, done, db = journey["work"], journey["done"], journey["db"]
    (std,) = read_measurement_file(done / "std.cgats").measurements
    judged = [g["geometry"] for g in json.loads((work / "tol.json").read_text())["geometries"]]
    std_lab = np.array(std.lab, dtype=float)
    lab = std_lab[[std.geometries.index(g) for g in judged]]  # the tolerance's geometries
    t1 = [lab + [d, 0.0, 0.0] for d in GOOD_DL]
    kept_de = float(_de00(lab, np.mean([r for i, r in enumerate(t1) if i != DIRTY], axis=0)).max())
    all_de = float(_de00(lab, np.mean(t1, axis=0)).max())
    assert kept_de < LIMIT < all_de  # the dirty reading alone decides the verdict

    # qc check on the vendor files the watcher moved to done/
    check: tuple[str, ...] = (
        "qc",
        "check",
        "--standard",
        str(done / "std.cgats"),
        "--sample",
        str(done / "t1.cgats"),
    )
    check += ("--tolerance", "tol.json", "--average-panels", "--json")
    out = json.loads(station(work, *check).stdout)
    assert out["verdict"] == "pass" and out["max_de"] == pytest.approx(kept_de, abs=2e-4)
    assert out["sample"]["repeats"]["left_out"] == [DIRTY]
    out = json.loads(station(work, *check, "--keep-outliers").stdout)
    assert out["verdict"] == "fail" and out["max_de"] == pytest.approx(all_de, abs=2e-4)

    # the database: every reading stored once, the standard set from the standard panel's repeats
    found = json.loads(station(work, "qc", "search", "--job", JOB, "--json", *db).stdout)["measurements"]
    assert len(found) == len(STD_DL) + len(GOOD_DL) + len(SERIES_DL)
    (std_id,) = [m["measurement_id"] for m in found if np.allclose(m["lab"], std_lab, rtol=0, atol=1e-9)]
    station(work, "qc", "standard", "set", "--job", JOB, "--part", PART, "--measurement", str(std_id), *db)
    avg = ("--tolerance", "tol.json", "--average-panels", *db)
    summary = json.loads(station(work, "qc", "summary", "--job", JOB, *avg, "--json").stdout)
    _assert_summary(summary, found, std.geometries.index(judged[0]), kept_de)

    # SPC: the drift is flagged before the first fail
    spc = ("qc", "spc", "--job", JOB, "--part", PART, "--baseline", str(BASELINE), "--out", "spc.png")
    _assert_spc(
        json.loads(station(work, *spc, *avg, "--json").stdout),
        dict(zip(judged, lab, strict=True)),
        work / "spc.png",
    )

    # the report a lab signs
    station(work, "qc", "report", "--job", JOB, "--out", "report.pdf", *avg)
    pdf = (work / "report.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page\b(?!s)", pdf)) > 0
    text = pdf_text(pdf)
    trials = [f"panel {t['panel_id']}, {PART}, {JOB}" for t in summary["parts"][0]["samples"]]
    for name in trials:  # every trial by its panel, part and job (the report's trial names)
        assert name in text, f"{name!r} not in the report's text"
    assert "before the" in text and "rst fail" in text  # the SPC page's drift line ("fi": a ligature)


def _assert_summary(summary: dict[str, Any], found: list[dict[str, Any]], k: int, kept_de: float) -> None:
    """T1 judged once on the mean of its four clean repeats, the dirty one named by its id; the standard
    the mean of its three repeats; every other panel a sample of its own."""
    (part,) = summary["parts"]
    assert len(part["standard"]["measurement_ids"]) == len(STD_DL) and part["standard"]["left_out"] == []
    samples = part["samples"]
    assert len(samples) == 1 + len(SERIES_DL)  # the standard's repeats are not samples
    (t1,) = [s for s in samples if s.get("left_out")]
    (dirty,) = t1["left_out"]
    (std_l,) = {
        m["lab"][k][0] for m in found if m["measurement_id"] in part["standard"]["measurement_ids"][:1]
    }
    dirty_l = next(m["lab"][k][0] for m in found if m["measurement_id"] == dirty)
    assert dirty_l - std_l == pytest.approx(GOOD_DL[DIRTY] - STD_DL[0], abs=0.03)
    assert t1["qc"]["verdict"] == "pass" and t1["qc"]["max_de"] == pytest.approx(kept_de, abs=2e-4)


def _assert_spc(out: dict[str, Any], std: dict[str, np.ndarray], png: Path) -> None:
    """Each geometry's ΔE00 series by colour-science: where a drift is flagged, the first flag comes
    before the first sample beyond the limit, and that flagged sample itself is within it."""
    dls = (float(np.mean([d for i, d in enumerate(GOOD_DL) if i != DIRTY])), *SERIES_DL)
    assert out["samples"] == len(dls) and png.stat().st_size > 10_000
    failing = 0
    for g in out["geometries"]:
        ref = std[g["geometry"]][None]
        de = [float(_de00(ref, ref + [d, 0.0, 0.0])[0]) for d in dls]
        first_fail = next((i for i, v in enumerate(de) if v > LIMIT), None)
        assert g["first_fail"] == first_fail, g["geometry"]
        if first_fail is None:
            continue
        failing += 1
        first_flag = min(p for h in g["drift"] for p in h["points"])
        assert first_flag < first_fail and g["drift_before_fail"] is True and de[first_flag] < LIMIT
    assert failing  # the planted drift ends in a fail somewhere
