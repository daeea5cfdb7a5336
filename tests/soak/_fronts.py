"""The fronts of the soak test: the product's writer processes, kept running and killed at random.

Each front runs in its own process group (``start_new_session``), so a SIGKILL of the group takes the
simulator it spawned along, and teardown kills every group that is left. Four fronts store into one
database:

* :class:`ViewerFront`: the viewer's models, headless (``python -m tests.soak._viewer``), which scan
  the MA6 simulator and log what they send themselves;
* :class:`ImportFront`: ``station import FILE --store URL`` run again and again from a folder outside
  the checkout, each file logged before the run and rerun after a kill (as a person would);
* :class:`ServiceFront` with :class:`MeasureSender`: a real ``station serve`` with an MA6 simulator,
  driven over HTTP (``POST /api/v1/instruments/{id}/measure`` under a client id, retried through kills);
* :class:`WatcherFront` with :class:`DropSender`: ``station import watch DIR``, fed files dropped
  into its folder; its ``--json`` outcomes (one line per file moved to ``done/``) are its answers.

A supervisor thread restarts a killed front until it is retired. Whatever goes wrong outside the
accounting (a crash, an error answer, a start that fails) is collected in :class:`Findings`.
"""

from __future__ import annotations

import json
import os
import random
import selectors
import signal
import subprocess
import sys
import threading
import time
import traceback
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import IO, Protocol

import httpx

from station.ingest.errors import ImportFileError
from station.ingest.formats import build_measurement, import_client_id, write_measurement_file
from station.ingest.formats.measurement import OBSERVERS, ImportedMeasurement, Instrument
from station.ingest.formats.records import file_sha256
from station.model.domain import ANGLES_6, ILLUMINATION_DEG, aspecular_name
from tests.serve_process import ServeProcess, ServeStartError
from tests.soak._log import SenderLog

REPO = Path(__file__).resolve().parents[2]
#: How long a front may take to start (seconds): a cold ``station serve`` on a loaded machine.
START_TIMEOUT_S = 120.0
#: How long one send may take through kills and restarts before the sender gives up on it (seconds).
SEND_DEADLINE_S = 240.0
#: Longest time a killed front stays down before it is restarted (seconds, drawn uniformly from 0): a
#: person or a service manager restarts a program some time after it died, not at once.
MAX_DOWN_S = 6.0
#: How long a retired front may take to end after its stop signal (seconds), then it is killed.
STOP_TIMEOUT_S = 60.0
FORMATS = ("cxf", "cgats", "csv")
SAMPLES_PER_FILE = 2
MEASURE_NAMESPACE = uuid.UUID("9b0a51f4-3c2e-4d7a-8f61-5e4c3b2a1d09")


class Findings:
    """What went wrong outside the accounting, from every thread (a crash, an error answer)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._items: list[str] = []

    def add(self, text: str) -> None:
        """Record one finding."""
        with self._lock:
            self._items.append(text)

    def items(self) -> list[str]:
        """The findings so far."""
        with self._lock:
            return list(self._items)


def child_env(work: Path) -> dict[str, str]:
    """The environment of every front: this checkout's code, a data folder and an operator of its own."""
    return dict(
        os.environ,
        PYTHONPATH=str(REPO),
        PYTHONUNBUFFERED="1",
        CACAD_DATA_DIR=str(work / "var"),
        CACAD_OPERATOR="soak",
    )


def kill_group(proc: subprocess.Popen[bytes] | subprocess.Popen[str] | None) -> None:
    """SIGKILL *proc*'s process group (it leads one) while *proc* is not yet reaped (a reaped id may
    be reused); a simulator left in the group ends on its own when its stdin closes."""
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def _tail(path: Path, lines: int = 15) -> str:
    try:
        return "\n".join(path.read_text(encoding="utf-8", errors="replace").splitlines()[-lines:])
    except FileNotFoundError:
        return ""


class StartError(Exception):
    """A front did not become ready."""


class Target(Protocol):
    """What the chaos loop kills: a front with a label and a count of the kills that landed."""

    label: str
    kills: int

    def kill(self) -> bool:
        """SIGKILL the front's process if one runs; whether a kill was sent."""
        ...


