"""The lab's QC day in the viewer's QC tab, by clicks and key presses on the real widgets, the readings
arriving as a lab's do: through the watch folder.

a reading of the MA6 simulator → vendor files written by the product's writers (CxF3 with BYK-mac i
texture values, CGATS.17) into a folder that a real ``station import watch`` process serves → the SQLite
database the viewer has open → Load jobs → the standard chosen in the tab (while the watcher stores the
day's next panels) → verdicts on each panel's mean with a dirty repeat left out (named with its robust z)
→ "keep outliers" averages it in and the verdict flips → the SPC tab flags the planted drift before the
first fail → Export PDF… writes the report (its text read back) and previews its first page. At the end
the watcher is stopped with Ctrl-C and every reading of the files is in the database once: two processes
on one SQLite file lost nothing.

The simulator is read once; the repeat scatter, the dirty reading (ΔL* +4) and the drift are planted as
ΔL* offsets on it (as tests/cli/test_journey_qc.py does for the command line). Every expected ΔE00 is
computed with colour-science from the Lab stored in the database, Cp/Cpk from their closed forms.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import os
import signal
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import colour
import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QFileDialog
from sqlalchemy import select

from db.engine import make_engine, make_sessionmaker
from db.models import Measurement
from station.ingest.formats import read_measurement_file, write_measurement_file
from station.ingest.formats.measurement import ImportedMeasurement, VendorValue, from_spectral_reading
from station.model.domain import ANGLES_3, aspecular_name
from station.qc.jobs import job_summary
from station.qc.tolerance import ToleranceSet
from station.scan import open_device, take
from tests.pdf_text import pdf_text
from tests.processes import Child
from tests.ui.screens import item_at
from tests.user_cli import REPO
from tests.waiting import wait_until
from ui.models.measure_db import LocalSink
from ui.models.qc import LocalQc, QcModel
from ui.widgets.qc_panels import SPC_COLUMNS, TEXTURE_COLUMNS
from ui.widgets.qc_screen import COLUMNS, QcScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]

JOB, PART = "J-26", "door"
LIMIT = 0.6  # CIEDE2000 limit of the customer's tolerance set
STD_DL = (0.0, 0.02, -0.02)  # the standard panel's three readings
GOOD_DL = (0.10, 0.12, 0.08, 4.0, 0.11)  # trial T1's five repeats; the fourth over a speck of dirt
DIRTY = 3
SERIES_DL = (0.13, 0.09, 0.12, 0.10, 0.11, 0.20, 0.30, 0.40, 0.52, 0.70)  # S1…S10: stable, then creeping
BASELINE = 6  # T1 and S1…S5 set the control limits
T0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.UTC)
VENDOR = "BYK-mac i"
#: Texture of the standard and of T1 (ΔS 0.9 of a limit 1: warn; ΔG 0.1 of 0.5: pass).
STD_TEXTURE = (
    VendorValue(VENDOR, "sparkle_intensity", 5.0, "45as15"),
    VendorValue(VENDOR, "graininess", 4.0),
)
T1_TEXTURE = (VendorValue(VENDOR, "sparkle_intensity", 5.9, "45as15"), VendorValue(VENDOR, "graininess", 4.1))
DATABASE = "station.sqlite3"  # the lab's database, in the test's folder: the watcher's and the viewer's
D2 = 1.128  # d₂ for n = 2 as published (Montgomery, Appendix VI; ASTM E2587 Table 6)


def _planted(
    base: ImportedMeasurement, sample: str, dl: float, when: dt.datetime, texture=()
) -> ImportedMeasurement:
    assert base.lab is not None
    lab = tuple((round(v[0] + dl, 4), v[1], v[2]) for v in base.lab)
    return dataclasses.replace(
        base, sample=sample, lab=lab, wavelengths_nm=None, spectra=None, measured_at=when, texture=texture
    )


def _readings() -> dict[str, list[ImportedMeasurement]]:
    """The simulator read once, then {file name: readings}: the standard (CxF3), T1's repeats (CxF3) and
    the series (CGATS), each as the instrument software writes it."""
    with open_device("sim:ma6") as device:
        base = from_spectral_reading(take(device.instrument, device="sim:ma6").colour, "STD")
    std = [_planted(base, "STD", d, T0, STD_TEXTURE) for d in STD_DL]
    t1 = [
        _planted(base, "T1", d, T0 + dt.timedelta(minutes=i + 1), T1_TEXTURE) for i, d in enumerate(GOOD_DL)
    ]
    series = [_planted(base, f"S{i + 1}", d, T0 + dt.timedelta(hours=i + 1)) for i, d in enumerate(SERIES_DL)]
    return {"std.cxf": std, "t1.cxf": t1, "series.cgats": series}


@pytest.fixture
def watcher(tmp_path: Path) -> Iterator[Child]:
    """``station import watch inbox`` storing into the test's database as job J-26, part door (JSON lines
    of outcomes on stdout); killed with what it started at teardown if the test did not stop it."""
    (tmp_path / "inbox").mkdir()
    argv = [sys.executable, "-m", "station.cli", "import", "watch", "inbox", "--json"]
    argv += ["--store", f"sqlite:///{tmp_path / DATABASE}", "--outbox", "watch-outbox.sqlite3"]
    argv += ["--job", JOB, "--part", PART, "--settle", "0.2", "--interval", "0.1"]
    env = {k: v for k, v in os.environ.items() if k != "CACAD_DATABASE_URL"}
    env.update(PYTHONPATH=str(REPO), STATION_CACHE_DIR=str(tmp_path / "cache"), CACAD_OPERATOR="lab")
    with Child(argv, cwd=tmp_path, env=env) as child:
        yield child


def _outcomes(watcher: Child, n: int) -> dict[str, dict]:
    """{file: outcome} once the watcher has reported *n* files (its JSON lines), at most 60 s."""

    def seen() -> dict[str, dict]:
        assert watcher.out is not None and watcher.poll() is None, watcher.err and watcher.err.text()
        lines = [json.loads(li) for li in watcher.out.text().splitlines() if li.strip()]
        return {o["file"]: o for o in lines} if len(lines) >= n else {}

    return wait_until(seen, timeout=60, what=f"the watcher to report {n} files")


def _stored_ids(outcome: dict, expected: int) -> list[int]:
    """The measurement ids of a file the watcher moved to done/, every reading stored (none queued)."""
    assert outcome["status"] == "done", outcome
    assert [r["status"] for r in outcome["receipts"]] == ["stored"] * expected, outcome
    return [int(r["measurement_id"]) for r in outcome["receipts"]]


def _part(screen: QcScreen) -> dict[str, Any]:
    """The shown summary's entry for the part under test (there is one)."""
    part = screen.model.part(PART)
    assert part is not None
    return part


