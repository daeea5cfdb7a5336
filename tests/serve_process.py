"""``station serve`` as a child process on a free loopback port: test and benchmark tooling (not shipped).

:class:`ServeProcess` starts ``python -m station.cli serve --data-dir DIR --port PORT`` (plus the caller's
arguments; *env* is the whole environment, default this process's), waits until uvicorn reports the socket bound (``Uvicorn running``), reads the
bootstrap admin token (printed to a terminal, else written to :data:`~station.api.settings.BOOTSTRAP_TOKEN_FILE`
in the data folder; a pipe is not a terminal), and then drains the log in a thread so a chatty service
never blocks on a full pipe. :meth:`ServeProcess.stop` sends SIGINT (a graceful uvicorn shutdown) and kills
after *stop_timeout_s*; :meth:`ServeProcess.kill` SIGKILLs the process group when started with
``own_group`` (the simulators it spawned die with it). The log stays readable in :attr:`ServeProcess.log`.
"""

from __future__ import annotations

import os
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

from station.api.errors import ApiError
from station.api.settings import BOOTSTRAP_TOKEN_FILE
from tests.processes import run

#: The root of this checkout (the ``PYTHONPATH`` of a child service).
REPO = Path(__file__).resolve().parents[1]
#: What uvicorn logs once the socket is bound (application startup completes before it).
READY_LINE = "Uvicorn running"
_TOKEN = re.compile(r"cst_[\w-]+")


class ServeStartError(ApiError):
    """``station serve`` exited or did not become ready; the message ends with its last log lines."""


def serve_env(**extra: str) -> dict[str, str]:
    """This process's environment for a ``station serve`` child of this checkout: ``PYTHONPATH`` the
    checkout, unbuffered output, *extra* set, and no ``CACAD_DATABASE_URL`` (the data folder's SQLite)."""
    env = dict(os.environ, PYTHONPATH=str(REPO), PYTHONUNBUFFERED="1", **extra)
    env.pop("CACAD_DATABASE_URL", None)
    return env


def upgrade_data_dir(data_dir: Path, env: Mapping[str, str], timeout_s: float = 120.0) -> None:
    """``station db upgrade --data-dir DATA_DIR`` in a child under *env* (at most *timeout_s* seconds);
    :class:`ServeStartError` with its stderr when it fails."""
    created = run(
        [sys.executable, "-m", "station.cli", "db", "upgrade", "--data-dir", str(data_dir)],
        env=env,
        timeout=timeout_s,
    )
    if created.returncode != 0:
        raise ServeStartError(f"db upgrade of {data_dir} exited {created.returncode}: {created.stderr}")


