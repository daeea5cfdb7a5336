"""End to end as a user runs it, from a temporary folder: the simulator writes vendor files
(``station measure sim:ma6 --out``), ``station import`` prints and stores them, ``station import watch``
ingests a drop folder into a real SQLite database, and ``station qc verdict`` judges the stored sample
against the stored standard (ΔE*ab checked against the closed form on the stored rows)."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import func, select

from db.engine import make_engine
from db.models import Measurement, Panel
from station.model.design_io import save_design
from station.model.representations import FaceFlopTravelGloss
from tests.user_cli import run_station


def station(cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args, env={"CACAD_OPERATOR": "qa"})


def _rows(url: str) -> tuple[list[Measurement], list[Panel]]:
    engine = make_engine(url)
    try:
        with engine.connect() as conn:
            ms = list(conn.execute(select(Measurement).order_by(Measurement.id)).all())
            ps = list(conn.execute(select(Panel).order_by(Panel.id)).all())
    finally:
        engine.dispose()
    return ms, ps  # type: ignore[return-value]


def _count(url: str) -> int:
    engine = make_engine(url)
    try:
        with engine.connect() as conn:
            return int(conn.execute(select(func.count()).select_from(Measurement)).scalar_one())
    finally:
        engine.dispose()


def test_simulator_to_watch_folder_to_database_to_verdict(
    tmp_path: Path,
    _migrated_sqlite: Path,
    sim_files: tuple[dict[str, object], dict[str, Path]],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from station.cli import main  # in this process, for the checks that need no process of their own

    db = tmp_path / "station.sqlite3"
    shutil.copyfile(_migrated_sqlite, db)
    url = f"sqlite:///{db}"
    store = ["--store", url, "--outbox", str(tmp_path / "outbox.sqlite3")]
    # the standard: the simulated MA-T12-style reading of std.json (two illumination blocks) as CxF3
    drop = tmp_path / "drop"
    drop.mkdir()
    shutil.copy(sim_files[1]["cxf"], drop / "std.cxf")
    # the trial: the simulator measuring a slightly different design, written as CGATS.17
    save_design(FaceFlopTravelGloss((81.2, -2.6, -21.0), (30.8, 1.3, -8.5), 60.0), tmp_path / "smp.json")
    res = station(
        tmp_path, "measure", "sim:ma6", "--design", "smp.json", "--sample", "trial 1", "--out", "smp.cgats"
    )
    assert res.returncode == 0, res.stderr

    # station import FILE --store --json: the contract, stored on a job and part
    res = station(tmp_path, "import", "smp.cgats", *store, "--job", "J-100", "--part", "fender", "--json")
    assert res.returncode == 0, res.stderr
    printed = json.loads(res.stdout)
    (m,) = printed["measurements"]
    assert m["sample"] == "trial 1" and m["geometries"] == [
        "45as-15",
        "45as15",
        "45as25",
        "45as45",
        "45as75",
        "45as110",
    ]
    assert len(m["lab"]) == 6 and all(len(v) == 3 for v in m["lab"]) and len(m["spectra"]) == 6
    assert m["instrument"]["model"] == "MA6" and m["instrument"]["serial"]
    assert [r["status"] for r in printed["stored"]] == ["stored"]

    # a malformed file: exit 2, one line naming file, line and field, nothing stored
    good = (tmp_path / "smp.cgats").read_text(encoding="utf-8").splitlines()
    bad = list(good)
    row = bad.index("BEGIN_DATA") + 2  # the second data row
    cells = bad[row].split(" ")  # id, '"trial', '1"', geometry, L*, …
    cells[4] = "nan"
    bad[row] = " ".join(cells)
    (tmp_path / "bad.cgats").write_text("\n".join(bad) + "\n", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert main(["import", "bad.cgats", *store, "--job", "J-100", "--part", "fender"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"bad.cgats, line {row + 1}" in err and "lab.L" in err
    assert _count(url) == 1

    # the watch folder: a good CxF, the good CGATS (already stored), a truncated CSV
    shutil.copy(tmp_path / "smp.cgats", drop / "smp.cgats")
    (drop / "broken.csv").write_text("sample,geometry,L,a,b\nx,45as15,50,1\n", encoding="utf-8")
    (drop / ".hidden.cxf").write_text("ignored", encoding="utf-8")
    res = station(tmp_path, "import", "watch", "drop", "--once", "--settle", "0", *store,
                  "--job", "J-100", "--part", "fender", "--json")  # fmt: skip
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert (out["done"], out["rejected"]) == (2, 1)
    status = {f["file"]: [r["status"] for r in f["receipts"]] for f in out["files"]}
    # the standard's file holds two illumination blocks: one measurement each
    assert status == {"broken.csv": [], "smp.cgats": ["duplicate"], "std.cxf": ["stored", "stored"]}
    assert sorted(p.name for p in (drop / "done").iterdir()) == ["smp.cgats", "std.cxf"]
    reason = (drop / "rejected" / "broken.csv.reason").read_text(encoding="utf-8")
    assert "CsvImportError" in reason and "broken.csv, line 2" in reason and "row" in reason
    assert (drop / "rejected" / "broken.csv").is_file() and (drop / ".hidden.cxf").is_file()

    ms, ps = _rows(url)
    assert len(ms) == 3 and [(p.job, p.part, p.notes) for p in ps] == [
        ("J-100", "fender", "sample: trial 1"),
        ("J-100", "fender", "sample: std panel"),
    ]
    smp, std, std15 = ms  # the sample was stored first, then the standard's 45° and 15° blocks
    assert smp.panel_id == ps[0].id and std.panel_id == std15.panel_id == ps[1].id
    assert (smp.illumination_deg, std.illumination_deg, std15.illumination_deg) == (45.0, 45.0, 15.0)
    assert std.geometries_deg == smp.geometries_deg == [-15.0, 15.0, 25.0, 45.0, 75.0, 110.0]

    # QC verdict on the stored rows: ΔE*ab per geometry is the Euclidean distance (CIE76)
    def triples(lab: list[list[float]]) -> str:
        return ";".join(",".join(repr(v) for v in t) for t in lab)

    assert main(["qc", "verdict", "--standard", triples(std.lab), "--sample", triples(smp.lab),
                 "--angles=-15,15,25,45,75,110", "--formula", "cie76", "--limit", "2.0", "--json"]) == 0  # fmt: skip
    verdict = json.loads(capsys.readouterr().out)
    by_hand = [math.dist(a, b) for a, b in zip(std.lab, smp.lab, strict=True)]
    assert [g["dE"] for g in verdict["per_geometry"]] == pytest.approx(by_hand, rel=1e-9)
    assert verdict["max_de"] == pytest.approx(max(by_hand))
    expected = "fail" if max(by_hand) > 2.0 else "warn" if max(by_hand) > 0.8 * 2.0 else "pass"
    assert verdict["verdict"] == expected
    assert 0.5 < max(by_hand) < 5.0  # the two designs differ by about 1.5 ΔE*ab at the face
    # the simulator's Lab (measure rounds Lab of the raw spectra, the file Lab of spectra rounded to 1e-6)
    assert np.asarray(std.lab) == pytest.approx(np.asarray(sim_files[0]["lab"][:6]), abs=1e-4 + 1e-9)  # type: ignore[index]


def test_import_refusals(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "latin1.csv").write_bytes(
        "sample,geometry,L,a,b\npaneel \xe9,45as15,50,1,2\n".encode("latin-1")
    )
    res = station(tmp_path, "import", "latin1.csv")
    assert res.returncode == 2 and res.stdout == ""
    assert (
        res.stderr
        == "error: encoding: expected UTF-8 (or ASCII) text, got 'byte 0xe9' (latin1.csv, line 2)\n"
    )

    from station.cli import main  # the same parser and runner, in this process (faster)

    monkeypatch.chdir(tmp_path)
    (tmp_path / "ok.csv").write_text("sample,geometry,L,a,b\np,45as15,50,1,2\n", encoding="utf-8")
    for argv, message in (
        (["import", "missing.cgats"], "FILE: expected an existing measurement file"),
        (["import", "watch", "nowhere", "--once"], "DIR: expected an existing folder"),
        (
            ["import", "ok.csv", "--store", "sqlite:///x.sqlite3", "--job", "J", "--part", "wing"],
            "--part: expected bumper |",
        ),
        (
            ["import", "ok.csv", "--store", "sqlite:///x.sqlite3", "--job", "J"],
            "--part: expected --job J and --part P together",
        ),
        (
            ["import", "ok.csv", "--store", "sqlite:///x.sqlite3", "--illumination", "15"],
            "illumination_deg: expected one of [45.0]",
        ),
        (["measure", "sim:ma6", "--out", "x.pdf"], "--out: expected a file ending in .cxf"),
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "x.sqlite3").exists()  # refused before the database was opened