class Front:
    """One long-running writer process, restarted by a supervisor thread after each kill until retired."""

    #: The signal that asks the front to end on its own.
    stop_signal = signal.SIGINT

    def __init__(self, name: str, work: Path, findings: Findings, seed: int) -> None:
        self.label = name
        self._rng = random.Random(seed)  # the supervisor's: how long a killed front stays down
        self.work = work
        self.findings = findings
        self.kills = 0
        self.starts = 0
        self.proc: subprocess.Popen[bytes] | subprocess.Popen[str] | None = None
        self._lock = threading.Lock()
        self._ready = threading.Event()
        self._retired = threading.Event()
        self._wake = threading.Event()  # set: a killed front is restarted at once
        self._asked: subprocess.Popen[bytes] | subprocess.Popen[str] | None = None
        self._thread: threading.Thread | None = None

    def _spawn(self) -> subprocess.Popen[bytes] | subprocess.Popen[str]:
        """Start the process and return it once it serves; :class:`StartError` when it does not."""
        raise NotImplementedError

    def _stderr_tail(self) -> str:
        return ""

    def _abort_start(self) -> None:
        """Kill a process that is starting (not yet ready), so that :meth:`_spawn` gives up."""

    def supervise(self) -> None:
        """Start the front and keep it running (in a thread) until :meth:`ask_to_end`."""
        self._thread = threading.Thread(target=self._keep_running, name=f"soak-{self.label}", daemon=True)
        self._thread.start()

    def _keep_running(self) -> None:
        first = True
        while not self._retired.is_set():
            if not first:
                self._wake.wait(self._rng.uniform(0.0, MAX_DOWN_S))
                if self._retired.is_set():
                    break
            first = False
            try:
                proc = self._spawn()
            except StartError as exc:
                if not self._retired.is_set():
                    self.findings.add(f"{self.label}: did not start: {exc}")
                continue
            except Exception:
                self.findings.add(f"{self.label}: supervisor failed:\n{traceback.format_exc()}")
                return
            with self._lock:
                self.proc = proc
                self.starts += 1
                if self._retired.is_set():
                    kill_group(proc)
                else:
                    self._ready.set()
            rc = proc.wait()
            self._ready.clear()
            if rc != -signal.SIGKILL and not (self._retired.is_set() and rc == 0):
                self.findings.add(f"{self.label}: exited with status {rc}\n{self._stderr_tail()}")

    def wait_ready(self, timeout_s: float) -> bool:
        """Whether the front is serving, waiting up to *timeout_s* seconds for it."""
        return self._ready.wait(timeout_s)

    def kill(self) -> bool:
        """SIGKILL the front if it is serving; whether a kill was sent."""
        with self._lock:
            proc = self.proc
            if not self._ready.is_set() or proc is None or proc.poll() is not None:
                return False
            self._ready.clear()
            kill_group(proc)
            self.kills += 1
            return True

    def hurry(self) -> None:
        """From now on restart a killed front at once (the soak is winding down)."""
        self._wake.set()

    def ask_to_end(self) -> None:
        """Stop restarting and ask the running process to end (:attr:`stop_signal`)."""
        with self._lock:
            self._retired.set()
            self._wake.set()
            proc = self._asked = self.proc
            if not self._ready.is_set():
                self._abort_start()
            elif proc is not None and proc.poll() is None:
                proc.send_signal(self.stop_signal)

    def wait_ended(self) -> None:
        """Wait for the process asked to end (:data:`STOP_TIMEOUT_S`, then it is killed, a finding)."""
        proc = self._asked
        if proc is not None:
            try:
                proc.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.findings.add(
                    f"{self.label}: did not end within {STOP_TIMEOUT_S:g} s of {self.stop_signal!r}"
                )
            kill_group(proc)
            proc.wait()
        if self._thread is not None:
            self._thread.join(STOP_TIMEOUT_S)

    def close(self) -> None:
        """Teardown: kill whatever runs and end the supervisor."""
        with self._lock:
            self._retired.set()
            self._wake.set()
            proc = self.proc
            self._abort_start()
        kill_group(proc)
        if proc is not None:
            proc.wait()
        if self._thread is not None:
            self._thread.join(STOP_TIMEOUT_S)