def _stored_lab(url: str) -> dict[int, np.ndarray]:
    engine = make_engine(url)
    try:
        with make_sessionmaker(engine)() as s:
            return {m.id: np.asarray(m.lab, dtype=float) for m in s.scalars(select(Measurement))}
    finally:
        engine.dispose()


def _type(edit, text: str) -> None:
    edit.setFocus()
    QTest.keyClick(edit, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    QTest.keyClicks(edit, text)


def _click(widget) -> None:
    assert widget.isEnabled(), widget.text()
    QTest.mouseClick(widget, Qt.MouseButton.LeftButton)


def _cells(table, name: str, columns) -> list[str]:
    j = columns.index(name)
    return [table.item(i, j).text() for i in range(table.rowCount())]


def _de00(std: np.ndarray, lab: np.ndarray) -> np.ndarray:
    return np.asarray(colour.delta_E(std, lab, method="CIE 2000"), dtype=float)


def test_the_qc_day_in_the_viewer(qtbot, tmp_path, monkeypatch, watcher):
    monkeypatch.chdir(tmp_path)  # the tolerance file typed as a lab types it: beside the work
    inbox = tmp_path / "inbox"
    readings = _readings()
    tol = ToleranceSet.uniform(ANGLES_3, LIMIT, formula="cie2000", mean_limit=LIMIT, name="customer")
    (tmp_path / "tol.json").write_text(json.dumps(tol.to_dict()))
    url = f"sqlite:///{tmp_path / DATABASE}"
    sink = LocalSink(url, tmp_path / "outbox.sqlite3")
    screen = QcScreen(QcModel(LocalQc(url)), sink=sink)
    qtbot.addWidget(screen)
    screen.resize(1280, 900)
    screen.show()
    _click(screen.load_btn)  # the viewer opens the lab's database (made here); nothing measured yet
    assert screen.status.text() == f"0 jobs from database {url}" and screen.job.count() == 0

    # the instrument software writes the standard's and T1's readings into the watched folder
    for name in ("std.cxf", "t1.cxf"):
        write_measurement_file(readings[name], inbox / name)
    done = _outcomes(watcher, 2)
    std_ids, t1_ids = (_stored_ids(done[n], len(readings[n])) for n in ("std.cxf", "t1.cxf"))

    # Load jobs picks up what the watcher stored; the job is picked
    _click(screen.load_btn)
    assert screen.status.text() == f"1 jobs from database {url}"
    screen.job.setCurrentIndex(screen.job.findText(JOB))
    assert screen.job.currentText() == JOB and screen.part.currentText() == PART

    # judging as the lab does: CIEDE2000 with the customer's tolerance file, panels averaged, texture limits
    screen.formula.setCurrentIndex(screen.formula.findText("cie2000"))
    _type(screen.tolerance, "tol.jsn")  # a typo: said, nothing judged
    _click(screen.judge_btn)
    assert screen.status.text().startswith("error: tolerance: expected a readable tolerance set JSON file")
    assert screen.table.rowCount() == 0 and not screen.pdf_btn.isEnabled()
    _type(screen.tolerance, "tol.json")
    _type(screen.texture_limits, "ds=1,dg=0.5")
    assert not screen.keep_outliers.isEnabled()
    _click(screen.average)
    assert screen.average.isChecked() and screen.keep_outliers.isEnabled()
    _click(screen.judge_btn)
    assert screen.job.currentText() == JOB and "no standard set" in screen.standard.text()
    # the day's next panels arrive as the standard is set: in the same seconds the watcher stores them and
    # the viewer writes the standard and judges, each process on the one SQLite file
    write_measurement_file(readings["series.cgats"], inbox / "series.cgats")
    # the standard: the simulator's own reading, averaged with its two repeats
    screen.standard_pick.setCurrentIndex(screen.standard_pick.findData(std_ids[0]))
    _click(screen.set_standard_btn)
    assert f"standard: measurement {std_ids[0]}" in screen.standard.text(), screen.status.text()
    series_ids = _stored_ids(_outcomes(watcher, 3)["series.cgats"], len(readings["series.cgats"]))
    _click(screen.judge_btn)  # judged again with the whole series

    # independent expectation: ΔE00 of T1's mean (without / with the dirty reading) against the standard's mean
    lab = _stored_lab(url)
    judged = [aspecular_name(a) for a in ANGLES_3]
    geoms = _part(screen)["standard"]["geometries"]
    idx = [geoms.index(g) for g in judged]
    std_mean = np.mean([lab[i] for i in std_ids], axis=0)[idx]
    kept = [lab[i] for k, i in enumerate(t1_ids) if k != DIRTY]
    kept_de = float(_de00(std_mean, np.mean(kept, axis=0)[idx]).max())
    all_de = float(_de00(std_mean, np.mean([lab[i] for i in t1_ids], axis=0)[idx]).max())
    assert kept_de < LIMIT < all_de  # the dirty reading alone decides T1's verdict

    def t1() -> dict:
        (s,) = [s for s in _part(screen)["samples"] if s.get("measurement_ids") == t1_ids]
        return s

    def t1_rows() -> list[int]:
        return [
            i
            for i, v in enumerate(_cells(screen.table, "sample", COLUMNS))
            if v == str(t1()["measurement_id"])
        ]

    s = t1()
    assert s["qc"]["verdict"] == "pass" and s["qc"]["max_de"] == pytest.approx(kept_de, abs=1e-9)
    assert s["left_out"] == [t1_ids[DIRTY]]
    shown = [float(_cells(screen.table, "ΔE", COLUMNS)[i]) for i in t1_rows()]
    assert max(shown) == pytest.approx(kept_de, abs=0.005)
    assert {_cells(screen.table, "verdict", COLUMNS)[i] for i in t1_rows()} <= {"pass", "warn"}
    said = screen.outliers.text()
    assert (
        f"panel {s['panel_id']}: measurement {t1_ids[DIRTY]} left out (robust z" in said
        and "mean of 4 of 5" in said
    )
    # the texture of T1 against the standard's, one vendor: ΔS 0.9 warns, ΔG 0.1 passes
    assert screen.texture_table.isVisible()
    tex = {
        (r[3], r[4]): r
        for r in (
            [item_at(screen.texture_table, i, j).text() for j in range(len(TEXTURE_COLUMNS))]
            for i in range(screen.texture_table.rowCount())
        )
    }
    assert tex[("sparkle_intensity", "45as15")][5:] == ["5.00", "5.90", "0.90", "ΔS ≤ 1", "warn"]
    assert tex[("graininess", "sample")][7:] == ["0.10", "ΔG ≤ 0.5", "pass"]
    _grab(screen, tmp_path / "qc-left-out.png")

    # keep outliers: judged again with the dirty reading in, the verdict flips — the CLI's numbers exactly
    _click(screen.keep_outliers)
    s = t1()
    assert s["qc"]["verdict"] == "fail" and s["qc"]["max_de"] == pytest.approx(all_de, abs=1e-9)
    assert "fail" in {_cells(screen.table, "verdict", COLUMNS)[i] for i in t1_rows()}
    assert f"measurement {t1_ids[DIRTY]} kept although flagged" in screen.outliers.text()
    cli = {keep: _cli_t1(url, tol, keep, t1_ids) for keep in (True, False)}
    assert cli[True] == s["qc"]
    _click(screen.keep_outliers)
    assert t1()["qc"]["verdict"] == "pass" and t1()["qc"] == cli[False]

    # SPC: individuals chart, limits from the first six panels; the drift flagged before the first fail
    QTest.mouseClick(
        screen.views.tabBar(), Qt.MouseButton.LeftButton, pos=screen.views.tabBar().tabRect(1).center()
    )
    assert screen.views.currentIndex() == 1
    _type(screen.spc.baseline, str(BASELINE))
    _click(screen.spc.draw_btn)
    panels = [kept, *([lab[i]] for i in series_ids)]
    _check_spc(screen, panels, std_mean, judged, idx)
    _grab(screen, tmp_path / "qc-spc.png")
    # X̄/R of consecutive pairs, limits from the first three: R̄ = mean range of those pairs
    screen.spc.subgroup.setCurrentIndex(screen.spc.subgroup.findData(2))
    _type(screen.spc.baseline, "3")
    _click(screen.spc.draw_btn)
    assert "X̄/R chart, subgroups of 2, limits from the first 3" in screen.spc.text.toPlainText()
    de = _de00(
        np.repeat(std_mean[None, 0], len(panels), axis=0),
        np.array([np.mean(p, axis=0)[idx][0] for p in panels]),
    )
    r_bar = float(np.abs(de[1:6:2] - de[0:6:2]).mean())
    r_cells = item_at(screen.spc.table, 0, SPC_COLUMNS.index("R̄ / R UCL")).text().split(" / ")
    assert float(r_cells[0]) == pytest.approx(r_bar, abs=6e-4) and float(r_cells[1]) == pytest.approx(
        3.267 * r_bar, abs=6e-4
    )

    # the PDF report from the tab, its first page previewed
    pdf = tmp_path / "report.pdf"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: (str(pdf), "")))
    _click(screen.pdf_btn)
    qtbot.waitUntil(lambda: screen.last_report == pdf and screen.pdf_btn.isEnabled(), timeout=60000)
    text = pdf_text(pdf.read_bytes())
    samples = _part(screen)["samples"]
    for t in samples:  # every trial named by its panel, part and job
        assert f"panel {t['panel_id']}, {PART}, {JOB}" in text
    assert "before the" in text and "rst fail" in text  # the SPC page's drift line ("fi": a ligature)
    assert screen.preview_png.startswith(b"\x89PNG") and not screen.preview.pixmap().isNull()
    QTest.mouseClick(
        screen.views.tabBar(), Qt.MouseButton.LeftButton, pos=screen.views.tabBar().tabRect(2).center()
    )
    _grab(screen, tmp_path / "qc-preview.png")
    screen.close()
    sink.close()

    # Ctrl-C ends the watcher cleanly; every reading of the three files is in the database once
    watcher.send_signal(signal.SIGINT)
    assert watcher.finish(timeout=30) == 0, watcher.err and watcher.err.text()
    assert sorted(p.name for p in (inbox / "done").iterdir()) == sorted(readings)
    assert not list((inbox / "rejected").iterdir())
    in_files = sum(len(read_measurement_file(p).measurements) for p in (inbox / "done").iterdir())
    stored = _stored_lab(url)
    assert len(stored) == in_files == len(STD_DL) + len(GOOD_DL) + len(SERIES_DL)
    assert sorted(stored) == sorted(std_ids + t1_ids + series_ids)


