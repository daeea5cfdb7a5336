"""A watch folder that stays inside: a real ``station import watch`` process against hostile drops.

Linked work folders make the watcher refuse to run (nothing moved through the link); dropped links,
FIFOs and hard links are rejected without being read (the file they point at is never echoed);
``.reason`` files are 0600 and hold no byte of the file; a file still being written is never imported
half; two watchers on one folder give every file exactly one outcome.
"""

from __future__ import annotations

import os
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from sqlalchemy import func, select

from db.engine import make_engine
from db.models import Measurement
from tests.processes import Child, run
from tests.waiting import WaitTimeout, wait_until

REPO = Path(__file__).resolve().parents[2]
#: A secret the dropped links point at: it must never appear in a reason, a log line or the output.
SECRET = "tok-3f9c1e7ab25d"
CSV_HEAD = "sample,geometry,L,a,b\n"


def _csv(sample: str, n: int = 2) -> str:
    rows = [f"{sample},45as{g},{50 + g / 10},1,2" for g in (15, 45, 75, 110)[:n]]
    return CSV_HEAD + "\n".join(rows) + "\n"


def _cgats(samples: list[str], end: bool = True) -> str:
    head = [
        "CGATS.17",
        "BEGIN_DATA_FORMAT",
        "SAMPLE_ID GEOMETRY LAB_L LAB_A LAB_B",
        "END_DATA_FORMAT",
        "BEGIN_DATA",
    ]
    rows = [f"{s} 45as{g} {40 + g / 10} 1.5 -2" for s in samples for g in (15, 45)]
    return "\n".join(head + rows + (["END_DATA"] if end else [])) + "\n"


class Station:
    """A throwaway SQLite database and the ``station`` processes started against it (killed at the end)."""

    def __init__(self, root: Path, template: Path) -> None:
        self.root = root
        self.db = root / "station.sqlite3"
        shutil.copyfile(template, self.db)
        self.url = f"sqlite:///{self.db}"
        self.drop = root / "drop"
        self.drop.mkdir()
        self.procs: list[Child] = []

    def _argv(self, *extra: str) -> list[str]:
        return [sys.executable, "-m", "station.cli", "import", "watch", "drop", "--store", self.url,
                "--outbox", str(self.root / "outbox.sqlite3"), *extra]  # fmt: skip

    def _env(self) -> dict[str, str]:
        return dict(os.environ, PYTHONPATH=str(REPO), CACAD_OPERATOR="qa")

    def once(self, *extra: str) -> subprocess.CompletedProcess[str]:
        """``station import watch drop --once --settle 0`` (and *extra*), run to its end."""
        return run(self._argv("--once", "--settle", "0", *extra), cwd=self.root, env=self._env(), timeout=120)

    def start(self, *extra: str) -> Child:
        """A watcher running in the background (stopped with :meth:`stop`, killed at teardown); its
        stdout and stderr are read into the child's streams (:meth:`ready` reads its stderr)."""
        proc = Child(self._argv(*extra), cwd=self.root, env=self._env())
        self.procs.append(proc)
        return proc

    def ready(self, proc: Child) -> bool:
        """Whether *proc* (a :meth:`start` watcher) says it is watching."""
        assert proc.err is not None
        return "watching drop" in proc.err.text()

    def stop(self, proc: Child) -> None:
        """Ctrl-C *proc* and wait (at most 30 s) for it to end."""
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)

    def kill_all(self) -> None:
        """Kill every watcher still running (with what it started) and close its pipes."""
        for proc in self.procs:
            proc.close()

    def stored(self) -> int:
        engine = make_engine(self.url)
        try:
            with engine.connect() as conn:
                return int(conn.execute(select(func.count()).select_from(Measurement)).scalar_one())
        finally:
            engine.dispose()


@pytest.fixture
def station(tmp_path: Path, _migrated_sqlite: Path) -> Iterator[Station]:
    st = Station(tmp_path, _migrated_sqlite)
    try:
        yield st
    finally:
        st.kill_all()


def _wait(cond: Callable[[], bool], timeout_s: float = 60.0) -> bool:
    """Whether *cond* came true within *timeout_s* seconds (polled every 0.02 s)."""
    try:
        wait_until(cond, timeout_s, interval=0.02)
    except WaitTimeout:
        return False
    return True


