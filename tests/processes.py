"""Child processes of the tests that never outlive them, and reads that never wait without a deadline.

:class:`Child` starts a command in a process group of its own and drains each of its pipes in a thread
(:class:`Stream`), so a chatty child never blocks on a full pipe and a test waits for output with a
deadline (:meth:`Stream.wait_for`). Leaving the ``with`` block kills the whole group (the child and
whatever it started), reaps the child and closes every pipe: a test that fails half-way leaves nothing
running to break a later test (a still-running ``Popen`` collected later raises ``ResourceWarning``,
which this suite turns into an error).

:func:`run` is ``subprocess.run(..., capture_output=True, text=True, timeout=...)`` on top of it: on a
timeout the whole group is killed, not only the child.

:func:`children_of_this_process` and :func:`end_leftovers` let ``tests/conftest.py`` find and end any
process a test left running, whoever started it.
"""

from __future__ import annotations

import os
import selectors
import signal
import subprocess
import threading
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO

from station.closing import Closing
from tests.waiting import WaitTimeout, wait_until

#: Seconds a killed child (SIGKILL) is given to be reaped, and its pipes to reach end of file.
KILL_WAIT_S = 10.0
#: Seconds between two checks of the stop flag while a stream has nothing to read.
_SELECT_S = 0.1


def _text(data: bytes) -> str:
    """Bytes as ``subprocess`` text mode decodes them (UTF-8, universal newlines)."""
    return data.decode("utf-8", errors="replace").replace("\r\n", "\n").replace("\r", "\n")


class Stream(Closing):
    """Everything read so far from file descriptor *fd*, read by a daemon thread until end of file.

    The thread waits on a selector (at most ``_SELECT_S`` s at a time), so :meth:`close` stops it even
    when the writer never closes its end; *fd* is closed only after the thread has ended (closing a
    descriptor another thread reads could hand its number to an unrelated file). A terminal's leader
    side reports EIO once every follower is closed: that is end of file here.
    """

    def __init__(self, fd: int, name: str, *, owner: IO[bytes] | None = None) -> None:
        """Read *fd*; *owner* is the file object that holds it (closed in :meth:`close`), else *fd* is
        closed itself."""
        self.name = name
        self._fd = fd
        self._owner = owner
        self._chunks: list[bytes] = []
        self._eof = False
        self._stop = threading.Event()
        self._cond = threading.Condition()
        self._thread = threading.Thread(target=self._drain, name=f"read {name}", daemon=True)
        self._thread.start()

    def _drain(self) -> None:
        sel = selectors.DefaultSelector()
        sel.register(self._fd, selectors.EVENT_READ)
        try:
            while not self._stop.is_set():
                if not sel.select(_SELECT_S):
                    continue
                try:
                    chunk = os.read(self._fd, 65536)
                except OSError:  # EIO: the terminal's last follower has closed
                    chunk = b""
                with self._cond:
                    if chunk:
                        self._chunks.append(chunk)
                    else:
                        break
                    self._cond.notify_all()
        finally:
            sel.close()
            with self._cond:
                self._eof = True
                self._cond.notify_all()

    @property
    def data(self) -> bytes:
        """The bytes read so far."""
        with self._cond:
            return b"".join(self._chunks)

    def text(self) -> str:
        """The text read so far (UTF-8, universal newlines)."""
        return _text(self.data)

    @property
    def at_eof(self) -> bool:
        """True once the writer side is closed (or the stream was stopped)."""
        with self._cond:
            return self._eof

    def wait_for(self, needle: str, timeout: float) -> str:
        """Wait until the text read contains *needle*; return the text read so far.

        Raises :class:`WaitTimeout` with the text read when *timeout* seconds pass, or when the stream
        ends without it."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                text = _text(b"".join(self._chunks))
                if needle in text:
                    return text
                left = deadline - time.monotonic()
                if self._eof or left <= 0:
                    why = "ended" if self._eof else f"not seen within {timeout:g} s"
                    raise WaitTimeout(f"{self.name}: {needle!r} {why}; read so far:\n{text[-4000:]}")
                self._cond.wait(left)

    def wait_eof(self, timeout: float) -> bool:
        """Wait up to *timeout* seconds for end of file; True when reached."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while not self._eof:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def close(self) -> None:
        """Stop reading and close the descriptor (idempotent)."""
        self._stop.set()
        self._thread.join(KILL_WAIT_S)
        if self._thread.is_alive():  # pragma: no cover - the select timeout bounds every wait
            raise RuntimeError(f"the reader of {self.name} did not stop")
        if self._owner is not None:
            if not self._owner.closed:
                self._owner.close()
        elif self._fd >= 0:
            os.close(self._fd)
        self._fd = -1


