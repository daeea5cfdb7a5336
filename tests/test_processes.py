"""The suite's own process and waiting rules (``tests.processes``, ``tests.waiting``, ``tests.services``):
a child never outlives its test, no read waits without a deadline, a missing service fails under CI."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.processes import Child, children_of_this_process, end_leftovers, is_running, run
from tests.services import service_missing
from tests.waiting import WaitTimeout, wait_until

#: A Python child that starts a grandchild (in its process group), writes the grandchild's pid to the
#: file named by argv[1], says "ready" on stdout and then runs for ten minutes, ignoring SIGINT/SIGTERM.
STUBBORN = """
import pathlib, signal, subprocess, sys, time
for sig in (signal.SIGINT, signal.SIGTERM):
    signal.signal(sig, signal.SIG_IGN)
kid = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
pathlib.Path(sys.argv[1]).write_text(str(kid.pid))
print("ready", flush=True)
time.sleep(600)
"""


def _stubborn(tmp_path: Path) -> tuple[list[str], Path]:
    pid_file = tmp_path / "grandchild.pid"
    return [sys.executable, "-c", STUBBORN, str(pid_file)], pid_file


def test_leaving_the_block_ends_the_child_and_what_it_started(tmp_path: Path) -> None:
    argv, pid_file = _stubborn(tmp_path)
    with Child(argv) as child:
        assert child.out is not None
        child.out.wait_for("ready", timeout=60)
        grandchild = int(pid_file.read_text())
        assert is_running(child.pid) and is_running(grandchild)
    assert child.proc.returncode == -signal.SIGKILL  # reaped
    assert child.proc.stdout is not None and child.proc.stdout.closed
    wait_until(lambda: not is_running(grandchild), 10, what="the grandchild to end with its group")


def test_a_failing_test_body_still_ends_the_child(tmp_path: Path) -> None:
    argv, pid_file = _stubborn(tmp_path)
    with pytest.raises(RuntimeError, match="half-way"), Child(argv) as child:
        assert child.out is not None
        child.out.wait_for("ready", timeout=60)
        raise RuntimeError("the test failed half-way")
    assert child.poll() == -signal.SIGKILL
    grandchild = int(pid_file.read_text())
    wait_until(lambda: not is_running(grandchild), 10, what="the grandchild to end with its group")


def test_a_read_waits_no_longer_than_its_deadline() -> None:
    """A silent child: waiting for a line it never prints fails at the deadline, with what was read."""
    argv = [sys.executable, "-c", "import sys, time; print('hello', flush=True); time.sleep(600)"]
    with Child(argv) as child:
        assert child.out is not None
        child.out.wait_for("hello", timeout=60)
        t0 = time.monotonic()
        with pytest.raises(WaitTimeout, match="hello") as raised:
            child.out.wait_for("goodbye", timeout=0.3)
        assert time.monotonic() - t0 < 30  # bounded by the deadline, not by the child (600 s)
        assert "not seen within 0.3 s" in str(raised.value)
        with pytest.raises(WaitTimeout, match="still running"):
            child.wait(0.2)


def test_a_read_of_a_stream_that_ends_fails_at_once() -> None:
    with Child([sys.executable, "-c", "print('only this')"]) as child:
        assert child.finish(60) == 0
        assert child.out is not None and child.out.text() == "only this\n"
        with pytest.raises(WaitTimeout, match="ended"):
            child.out.wait_for("more", timeout=600)


def test_a_chatty_child_never_blocks_on_a_full_pipe() -> None:
    """4 MiB on stdout and stderr each, far beyond a pipe's buffer, drained while the child runs."""
    code = "import sys; sys.stdout.write('o' * (4 << 20)); sys.stderr.write('e' * (4 << 20))"
    res = run([sys.executable, "-c", code], timeout=120)
    assert res.returncode == 0 and len(res.stdout) == 4 << 20 and len(res.stderr) == 4 << 20