def _tree(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.mark.parametrize("work", ["done", "rejected"])
def test_a_linked_work_folder_makes_the_watcher_refuse(station: Station, work: str) -> None:
    """``done/`` or ``rejected/`` made beforehand as a symbolic link: the watcher refuses to run with
    one line naming it, and nothing is moved through the link (the attacker's files stay where
    they were dropped)."""
    target = station.root / "dot-ssh"
    target.mkdir()
    (station.drop / work).symlink_to(target)
    (station.drop / "authorized_keys").write_text("ssh-ed25519 AAAAC3Nza attacker@host\n")
    (station.drop / "good.csv").write_text(_csv("p1"))
    res = station.once()
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{work}: expected a folder the watcher makes" in lines[0], res.stderr
    assert "a symbolic link" in lines[0]
    assert list(target.iterdir()) == []
    assert (station.drop / "authorized_keys").is_file() and (station.drop / "good.csv").is_file()
    assert (station.drop / work).is_symlink() and station.stored() == 0


def test_a_work_folder_that_is_a_file_or_foreign_is_refused(station: Station) -> None:
    (station.drop / "done").write_text("not a folder")
    res = station.once()
    assert res.returncode == 2 and "done: expected a folder the watcher makes" in res.stderr
    assert (station.drop / "done").read_text() == "not a folder"
    if os.geteuid() == 0:  # only root can give a folder away: the other user's folder is not used
        (station.drop / "done").unlink()
        (station.drop / "rejected").mkdir(mode=0o755)
        os.chown(station.drop / "rejected", 4321, 4321)
        (station.drop / "bad.csv").write_text("nothing,here\n")
        res = station.once()
        assert res.returncode == 2 and "rejected: expected a folder" in res.stderr
        assert "user id 4321" in res.stderr and (station.drop / "bad.csv").is_file()
        assert stat.S_IMODE((station.drop / "rejected").stat().st_mode) == 0o755


def test_links_fifos_and_hard_links_are_rejected_unread(station: Station) -> None:
    """A dropped symlink to the service's token (and to /etc/passwd), a FIFO and a hard link to the
    token go to ``rejected/`` as they are, without being opened: no reason, log line or output holds
    a byte of what they point at, and the token itself is untouched."""
    private = station.root / "data"
    private.mkdir(mode=0o700)
    token = private / "bootstrap-token"
    token.write_text(SECRET + "\n")
    token.chmod(0o600)
    (station.drop / "token.csv").symlink_to(token)
    (station.drop / "passwd.csv").symlink_to("/etc/passwd")
    (station.drop / "hard.csv").hardlink_to(token)
    os.mkfifo(station.drop / "pipe.cgats")
    res = station.once("--json")
    assert res.returncode == 0, res.stderr
    rejected = station.drop / "rejected"
    assert _tree(rejected) == sorted(f"{n}{s}" for n in ("hard.csv", "passwd.csv", "pipe.cgats", "token.csv")
                                     for s in ("", ".reason"))  # fmt: skip
    assert (rejected / "token.csv").is_symlink() and os.readlink(rejected / "token.csv") == str(token)
    assert stat.S_ISFIFO((rejected / "pipe.cgats").lstat().st_mode)
    reasons = {p.name: p for p in rejected.glob("*.reason")}
    for p in reasons.values():
        assert stat.S_IMODE(p.stat().st_mode) == 0o600, p.name
        text = p.read_text()
        assert SECRET not in text and "root:" not in text, text
    assert "a symbolic link" in reasons["token.csv.reason"].read_text()
    assert "a FIFO" in reasons["pipe.cgats.reason"].read_text()
    assert "hard link" in reasons["hard.csv.reason"].read_text()
    assert SECRET not in res.stdout + res.stderr and "root:" not in res.stdout + res.stderr
    assert token.read_text() == SECRET + "\n" and stat.S_IMODE(token.stat().st_mode) == 0o600
    assert station.stored() == 0
    for name in ("done", "rejected", "processing"):  # the watcher's own folders: made private
        st = (station.drop / name).lstat()
        assert stat.S_ISDIR(st.st_mode) and stat.S_IMODE(st.st_mode) == 0o700, name


def test_reasons_hold_no_byte_of_the_file(station: Station) -> None:
    """Files that fail in ways whose errors carry the offending value (a bad number, a missing
    column, an unknown format, a repeated geometry): the reason names the class, field, accepted form
    and line, never the value; 0600; and the log line on stderr is the same."""
    marks = [f"Zq{n}x{SECRET}" for n in range(5)]
    (station.drop / "number.csv").write_text(CSV_HEAD + f"p1,45as15,{marks[0]},1,2\n")
    (station.drop / "header.csv").write_text(f"{marks[1]},geometry\n")
    (station.drop / "number.cgats").write_text(_cgats(["s1"]).replace("1.5", marks[2], 1))
    (station.drop / "keys").write_text(f"ssh-ed25519 {marks[3]}\n")
    (station.drop / "twice.csv").write_text(
        CSV_HEAD + f"{marks[4]},45as15,50,1,2\n{marks[4]},45as15,50,1,2\n"
    )
    res = station.once("--json")
    assert res.returncode == 0, res.stderr
    reasons = sorted((station.drop / "rejected").glob("*.reason"))
    assert [p.name for p in reasons] == sorted(
        f"{n}.reason" for n in ("number.csv", "header.csv", "number.cgats", "keys", "twice.csv")
    )
    for p in reasons:
        text = p.read_text()
        assert stat.S_IMODE(p.stat().st_mode) == 0o600, p.name
        assert text.count("\n") == 1 and "expected" in text, text
        assert not any(m in text for m in marks) and SECRET not in text, text
    assert (
        "CsvImportError: L: expected a number (number.csv, line 2)"
        in (station.drop / "rejected/number.csv.reason").read_text()
    )
    assert SECRET not in res.stdout + res.stderr
    assert station.stored() == 0


def test_a_file_still_being_written_is_never_imported_half(station: Station) -> None:
    """CGATS without END_DATA yet, CxF with its root open, a CSV cut inside a row: each is left in the
    folder for as long as the watcher is told to be patient (here two hours; an hour-old file waits);
    once finished it is imported whole (4 samples, not 2)."""
    full_cgats = _cgats(["s1", "s2", "s3", "s4"])
    cut = full_cgats.index("s3 ")
    (station.drop / "slow.cgats").write_text(full_cgats[:cut])
    (station.drop / "slow.csv").write_text(CSV_HEAD + "c1,45as15,50,1,2\nc1,45as45,40,1")
    long_ago = time.time() - 3600
    for p in station.drop.iterdir():
        os.utime(p, (long_ago, long_ago))  # settled: unchanged for an hour
    res = station.once("--json", "--abandon", "7200")
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in station.drop.iterdir() if p.is_file()) == ["slow.cgats", "slow.csv"]
    assert list((station.drop / "done").iterdir()) == list((station.drop / "rejected").iterdir()) == []
    assert station.stored() == 0
    with (station.drop / "slow.cgats").open("a") as fh:
        fh.write(full_cgats[cut:])
    with (station.drop / "slow.csv").open("a") as fh:
        fh.write(".5,2.5\n")
    res = station.once("--json", "--abandon", "7200")
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in (station.drop / "done").iterdir()) == ["slow.cgats", "slow.csv"]
    assert station.stored() == 5


