"""SIGKILL a real ``station import watch`` process while it ingests a drop folder, then restart it:
every file ends in ``done/`` exactly once, every measurement of every file is stored exactly once
(under the client id its bytes give), and the stored Lab is the file's."""

from __future__ import annotations

import os
import random
import shutil
import signal
import subprocess
import sys
from pathlib import Path

from sqlalchemy import select

from db.engine import make_engine
from db.models import Measurement
from station.ingest.errors import ImportFileError
from station.ingest.formats import build_measurement, import_client_id, write_measurement_file
from station.ingest.formats.measurement import OBSERVERS, Instrument
from station.ingest.formats.records import file_sha256
from station.model.domain import ANGLES_6, aspecular_name
from tests.processes import Child
from tests.waiting import wait_until

REPO = Path(__file__).resolve().parents[2]
FILES = 30
KILLS = 1
SAMPLES = 2
FORMATS = ("cxf", "cgats", "csv")


def _write_drop(drop: Path, rng: random.Random) -> dict[str, list[list[list[float]]]]:
    """FILES files of SAMPLES samples each (Lab only, the 6-angle set); returns name → Lab per sample."""
    expected = {}
    geometries = [aspecular_name(a) for a in ANGLES_6]

    def err(fld: str, accepted: str, got: object) -> ImportFileError:
        return ImportFileError("generated", "", fld, accepted, got)

    for n in range(FILES):
        samples = []
        for s in range(SAMPLES):
            lab = [[round(rng.uniform(20, 90), 4), round(rng.uniform(-20, 20), 4), round(rng.uniform(-20, 20), 4)]
                   for _ in geometries]  # fmt: skip
            samples.append(
                build_measurement(
                    sample=f"panel {n}-{s}",
                    rows=[(g, err) for g in geometries],
                    lab=lab,
                    wavelengths_nm=None,
                    spectra=None,
                    instrument=Instrument("MA-T6", f"SN{n}"),
                    illuminant="D65",
                    observer=OBSERVERS[1],
                    measured_at=None,
                    err=err,
                )
            )
        name = f"m{n:02d}.{FORMATS[n % 3]}"
        tmp = drop / (name + ".part")  # written aside, then renamed in: the watcher skips .part files
        write_measurement_file(samples, tmp, FORMATS[n % 3])
        os.replace(tmp, drop / name)
        expected[name] = [[list(v) for v in m.lab or ()] for m in samples]
    return expected


def _spawn(cwd: Path, url: str, *extra: str) -> Child:
    """``station import watch drop`` (and *extra*) in *cwd*, its stderr read into ``child.err``."""
    env = dict(os.environ, PYTHONPATH=str(REPO), CACAD_OPERATOR="qa")
    return Child(
        [sys.executable, "-m", "station.cli", "import", "watch", "drop", "--settle", "0", "--interval", "0.05",
         "--store", url, "--outbox", str(cwd / "outbox.sqlite3"), *extra],
        cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )  # fmt: skip


def test_killed_watcher_ingests_each_file_exactly_once(tmp_path: Path, _migrated_sqlite: Path) -> None:
    db = tmp_path / "station.sqlite3"
    shutil.copyfile(_migrated_sqlite, db)
    url = f"sqlite:///{db}"
    drop = tmp_path / "drop"
    drop.mkdir()
    rng = random.Random(int.from_bytes(os.urandom(4), "little"))
    expected = _write_drop(drop, rng)
    shas = {name: file_sha256(drop / name) for name in expected}
    killed_mid_run = 0
    for _ in range(KILLS):
        # Kill it at a random point of the run: once a random number of files (1 .. FILES/2) is done. A
        # random delay after the first file let a fast machine finish all 30 before the kill landed.
        target = rng.randint(1, FILES // 2)
        with _spawn(tmp_path, url) as proc:

            def reached(n: int = target) -> bool:
                return (drop / "done").exists() and len(list((drop / "done").iterdir())) >= n

            wait_until(reached, 90, interval=0.001, what=f"{target} files done")
            proc.send_signal(signal.SIGKILL)
            assert proc.wait(10) == -signal.SIGKILL, proc.err.text() if proc.err else ""
        left = [p for p in drop.iterdir() if p.is_file()]
        killed_mid_run += bool(left)
    with _spawn(tmp_path, url, "--once") as proc:
        assert proc.finish(120) == 0, proc.err.text() if proc.err else ""
    assert killed_mid_run == KILLS, "the kill landed after the folder was empty: the test proved nothing"

    assert [p.name for p in drop.iterdir() if p.is_file()] == []
    assert sorted(p.name for p in (drop / "done").iterdir()) == sorted(expected)
    assert list((drop / "rejected").iterdir()) == []
    assert [p.name for p in (drop / "processing").iterdir()] == []  # every claim folder given back
    engine = make_engine(url)
    with engine.connect() as conn:
        rows = conn.execute(select(Measurement.client_id, Measurement.lab, Measurement.geometries_deg)).all()
    engine.dispose()
    assert len(rows) == FILES * SAMPLES, "a measurement is missing or stored twice"
    stored = {str(r.client_id): r for r in rows}
    for name, labs in expected.items():
        for i, lab in enumerate(labs):
            row = stored[str(import_client_id(shas[name], i, 45))]
            assert row.lab == lab and row.geometries_deg == list(ANGLES_6)