class ViewerFront(Front):
    """The viewer's models in a child process (:mod:`tests.soak._viewer`), logging to *log*."""

    stop_signal = signal.SIGTERM

    def __init__(self, work: Path, findings: Findings, seed: int, url: str, log: Path) -> None:
        super().__init__("viewer", work, findings, seed)
        self.url = url
        self.log = log
        self.outbox = work / "viewer-outbox.sqlite3"
        self.stderr = work / "viewer.stderr"
        self._starting: subprocess.Popen[bytes] | None = None

    def _stderr_tail(self) -> str:
        return _tail(self.stderr)

    def _abort_start(self) -> None:
        if self._starting is not None and self._starting.poll() is None:
            kill_group(self._starting)

    def _spawn(self) -> subprocess.Popen[bytes]:
        with open(self.stderr, "ab") as err:
            proc = subprocess.Popen(
                [sys.executable, "-m", "tests.soak._viewer", self.url, str(self.outbox), str(self.log)],
                cwd=self.work,
                env=child_env(self.work),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=err,
                start_new_session=True,
                bufsize=0,
            )
        self._starting = proc
        assert proc.stdout is not None
        try:
            if _wait_line(proc.stdout, b"ready", START_TIMEOUT_S):
                return proc
        finally:
            proc.stdout.close()
        kill_group(proc)
        rc = proc.wait()
        raise StartError(f"viewer not ready (status {rc})\n{self._stderr_tail()}")


def _copy(stream: IO[bytes], path: Path) -> None:
    """Append what *stream* carries to *path* until it ends, then close it."""
    with stream, open(path, "ab") as out:
        for line in stream:
            out.write(line)
            out.flush()


def _wait_line(stream: IO[bytes], wanted: bytes, timeout_s: float) -> bool:
    """Whether a line starting with *wanted* arrives on *stream* (unbuffered, so that what ``select``
    sees is what is unread) within *timeout_s* seconds."""
    end = time.monotonic() + timeout_s
    with selectors.DefaultSelector() as sel:
        sel.register(stream, selectors.EVENT_READ)
        while (left := end - time.monotonic()) > 0:
            if not sel.select(left):
                continue
            line = stream.readline()
            if not line:
                return False
            if line.startswith(wanted):
                return True
    return False


class ServiceFront(Front):
    """``station serve`` with an MA6 simulator on the database *url*, its data folder under *work*."""

    def __init__(self, work: Path, findings: Findings, seed: int, url: str) -> None:
        super().__init__("service", work, findings, seed)
        self.url = url
        self.data_dir = work / "service"
        self.serve = ServeProcess(
            self.data_dir,
            ("--database", url, "--no-demo-library", "--simulators", "ma6"),
            env=child_env(work),
            cwd=work,
            own_group=True,
            start_timeout_s=START_TIMEOUT_S,
        )

    @property
    def outbox(self) -> Path:
        """The service's outbox (``Settings.outbox_path``)."""
        from station.api.settings import Settings

        return Settings.model_validate({"data_dir": self.data_dir}).outbox_path

    def _stderr_tail(self) -> str:
        return self.serve.tail(15)

    def _abort_start(self) -> None:
        proc = self.serve.proc
        if proc is not None and proc.poll() is None:
            kill_group(proc)  # the one starting: its log ends, ServeProcess.start gives up

    def _spawn(self) -> subprocess.Popen[str]:
        try:
            self.serve.start()
        except ServeStartError as exc:
            proc = self.serve.proc  # ServeProcess.start leaves the failed start's log pipe open
            if proc is not None and proc.stdout is not None:
                proc.stdout.close()
            raise StartError(str(exc)) from exc
        assert self.serve.proc is not None
        if not self.serve.token:
            kill_group(self.serve.proc)
            raise StartError("no bootstrap admin token")
        return self.serve.proc

    def target(self, timeout_s: float) -> tuple[str, dict[str, str]] | None:
        """``(base URL, auth header)`` of the serving service, waiting up to *timeout_s*; else ``None``."""
        with self._lock:
            if self._ready.is_set():
                return self.serve.base, {"Authorization": f"Bearer {self.serve.token}"}
        if not self._ready.wait(timeout_s):
            return None
        return self.serve.base, {"Authorization": f"Bearer {self.serve.token}"}