class Child(Closing):
    """A command run in a process group of its own, its pipes drained, ended with the ``with`` block.

    *stdin*, *stdout* and *stderr* are as for :class:`subprocess.Popen` (default: no input, both outputs
    piped and read into :attr:`out` and :attr:`err`; ``subprocess.STDOUT`` merges stderr into
    :attr:`out`). A pipe's data is in ``child.out`` / ``child.err`` (:class:`Stream`), ``None`` when that
    output is not piped.
    """

    def __init__(
        self,
        argv: Sequence[str],
        *,
        cwd: Path | str | None = None,
        env: Mapping[str, str] | None = None,
        stdin: int | IO[bytes] | None = subprocess.DEVNULL,
        stdout: int | IO[bytes] | None = subprocess.PIPE,
        stderr: int | IO[bytes] | None = subprocess.PIPE,
        pass_fds: Sequence[int] = (),
    ) -> None:
        self.argv = list(argv)
        self.proc = subprocess.Popen(
            self.argv,
            cwd=cwd,
            env=None if env is None else dict(env),
            stdin=stdin,
            stdout=stdout,
            stderr=stderr,
            pass_fds=tuple(pass_fds),
            start_new_session=True,  # its own process group: ended as a whole
        )
        self.out = self._stream(self.proc.stdout, "stdout")
        self.err = self._stream(self.proc.stderr, "stderr")
        self._closed = False

    def _stream(self, pipe: IO[bytes] | None, name: str) -> Stream | None:
        if pipe is None:
            return None
        return Stream(pipe.fileno(), f"{name} of {' '.join(self.argv[:4])}", owner=pipe)

    @property
    def pid(self) -> int:
        """The child's process id (also its process group's id)."""
        return self.proc.pid

    @property
    def stdin(self) -> IO[bytes] | None:
        """The write end of the child's stdin when it was started with ``stdin=subprocess.PIPE``."""
        return self.proc.stdin

    def poll(self) -> int | None:
        """The exit status once the child has ended, else None."""
        return self.proc.poll()

    def send_signal(self, sig: int) -> None:
        """Send *sig* to the child alone (as ``Popen.send_signal``)."""
        self.proc.send_signal(sig)

    def wait(self, timeout: float) -> int:
        """The exit status; raises :class:`WaitTimeout` with the output so far after *timeout* seconds."""
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            raise WaitTimeout(f"{self.argv[:4]} still running after {timeout:g} s{self._tail()}") from None

    def finish(self, timeout: float) -> int:
        """Wait for the child to exit and its pipes to reach end of file (both within *timeout* seconds);
        return its exit status."""
        deadline = time.monotonic() + timeout
        status = self.wait(timeout)
        for stream in (self.out, self.err):
            if stream is not None and not stream.wait_eof(max(0.0, deadline - time.monotonic())):
                why = f"still open {timeout:g} s after the wait began (a process it started holds it)"
                raise WaitTimeout(f"{stream.name}: {why}{self._tail()}")
        return status

    def _tail(self) -> str:
        parts = [f"\n{s.name}:\n{s.text()[-2000:]}" for s in (self.out, self.err) if s is not None]
        return "".join(parts)

    def kill(self) -> None:
        """SIGKILL the child's whole process group (no-op once it is gone)."""
        kill_group(self.proc.pid)

    def close(self) -> None:
        """Kill the group, reap the child, stop the readers and close every pipe (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            self.kill()
            self.proc.wait(KILL_WAIT_S)
        finally:
            for stream in (self.out, self.err):
                if stream is not None:
                    stream.close()
            if self.proc.stdin is not None and not self.proc.stdin.closed:
                try:
                    self.proc.stdin.close()
                except BrokenPipeError:
                    pass


def kill_group(pid: int) -> None:
    """SIGKILL process group *pid* (a :class:`Child` leads its own); no-op once it has no member."""
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def run(
    argv: Sequence[str],
    *,
    timeout: float,
    cwd: Path | str | None = None,
    env: Mapping[str, str] | None = None,
    input: str | None = None,
) -> subprocess.CompletedProcess[str]:
    """Run *argv* to its end and return its exit status and output as text, like
    ``subprocess.run(argv, capture_output=True, text=True, timeout=timeout)``; on a timeout the child's
    whole process group is killed and :class:`subprocess.TimeoutExpired` raised with the output so far."""
    stdin = subprocess.PIPE if input is not None else subprocess.DEVNULL
    with Child(argv, cwd=cwd, env=env, stdin=stdin) as child:
        if input is not None and child.stdin is not None:
            feeder = threading.Thread(target=_feed, args=(child.stdin, input), daemon=True)
            feeder.start()
        try:
            status = child.finish(timeout)
        except WaitTimeout:
            child.kill()
            assert child.out is not None and child.err is not None
            raise subprocess.TimeoutExpired(child.argv, timeout, child.out.data, child.err.data) from None
        assert child.out is not None and child.err is not None
        return subprocess.CompletedProcess(child.argv, status, child.out.text(), child.err.text())


def _feed(pipe: IO[bytes], text: str) -> None:
    """Write *text* to the child's stdin and close it (a child that stops reading ends it early)."""
    try:
        with pipe:
            pipe.write(text.encode())
    except (BrokenPipeError, ValueError):
        pass