def test_a_file_left_unfinished_past_the_patience_is_rejected_as_incomplete(station: Station) -> None:
    """The same cut CGATS, unchanged for an hour: with the default patience (600 s) it is rejected as
    Incomplete (never half imported); a cut file written just now still waits; a bad --abandon is one
    line and exit 2 with nothing moved."""
    full_cgats = _cgats(["s1", "s2", "s3", "s4"])
    cut = full_cgats[: full_cgats.index("s3 ")]
    (station.drop / "old.cgats").write_text(cut)
    long_ago = time.time() - 3600
    os.utime(station.drop / "old.cgats", (long_ago, long_ago))
    (station.drop / "new.cgats").write_text(cut)
    bad = station.once("--abandon", "0")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--abandon" in bad.stderr
    assert sorted(p.name for p in station.drop.iterdir()) == ["new.cgats", "old.cgats"]
    res = station.once("--json")
    assert res.returncode == 0, res.stderr
    assert [p.name for p in station.drop.iterdir() if p.is_file()] == ["new.cgats"]
    assert sorted(p.name for p in (station.drop / "rejected").iterdir()) == ["old.cgats", "old.cgats.reason"]
    reason = (station.drop / "rejected" / "old.cgats.reason").read_text()
    assert reason.startswith("Incomplete: file:") and "s1" not in reason
    assert station.stored() == 0