class WatcherFront(Front):
    """``station import watch DROP --json`` on the database *url*; its outcomes go to :attr:`outcomes`."""

    def __init__(self, work: Path, findings: Findings, seed: int, url: str) -> None:
        super().__init__("watcher", work, findings, seed)
        self.url = url
        self.drop = work / "drop"
        self.drop.mkdir(exist_ok=True)
        self.outbox = work / "watch-outbox.sqlite3"
        self.outcomes = work / "watch-outcomes.jsonl"
        self.stderr = work / "watcher.stderr"
        self._starting: subprocess.Popen[bytes] | None = None

    def _stderr_tail(self) -> str:
        return _tail(self.stderr)

    def _abort_start(self) -> None:
        if self._starting is not None and self._starting.poll() is None:
            kill_group(self._starting)

    def _spawn(self) -> subprocess.Popen[bytes]:
        out = os.open(self.outcomes, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
        try:
            proc = subprocess.Popen(
                [sys.executable, "-m", "station.cli", "import", "watch", self.drop.name,
                 "--settle", "0", "--interval", "0.05", "--store", self.url,
                 "--outbox", str(self.outbox), "--job", "SOAK-W", "--part", "door", "--json"],
                cwd=self.work, env=child_env(self.work), stdin=subprocess.DEVNULL, stdout=out,
                stderr=subprocess.PIPE, start_new_session=True, bufsize=0,
            )  # fmt: skip
        finally:
            os.close(out)
        self._starting = proc
        assert proc.stderr is not None
        ready = _wait_line(proc.stderr, b"watching", START_TIMEOUT_S)  # printed once it watches
        threading.Thread(target=_copy, args=(proc.stderr, self.stderr), daemon=True).start()
        if ready:
            return proc
        kill_group(proc)
        rc = proc.wait()
        raise StartError(f"watcher not ready (status {rc})\n{self._stderr_tail()}")

    def pending(self) -> list[Path]:
        """The dropped files still waiting in the folder."""
        return [p for p in self.drop.iterdir() if p.is_file() and not p.name.endswith(".part")]


def write_sample_file(
    path: Path, fmt: str, stem: str, rng: random.Random
) -> list[tuple[str, list[list[float]]]]:
    """Write :data:`SAMPLES_PER_FILE` Lab-only samples (the 6 aspecular angles at 45°) to *path* as
    *fmt*; returns ``(client id, Lab)`` of each, the client ids an import of these bytes gives."""
    geometries = [aspecular_name(a) for a in ANGLES_6]

    def err(fld: str, accepted: str, got: object) -> ImportFileError:
        return ImportFileError("generated", "", fld, accepted, got)

    samples: list[ImportedMeasurement] = []
    labs = []
    for s in range(SAMPLES_PER_FILE):
        lab = [[round(rng.uniform(20, 90), 4), round(rng.uniform(-20, 20), 4), round(rng.uniform(-20, 20), 4)]
               for _ in geometries]  # fmt: skip
        labs.append(lab)
        samples.append(
            build_measurement(
                sample=f"{stem} sample {s}",
                rows=[(g, err) for g in geometries],
                lab=lab,
                wavelengths_nm=None,
                spectra=None,
                instrument=Instrument("MA-T6", "SN-SOAK"),
                illuminant="D65",
                observer=OBSERVERS[1],
                measured_at=None,
                err=err,
            )
        )
    write_measurement_file(samples, path, fmt)
    sha = file_sha256(path)
    return [(str(import_client_id(sha, i, ILLUMINATION_DEG)), lab) for i, lab in enumerate(labs)]


class _Sender(threading.Thread):
    """A thread that sends until :attr:`stop_sending` is set, recording a crash as a finding."""

    def __init__(self, name: str, findings: Findings, stop_sending: threading.Event) -> None:
        super().__init__(name=f"soak-{name}-sender", daemon=True)
        self.sender = name
        self.findings = findings
        self.stop_sending = stop_sending
        self.sends = 0

    def run(self) -> None:
        try:
            self.send_all()
        except Exception:
            self.findings.add(f"{self.sender} sender crashed:\n{traceback.format_exc()}")

    def send_all(self) -> None:
        raise NotImplementedError


class ImportFront(_Sender):
    """``station import FILE --store URL --json``, one new file after another; a killed run is rerun."""

    label = "import"

    def __init__(
        self, work: Path, findings: Findings, stop_sending: threading.Event, url: str, log: Path, seed: int
    ) -> None:
        super().__init__("import", findings, stop_sending)
        self.work = work / "cli"
        self.work.mkdir(exist_ok=True)
        self.url = url
        self.log = log
        self.rng = random.Random(seed)
        self.outbox = work / "import-outbox.sqlite3"
        self.kills = 0
        self.reruns = 0
        self._lock = threading.Lock()
        self._proc: subprocess.Popen[bytes] | None = None
        self._retired = False

    def kill(self) -> bool:
        """SIGKILL the import that runs now, if any; whether a kill was sent."""
        with self._lock:
            proc = self._proc
            if proc is None or proc.poll() is not None:
                return False
            kill_group(proc)
            self.kills += 1
            return True

    def close(self) -> None:
        """Teardown: no new run, kill the one in hand."""
        with self._lock:
            self._retired = True
            kill_group(self._proc)

    def send_all(self) -> None:
        with SenderLog(self.log, self.sender) as log:
            n = 0
            while not self.stop_sending.is_set():
                fmt = FORMATS[n % len(FORMATS)]
                path = self.work / f"import-{n:04d}.{fmt}"
                for cid, lab in write_sample_file(path, fmt, f"import {n}", self.rng):
                    log.sent(cid, lab)
                self._import(path, log)
                self.sends += 1
                n += 1

    def _import(self, path: Path, log: SenderLog) -> None:
        end = time.monotonic() + SEND_DEADLINE_S
        cmd = [sys.executable, "-m", "station.cli", "import", path.name, "--store", self.url,
               "--outbox", str(self.outbox), "--job", "SOAK-I", "--part", "hood", "--json"]  # fmt: skip
        while time.monotonic() < end:
            with self._lock:
                if self._retired:
                    return
                proc = self._proc = subprocess.Popen(
                    cmd, cwd=self.work, env=child_env(self.work.parent), stdin=subprocess.DEVNULL,
                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                )  # fmt: skip
            try:
                out, err = proc.communicate(timeout=max(1.0, end - time.monotonic()))
            except subprocess.TimeoutExpired:
                kill_group(proc)
                proc.communicate()
                self.findings.add(f"import: {path.name} did not finish within {SEND_DEADLINE_S:g} s")
                return
            if proc.returncode == -signal.SIGKILL:
                self.reruns += 1  # killed: the person runs the same import again
                continue
            if proc.returncode != 0:
                self.findings.add(
                    f"import: {path.name} exited with status {proc.returncode}: "
                    f"{err.decode(errors='replace')[-2000:]}"
                )
                return
            for r in json.loads(out)["stored"]:
                log.ack(str(r["client_id"]), str(r["status"]), r["measurement_id"])
            return
        self.findings.add(f"import: {path.name} not answered within {SEND_DEADLINE_S:g} s")


class MeasureSender(_Sender):
    """Measures through the service's measure route under fresh client ids, retrying one through kills."""

    def __init__(
        self,
        service: ServiceFront,
        findings: Findings,
        stop_sending: threading.Event,
        log: Path,
        seed: int,
    ) -> None:
        super().__init__("service", findings, stop_sending)
        self.service = service
        self.log = log
        self.seed = seed
        self.retries = 0
        self._panel: int | None = None
        self._instrument: dict[str, str] = {}
        self._backoff = threading.Event()  # never set: a pause between two asks

    def send_all(self) -> None:
        with SenderLog(self.log, self.sender) as log, httpx.Client(timeout=60.0) as http:
            n = 0
            while not self.stop_sending.is_set():
                cid = str(uuid.uuid5(MEASURE_NAMESPACE, f"{self.seed}/{n}"))
                n += 1
                log.sent(cid)
                answer = self._measure(http, cid)
                if answer is None:
                    return
                status, mid, lab = answer
                log.ack(cid, status, mid, lab)
                self.sends += 1

    def _measure(
        self, http: httpx.Client, cid: str
    ) -> tuple[str, int | None, list[list[float]] | None] | None:
        end = time.monotonic() + SEND_DEADLINE_S
        while (left := end - time.monotonic()) > 0:
            target = self.service.target(min(left, 1.0))
            if target is None:
                if self.stop_sending.is_set():
                    return None  # the soak ends while the service is down: left unacknowledged
                continue
            base, auth = target
            try:
                if self._panel is None:
                    r = http.post(
                        f"{base}/api/v1/panels", json={"job": "SOAK-S", "part": "bumper"}, headers=auth
                    )
                    if r.status_code != 201:
                        self.findings.add(f"service: POST /panels answered {r.status_code}: {r.text[:300]}")
                        return None
                    self._panel = int(r.json()["id"])
                ma6 = self._ma6(http, base, auth)
                if ma6 is None:
                    return None
                r = http.post(
                    f"{base}/api/v1/instruments/{ma6}/measure",
                    json={"client_id": cid, "panel_id": self._panel},
                    headers=auth,
                )
            except httpx.TransportError:  # killed under us (or slow): the same client id again
                self.retries += 1
                continue
            if r.status_code == 503:  # unavailable for a moment: ask again shortly
                self.retries += 1
                self._backoff.wait(0.1)
                continue
            if r.status_code not in (200, 201):
                self.findings.add(f"service: measure {cid} answered {r.status_code}: {r.text[:300]}")
                return None
            body = r.json()
            m = body.get("measurement")
            return str(body["status"]), None if m is None else int(m["id"]), None if m is None else m["lab"]
        self.findings.add(f"service: measure {cid} not answered within {SEND_DEADLINE_S:g} s")
        return None

    def _ma6(self, http: httpx.Client, base: str, auth: dict[str, str]) -> str | None:
        """The id of the service's MA6 simulator (looked up once per start), or ``None`` (a finding)."""
        if base not in self._instrument:
            r = http.get(f"{base}/api/v1/instruments", headers=auth)
            ids = [str(i["id"]) for i in r.json() if i["model"] == "MA6"] if r.status_code == 200 else []
            if len(ids) != 1:
                self.findings.add(f"service: GET /instruments answered {r.status_code}: {r.text[:300]}")
                return None
            self._instrument[base] = ids[0]
        return self._instrument[base]


class DropSender(_Sender):
    """Drops sample files into the watcher's folder (written aside, renamed in), a few waiting at most."""

    #: Most files waiting in the folder before the next is dropped.
    MAX_WAITING = 3
    #: Pause between two looks at the folder (seconds, drawn uniformly).
    PACE_S = (0.1, 0.6)

    def __init__(
        self,
        watcher: WatcherFront,
        findings: Findings,
        stop_sending: threading.Event,
        log: Path,
        seed: int,
    ) -> None:
        super().__init__("watcher", findings, stop_sending)
        self.watcher = watcher
        self.log = log
        self.rng = random.Random(seed)

    def send_all(self) -> None:
        with SenderLog(self.log, self.sender) as log:
            n = 0
            while not self.stop_sending.is_set():
                if len(self.watcher.pending()) < self.MAX_WAITING:
                    fmt = FORMATS[n % len(FORMATS)]
                    name = f"drop-{n:04d}.{fmt}"
                    aside = self.watcher.drop / (name + ".part")  # the watcher skips .part files
                    for cid, lab in write_sample_file(aside, fmt, f"drop {n}", self.rng):
                        log.sent(cid, lab)
                    os.replace(aside, self.watcher.drop / name)
                    self.sends += 1
                    n += 1
                self.stop_sending.wait(self.rng.uniform(*self.PACE_S))


def wait_until(done: Callable[[], bool], timeout_s: float, poll_s: float = 0.1) -> bool:
    """Whether *done* turns true within *timeout_s* seconds (asked every *poll_s*)."""
    end = time.monotonic() + timeout_s
    pause = threading.Event()
    while not done():
        if time.monotonic() >= end:
            return False
        pause.wait(poll_s)
    return True