def free_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class ServeProcess:
    """One ``station serve`` child (see the module docstring); :meth:`start` it, then :meth:`stop` it."""

    def __init__(
        self,
        data_dir: Path,
        args: Sequence[str] = (),
        *,
        env: Mapping[str, str] | None = None,
        cwd: Path | None = None,
        own_group: bool = False,
        start_timeout_s: float = 90.0,
        stop_timeout_s: float = 20.0,
    ) -> None:
        self.data_dir = Path(data_dir)
        self.args = tuple(args)
        self.env = dict(os.environ if env is None else env)
        self.env.setdefault("PYTHONUNBUFFERED", "1")
        self.cwd = cwd
        self.own_group = own_group
        self.start_timeout_s = start_timeout_s
        self.stop_timeout_s = stop_timeout_s
        self.proc: subprocess.Popen[str] | None = None
        self.port = 0
        self.base = ""
        self.token = ""
        self.log: list[str] = []
        self._reader: threading.Thread | None = None

    @property
    def pid(self) -> int:
        """The service's process id (0 before :meth:`start`)."""
        return self.proc.pid if self.proc is not None else 0

    def start(self) -> ServeProcess:
        """Start the service on a fresh free port and wait until it listens; returns ``self``."""
        self._close_previous()
        self.port = free_port()
        cmd = [sys.executable, "-m", "station.cli", "serve", "--data-dir", str(self.data_dir)]
        cmd += ["--port", str(self.port), *self.args]
        self.proc = subprocess.Popen(
            cmd,
            cwd=self.cwd,
            env=self.env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=self.own_group,
        )
        self.base = f"http://127.0.0.1:{self.port}"
        lines: queue.SimpleQueue[str | None] = queue.SimpleQueue()
        self._reader = threading.Thread(target=self._drain, args=(self.proc, lines), daemon=True)
        self._reader.start()
        deadline = time.monotonic() + self.start_timeout_s
        while (left := deadline - time.monotonic()) > 0:
            try:
                line = lines.get(timeout=left)  # the reader thread reads, so a silent child cannot hang us
            except queue.Empty:
                break
            if line is None:  # the pipe closed: the service exited before it listened
                self.proc.wait()
                raise ServeStartError(f"station serve exited ({self.proc.returncode}):\n{self.tail()}")
            found = _TOKEN.search(line)
            if found and not self.token:
                self.token = found.group(0)
            if READY_LINE in line:
                token_file = self.data_dir / BOOTSTRAP_TOKEN_FILE
                if not self.token and token_file.exists():
                    self.token = token_file.read_text().strip()
                return self
        self.kill()
        self._reader.join(10)
        raise ServeStartError(f"station serve did not start in {self.start_timeout_s:g} s:\n{self.tail()}")

    def tail(self, lines: int = 40) -> str:
        """The last *lines* lines of the log."""
        return "".join(self.log[-lines:])

    def _drain(self, proc: subprocess.Popen[str], lines: queue.SimpleQueue[str | None] | None = None) -> None:
        """Collect the log until the service exits (passing each line to *lines* too, then ``None``),
        then reap it and close the pipe."""
        if proc.stdout is not None:
            with proc.stdout:
                for line in proc.stdout:
                    self.log.append(line)
                    if lines is not None:
                        lines.put(line)
        if lines is not None:
            lines.put(None)
        proc.wait()

    def _close_previous(self) -> None:
        """Close the pipe of an earlier process that has ended (before a restart)."""
        old = self.proc
        if old is None or old.poll() is None:
            return
        if self._reader is not None:
            self._reader.join(10)
        elif old.stdout is not None:
            old.stdout.close()

    def kill(self, proc: subprocess.Popen[str] | None = None) -> None:
        """SIGKILL the service, or the earlier *proc* of it (its process group with ``own_group``, which
        takes the simulators it spawned along); no-op once it is gone."""
        proc = proc or self.proc
        if proc is None:
            return
        try:
            if self.own_group:
                os.killpg(proc.pid, signal.SIGKILL)
            elif proc.poll() is None:
                proc.kill()
        except (ProcessLookupError, PermissionError):
            pass

    def stop(self, sig: int = signal.SIGINT) -> int | None:
        """Stop the service with *sig*, SIGKILL after *stop_timeout_s*; returns its exit status."""
        proc = self.proc
        if proc is None:
            return None
        if proc.poll() is None:
            proc.send_signal(sig)
            try:
                proc.wait(self.stop_timeout_s)
            except subprocess.TimeoutExpired:
                self.kill()
                proc.wait()
        if self.own_group:
            self.kill(proc)  # whatever is left of the group
            proc.wait()
        if self._reader is not None:
            self._reader.join(10)
        elif proc.stdout is not None:
            proc.stdout.close()
        return proc.returncode


@contextmanager
def serving(data_dir: Path, *args: str, **options: object) -> Iterator[ServeProcess]:
    """``with serving(dir, "--no-demo-library") as svc:`` a started :class:`ServeProcess`, stopped after."""
    svc = ServeProcess(data_dir, args, **options)  # type: ignore[arg-type]
    svc.start()
    try:
        yield svc
    finally:
        svc.stop()