def _cli_t1(url: str, tol: ToleranceSet, keep: bool, t1_ids: list[int]) -> Mapping[str, object]:
    """T1's verdict as ``station qc summary --average-panels [--keep-outliers]`` computes it."""
    engine = make_engine(url)
    try:
        with make_sessionmaker(engine)() as session:
            out = job_summary(session, JOB, tol, "cie2000", None, True, keep_outliers=keep).to_dict()
    finally:
        engine.dispose()
    (s,) = [s for s in out["parts"][0]["samples"] if s.get("measurement_ids") == t1_ids]
    return s["qc"]


def _check_spc(screen, panels, std_mean, judged, idx) -> None:
    """ΔE00 per panel mean and geometry by colour-science: the first fail, a drift flagged before it,
    and Cp/Cpk from the baseline's moving range (Cp = USL / 6σ, Cpk = (USL − mean) / 3σ, σ = MR̄ / d₂)."""
    means = np.array([np.mean(p, axis=0)[idx] for p in panels])  # panels × judged geometries × 3
    rows = {r: i for i, r in enumerate(_cells(screen.spc.table, "geometry", SPC_COLUMNS))}
    assert sorted(rows) == sorted(judged)
    text = screen.spc.text.toPlainText()
    failing = 0
    for k, g in enumerate(judged):
        de = _de00(np.repeat(std_mean[k][None], len(means), axis=0), means[:, k])
        base = de[:BASELINE]
        sigma = np.abs(np.diff(base)).mean() / D2
        cell = {c: screen.spc.table.item(rows[g], SPC_COLUMNS.index(c)).text() for c in SPC_COLUMNS}
        assert float(cell["centre"]) == pytest.approx(base.mean(), abs=6e-4)
        assert float(cell["UCL"]) == pytest.approx(base.mean() + 3 * sigma, abs=6e-4)
        assert float(cell["Cp"]) == pytest.approx(LIMIT / (6 * sigma), abs=0.006)
        assert float(cell["Cpk"]) == pytest.approx((LIMIT - base.mean()) / (3 * sigma), abs=0.006)
        first_fail = next((i for i, v in enumerate(de) if v > LIMIT), None)
        if first_fail is None:
            continue
        failing += 1
        line = next(li for li in text.splitlines() if li.startswith(f"DRIFT {g}: drift from sample #"))
        flagged = int(line.split("#")[1].split(" ")[0]) - 1
        assert flagged < first_fail and de[flagged] < LIMIT, (line, de)
        assert f"before the first fail (sample #{first_fail + 1})" in line
        assert cell["rule hits"] != "none"
    assert failing  # the planted drift ends in a fail at some geometry
    assert screen.spc.png.startswith(b"\x89PNG") and not screen.spc.chart.pixmap().isNull()


def _grab(screen, path: Path) -> None:
    """The tab as the technician sees it (kept with the test's files to look at)."""
    assert screen.grab().save(str(path))