def test_run_is_subprocess_run_with_text_output(tmp_path: Path) -> None:
    code = "import os, sys; print(sys.stdin.read().upper(), os.getcwd()); sys.stderr.write('a\\r\\nb'); sys.exit(3)"
    res = run([sys.executable, "-c", code], timeout=60, cwd=tmp_path, input="abc")
    assert res.returncode == 3
    assert res.stdout == f"ABC {tmp_path}\n" and res.stderr == "a\nb"  # universal newlines, as text=True


def test_run_past_its_timeout_kills_the_whole_group(tmp_path: Path) -> None:
    """``subprocess.run`` kills only the child: a grandchild keeps running (and keeps the pipe open)."""
    argv, pid_file = _stubborn(tmp_path)
    for timeout in (2, 20, 120):  # long enough for the child to have started its grandchild
        with pytest.raises(subprocess.TimeoutExpired) as raised:
            run(argv, timeout=timeout)
        if raised.value.stdout is not None and b"ready" in raised.value.stdout:
            break
    else:
        pytest.fail("the child never got to start its grandchild")
    grandchild = int(pid_file.read_text())
    wait_until(lambda: not is_running(grandchild), 10, what="the grandchild to end with its group")


def test_a_process_left_running_is_found_and_ended() -> None:
    """What ``tests/conftest.py`` does after every test: a child started (and not ended) since the look
    before is killed and named; one that has ended, or ends by itself within the grace time, is not."""
    before = set(children_of_this_process())
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    stopping = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=subprocess.PIPE)
    left_behind = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    try:
        assert ended.wait(60) == 0
        assert {stopping.pid, left_behind.pid} <= set(children_of_this_process())
        killed = end_leftovers(before, grace_s=0.2)
        assert set(killed) == {stopping.pid, left_behind.pid}
        assert "time.sleep(600)" in killed[left_behind.pid]
        assert left_behind.wait(10) == -signal.SIGKILL
        assert stopping.wait(10) == -signal.SIGKILL
        told = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=subprocess.PIPE)
        assert told.stdin is not None
        told.stdin.close()  # told to stop: it goes by itself, well within the grace time
        assert end_leftovers(before, grace_s=120) == {}
        assert told.wait(10) == 0
    finally:
        for proc in (ended, stopping, left_behind):
            if proc.poll() is None:
                proc.kill()
            proc.wait(10)
            if proc.stdin is not None:
                proc.stdin.close()


def test_wait_until_returns_the_value_or_fails_at_the_deadline() -> None:
    calls: list[int] = []

    def third_time() -> int:
        calls.append(1)
        return len(calls) if len(calls) >= 3 else 0

    assert wait_until(third_time, timeout=60, interval=0.001) == 3
    with pytest.raises(WaitTimeout, match=r"not true within 0\.1 s: the answer \(last seen: 0\)"):
        wait_until(lambda: 0, timeout=0.1, interval=0.01, what="the answer")
    seen: list[int] = []
    with pytest.raises(WaitTimeout):
        wait_until(lambda: seen.append(1), timeout=0)
    assert seen == [1]  # called once even with no time left
    with pytest.raises(ValueError, match="interval"):
        wait_until(lambda: True, timeout=1, interval=0)


def test_a_missing_service_skips_on_a_desk_and_fails_under_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match="no OpenGL context"):
        service_missing("no OpenGL context: EGL not found")
    for value in ("true", "TRUE", "True"):
        monkeypatch.setenv("CI", value)
        with pytest.raises(pytest.fail.Exception, match="no OpenGL context"):
            service_missing("no OpenGL context: EGL not found")
    monkeypatch.setenv("CI", "false")
    with pytest.raises(pytest.skip.Exception):
        service_missing("PostgreSQL not reachable")


def test_the_processes_tests_start_take_ctrl_c() -> None:
    """Even when the runner was started with SIGINT ignored (``nohup … &``), the processes the tests start
    get SIGINT's default (tests/conftest.py), so the Ctrl-C tests test the product, not the runner."""
    import signal

    assert signal.getsignal(signal.SIGINT) is not signal.SIG_IGN
    code = "import signal; print(signal.getsignal(signal.SIGINT) is signal.default_int_handler)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "True"