def children_of_this_process() -> dict[int, str]:
    """{pid: command line} of every living child process of this process (zombies left out: they have
    ended, and their ``Popen`` reaps them without a warning). Empty where ``/proc`` has no task list."""
    found: dict[int, str] = {}
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        return found
    for tid in tasks:
        try:
            pids = Path(f"/proc/self/task/{tid}/children").read_text().split()
        except OSError:  # the thread has ended
            continue
        for pid in map(int, pids):
            state, command = _state(pid)
            if state not in ("", "Z", "X"):
                found[pid] = command
    return found


def is_running(pid: int) -> bool:
    """True while process *pid* exists and has not ended (a zombie has ended)."""
    return _state(pid)[0] not in ("", "Z", "X")


def _state(pid: int) -> tuple[str, str]:
    """(state letter, command line) of process *pid*; ("", "") once it is gone."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        command = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return "", ""
    return stat.rsplit(")", 1)[1].split()[0], command.strip()


def end_leftovers(before: set[int], grace_s: float) -> dict[int, str]:
    """End the children of this process that were not in *before* and are still running after
    *grace_s* seconds (a process already told to stop gets that long to go); return {pid: command line}
    of those that had to be killed (with their process group when they lead one)."""

    def new() -> dict[int, str]:
        return {p: c for p, c in children_of_this_process().items() if p not in before}

    try:
        wait_until(lambda: not new(), grace_s, what="the processes this test started to end")
    except WaitTimeout:
        pass
    left = new()
    for pid in left:
        try:
            leads = os.getpgid(pid) == pid
        except ProcessLookupError:
            continue
        if leads:
            kill_group(pid)
        else:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    return left
