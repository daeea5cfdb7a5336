"""``station qc check|report|trend|standard|search|metamerism`` on `station measure --json` output and a
populated SQLite database: the main journeys as real subprocesses from a temporary folder, the
refusals and side commands through the same entry point in-process (``station.cli.main``, exit 2 and
one line on stderr), to keep the suite fast."""

from __future__ import annotations

import csv
import itertools
import json
import math
import os
import re
import subprocess
from pathlib import Path

import pytest

from db.engine import make_engine, make_sessionmaker
from db.migrate import ensure_at_head
from station.qc.errors import QcInputError
from station.qc.jobs import job_summary
from station.qc.report import csv_text, pdf_bytes, write_pdf, write_trend_png
from station.qc.spc import D2_RANGE_OF_TWO
from tests.qc.conftest import FENDER_OFFSETS, FENDER_STD, Job, populate
from tests.user_cli import run_station


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args)


def _refused(res: subprocess.CompletedProcess[str], field: str) -> None:
    assert res.returncode == 2, (res.stdout, res.stderr)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0], res.stderr


def inproc(capsys: pytest.CaptureFixture[str], cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``station ARGS`` through :func:`station.cli.main` in this process, run in *cwd*."""
    from station.cli import main

    here = Path.cwd()
    os.chdir(cwd)
    try:
        rc = main(list(args))
    finally:
        os.chdir(here)
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(list(args), rc, out, err)


def set_standard(
    capsys: pytest.CaptureFixture[str], cwd: Path, job: str, measurement: int | str, url: str, *extra: str
) -> subprocess.CompletedProcess[str]:
    """``station qc standard set --job JOB --part fender --measurement ID --db URL [EXTRA]`` in-process."""
    return inproc(
        capsys, cwd, "qc", "standard", "set", "--job", job, "--part", "fender",
        "--measurement", str(measurement), "--db", url, *extra,
    )  # fmt: skip


@pytest.fixture
def db(tmp_path: Path) -> tuple[str, Job]:
    url = f"sqlite:///{tmp_path / 'qc.sqlite3'}"
    ensure_at_head(url)
    engine = make_engine(url)
    with make_sessionmaker(engine)() as s:
        job = populate(s)
        s.commit()
    engine.dispose()
    return url, job


def test_check_on_measure_output(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    res = inproc(capsys, tmp_path, "measure", "sim:ma6", "--json")
    assert res.returncode == 0, res.stderr
    (tmp_path / "std.json").write_text(res.stdout)
    measured = json.loads(res.stdout)
    sample = dict(measured, lab=[[r[0] + 0.9, r[1], r[2]] for r in measured["lab"]])
    (tmp_path / "smp.json").write_text(json.dumps(sample))
    res = station(
        tmp_path,
        "qc",
        "check",
        "--standard",
        "std.json",
        "--sample",
        "smp.json",
        "--formula",
        "cie76",
        "--json",
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert set(out) >= {"verdict", "formula", "per_geometry", "mean_de", "max_de", "worst_geometry"}
    assert [g["geometry"] for g in out["per_geometry"]] == measured["geometries"]
    assert [g["aspecular_deg"] for g in out["per_geometry"]] == [-15, 15, 25, 45, 75, 110]
    # ΔL* 0.9 alone: ΔE*ab = 0.9 at every geometry, in the warn band (0.8 < 0.9 <= 1)
    for g in out["per_geometry"]:
        assert g["dL"] == pytest.approx(0.9, abs=1e-9) and g["dE"] == pytest.approx(0.9, abs=1e-9)
        assert g["da"] == g["db"] == 0 and g["verdict"] == "warn"
        assert set(g) >= {"geometry", "aspecular_deg", "dL", "da", "db", "dC", "dH", "dE", "verdict"}
    assert out["verdict"] == "warn" and out["formula"] == "cie76" and out["max_de"] == pytest.approx(0.9)
    # three repeat readings in one import-style file are averaged, one of them an outlier
    reps = {
        "measurements": [
            dict(measured, lab=[[r[0] + d, r[1], r[2]] for r in measured["lab"]])
            for d in (0.0, 0.02, 2.0, 0.01)
        ]
    }
    (tmp_path / "reps.json").write_text(json.dumps(reps))
    res = inproc(
        capsys,
        tmp_path,
        "qc",
        "check",
        "--standard",
        "std.json",
        "--sample",
        "reps.json",
        "--formula",
        "cie76",
        "--json",
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["sample"]["repeats"]["n"] == 4 and out["sample"]["repeats"]["outliers"] == [2]
    # the flagged reading is left out of the mean: ΔL* (0 + 0.02 + 0.01) / 3
    assert out["sample"]["repeats"]["left_out"] == [2] and out["max_de"] == pytest.approx(0.01, abs=1e-9)
    res = inproc(
        capsys, tmp_path, "qc", "metamerism", "--standard", "std.json", "--sample", "std.json", "--json"
    )
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["max_index"] == {"A": 0.0, "F11": 0.0}  # a sample is no metamer of itself
    _refused(station(tmp_path, "qc", "check", "--standard", "nope.json", "--sample", "smp.json"), "nope.json")
    _refused(
        inproc(
            capsys,
            tmp_path,
            "qc",
            "check",
            "--standard",
            "std.json",
            "--sample",
            "smp.json",
            "--formula",
            "x",
        ),
        "formula",
    )
    short = dict(measured, geometries=measured["geometries"][:2], lab=measured["lab"][:2], spectra=None)
    (tmp_path / "short.json").write_text(json.dumps(short))
    _refused(
        inproc(capsys, tmp_path, "qc", "check", "--standard", "std.json", "--sample", "short.json"),
        "sample.geometries",
    )


def test_report_pdf_csv_and_trend(
    tmp_path: Path, db: tuple[str, Job], capsys: pytest.CaptureFixture[str]
) -> None:
    url, job = db
    res = set_standard(capsys, tmp_path, "J-100", job.standard_id, url, "--json")
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)["measurement_id"] == job.standard_id
    _refused(
        inproc(
            capsys,
            tmp_path,
            "qc",
            "standard",
            "set",
            "--job",
            "J-100",
            "--part",
            "fender",
            "--design",
            str(job.design_id),
            "--db",
            url,
        ),
        "replace",
    )
    res = station(
        tmp_path, "qc", "report", "--job", "J-100", "--out", "r.pdf", "--csv", "r.csv",
        "--formula", "cie76", "--progress", "--db", url, "--json",
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["counts"] == {"pass": 6, "warn": 0, "fail": 1} and out["written"] == ["r.pdf", "r.csv"]
    assert "7/7 pages" not in res.stderr and "4/4 pages" in res.stderr  # cover + three pages of the fender
    pdf = (tmp_path / "r.pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page\b(?!s)", pdf)) == 4
    assert not list(tmp_path.glob("*.part"))
    with (tmp_path / "r.csv").open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 3 * len(FENDER_OFFSETS)
    for row in rows:
        i = job.sample_ids.index(int(row["measurement_id"]))
        k = [15.0, 45.0, 110.0].index(float(row["aspecular_deg"]))
        assert float(row["dE"]) == pytest.approx(math.hypot(*FENDER_OFFSETS[i]), abs=1e-9)
        assert float(row["L_standard"]) == FENDER_STD[k][0]
        assert float(row["L"]) == pytest.approx(FENDER_STD[k][0] + FENDER_OFFSETS[i][0])
    res = inproc(
        capsys,
        tmp_path,
        "qc",
        "trend",
        "--job",
        "J-100",
        "--part",
        "fender",
        "--out",
        "t.png",
        "--formula",
        "cie76",
        "--db",
        url,
        "--json",
    )
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "t.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lim = json.loads(res.stdout)["limits"]["45as45"]
    de = [math.hypot(*o) for o in FENDER_OFFSETS]
    mr = sum(abs(b - a) for a, b in itertools.pairwise(de)) / (len(de) - 1)
    assert lim["centre"] == pytest.approx(sum(de) / len(de)) and lim["ucl"] == pytest.approx(
        sum(de) / len(de) + 3 * mr / D2_RANGE_OF_TWO
    )
    res = inproc(
        capsys, tmp_path, "qc", "search", "--job", "J-100", "--part", "bumper", "--db", url, "--json"
    )
    assert [m["measurement_id"] for m in json.loads(res.stdout)["measurements"]] == list(job.bumper_ids)
    engine = make_engine(url)
    with make_sessionmaker(engine)() as s:  # the functions the service calls give the same files
        assert csv_text(job_summary(s, "J-100", formula="cie76")) == (tmp_path / "r.csv").read_bytes().decode(
            "utf-8"
        )
        cover_only = pdf_bytes(job_summary(s, "J-200"))  # no standard: the cover page alone
        with pytest.raises(QcInputError, match="out"):  # refused before anything is drawn or written
            write_pdf(job_summary(s, "J-200"), tmp_path / "no-such-folder" / "r.pdf")
        with pytest.raises(QcInputError, match="part"):
            write_trend_png(job_summary(s, "J-100"), "roof", tmp_path / "t2.png")
    engine.dispose()
    assert cover_only.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page\b(?!s)", cover_only)) == 1
    panel = json.loads(res.stdout)["measurements"][0]["panel_id"]
    res = inproc(capsys, tmp_path, "qc", "correlate", "--panel", str(panel), "--db", url, "--json")
    assert res.returncode == 0, res.stderr
    bias = json.loads(res.stdout)
    # MA3 (50, 0.6, 0) against the MA6 correction (50.3, 0, 0): bias (−0.3, 0.6, 0) at each geometry
    assert (bias["instrument_a"], bias["instrument_b"]) == ("MA6 600123", "MA3 700200")
    assert [g["dL"] for g in bias["per_geometry"]] == pytest.approx([-0.3] * 3)
    assert bias["max_de"] == pytest.approx(math.hypot(0.3, 0.6))
    _refused(
        inproc(capsys, tmp_path, "qc", "correlate", "--panel", str(panel), "--a", "X9", "--db", url), "a"
    )
    res = inproc(capsys, tmp_path, "qc", "repeats", "--panel", str(panel), "--db", url, "--json")
    assert json.loads(res.stdout)["per_geometry"][0]["mean"] == pytest.approx([50.15, 0.3, 0.0])
    _refused(inproc(capsys, tmp_path, "qc", "report", "--job", "J-100", "--out", "r.txt", "--db", url), "out")
    _refused(inproc(capsys, tmp_path, "qc", "report", "--job", "J-404", "--out", "r.pdf", "--db", url), "job")
    _refused(inproc(capsys, tmp_path, "qc", "search", "--since", "last week", "--db", url), "since")
    assert not (tmp_path / "r.txt").exists()


def test_check_reads_vendor_files_through_the_importers(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # one reading written in two formats (two runs would be two readings: the simulator's noise differs)
    res = inproc(capsys, tmp_path, "measure", "sim:ma6", "--out", "s.cgats", "--out", "s.cxf", "--json")
    assert res.returncode == 0, res.stderr
    measured = json.loads(res.stdout)
    res = inproc(
        capsys,
        tmp_path,
        "qc",
        "check",
        "--standard",
        "s.cgats",
        "--sample",
        "s.cxf",
        "--formula",
        "cie76",
        "--json",
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert [g["geometry"] for g in out["per_geometry"]] == measured["geometries"]
    assert out["max_de"] < 0.01  # the same simulated panel, written in two formats (rounded Lab)
    (tmp_path / "bad.cgats").write_text("CGATS.17\nBEGIN_DATA_FORMAT\nSAMPLE_ID LAB_L\nEND_DATA_FORMAT\n")
    _refused(
        inproc(capsys, tmp_path, "qc", "check", "--standard", "bad.cgats", "--sample", "s.cxf"), "bad.cgats"
    )