def _cxf(samples: int) -> bytes:
    """A CxF3 file of *samples* Lab-only samples (6 geometries), as bytes."""
    from station.ingest.errors import ImportFileError
    from station.ingest.formats import build_measurement, write_measurement_file
    from station.ingest.formats.measurement import OBSERVERS, Instrument
    from station.model.domain import ANGLES_6, aspecular_name

    def err(fld: str, accepted: str, got: object) -> ImportFileError:
        return ImportFileError("generated", "", fld, accepted, got)

    geometries = [aspecular_name(a) for a in ANGLES_6]
    ms = [
        build_measurement(
            sample=f"panel {s}",
            rows=[(g, err) for g in geometries],
            lab=[[50.0 + s, 1.0 + k, -2.0] for k in range(len(geometries))],
            wavelengths_nm=None,
            spectra=None,
            instrument=Instrument("MA-T6", "SN1"),
            illuminant="D65",
            observer=OBSERVERS[1],
            measured_at=None,
            err=err,
        )
        for s in range(samples)
    ]
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "x.cxf"
        write_measurement_file(ms, path, "cxf")
        return path.read_bytes()


def test_a_live_watcher_waits_for_a_paused_writer(station: Station) -> None:
    """A running watcher (settle 0.2 s) and a writer that stops half way through a CxF file of four
    samples for well over the settle time: the file is imported once, whole, after the writer ends."""
    data = _cxf(4)
    proc = station.start("--settle", "0.2", "--interval", "0.05")
    assert _wait(lambda: station.ready(proc))
    half = station.drop / "four.cxf"
    with half.open("wb") as fh:
        fh.write(data[: len(data) // 2])
        fh.flush()
        # well past the settle time, polled: the watcher must leave the half file where it is
        assert not _wait(lambda: not half.exists(), timeout_s=1.5)
        fh.write(data[len(data) // 2 :])
    assert _wait(lambda: (station.drop / "done" / "four.cxf").exists())
    assert _wait(lambda: station.stored() == 4)
    station.stop(proc)
    assert list((station.drop / "rejected").iterdir()) == []
    assert (station.drop / "done" / "four.cxf").read_bytes() == data
    assert station.stored() == 4


def test_two_watchers_give_each_file_one_outcome(station: Station) -> None:
    """Two watchers on one folder: every file is claimed by one of them, so each rejected file has
    exactly one reason, no reason is left without its file, and every good sample is stored once."""
    a = station.start("--settle", "0", "--interval", "0.05")
    b = station.start("--settle", "0", "--interval", "0.05")
    assert _wait(lambda: station.ready(a) and station.ready(b))
    names = []
    for n in range(40):
        name = f"f{n:02d}.csv"
        text = _csv(f"p{n}") if n % 2 else CSV_HEAD + f"p{n},45as15,50,1\n"  # odd good, even short
        (station.drop / (name + ".part")).write_text(text)
        (station.drop / (name + ".part")).rename(station.drop / name)
        names.append(name)
    assert _wait(lambda: not any(p.is_file() for p in station.drop.iterdir()))
    assert _wait(lambda: len(list((station.drop / "done").iterdir())) + len(list((station.drop / "rejected").glob("*.csv"))) == 40)  # fmt: skip
    station.stop(a)
    station.stop(b)
    done = sorted(p.name for p in (station.drop / "done").iterdir())
    rejected = sorted(p.name for p in (station.drop / "rejected").iterdir())
    assert done == names[1::2]
    assert rejected == sorted(n + s for n in names[0::2] for s in ("", ".reason"))
    assert list((station.drop / "processing").iterdir()) == []
    assert station.stored() == 20
