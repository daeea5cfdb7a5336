"""The command line as a person uses it, each a real ``station`` (or ``python -m bench.X``) subprocess
run from a temporary user folder that is not the repository: a relative ``--design`` reaches the
simulator, ``analysis seam`` takes ``station measure --json`` output, ``model plot`` names unnamed
designs by their file, a closed pipe is quiet, help texts are for people, benchmarks refuse to start
on ``--help``, ``serve`` says what it is doing from the start."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.design_io import save_design
from station.model.spectra import reflectance_to_lab
from tests.processes import Child, Stream, children_of_this_process, is_running, run
from tests.serve_process import free_port
from tests.user_cli import run_station
from tests.waiting import WaitTimeout, wait_until

REPO = Path(__file__).resolve().parents[2]
SILVER = FaceFlopTravelGloss((90.0, 0.0, -2.0), (30.0, 0.0, -4.0), 60.0, 85.0, "silver")


def _folders(cwd: Path) -> dict[str, str]:
    """The cache and data folders in the user's folder *cwd*."""
    return {"CACAD_CACHE_DIR": str(cwd / "cache"), "CACAD_DATA_DIR": str(cwd / "data")}


def _env(cwd: Path) -> dict[str, str]:
    """The whole environment for the cases that drive the process themselves (Popen), as run_station."""
    env = dict(os.environ, PYTHONPATH=str(REPO), **_folders(cwd))
    env.pop("CACAD_DATABASE_URL", None)
    return env


def station(cwd: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args, env=_folders(cwd), timeout=timeout)


@pytest.mark.slow
def test_measure_from_the_users_folder_then_seam_of_its_output(tmp_path: Path) -> None:
    assert not tmp_path.is_relative_to(REPO)
    save_design(SILVER, tmp_path / "silver.json")
    res = station(tmp_path, "measure", "sim:ma6", "--design", "silver.json", "--json")
    assert res.returncode == 0, res.stderr
    (tmp_path / "scan.json").write_text(res.stdout)
    scan = json.loads(res.stdout)
    assert scan["geometries"] == ["45as-15", "45as15", "45as25", "45as45", "45as75", "45as110"]
    # the simulator measured the design it was given (relative to the user's folder)
    lab = reflectance_to_lab(np.asarray(scan["spectra"]))
    np.testing.assert_allclose(lab[1], SILVER.lab_at(15.0), atol=1.5)
    np.testing.assert_allclose(lab[-1], SILVER.lab_at(110.0), atol=1.5)
    seam = station(tmp_path, "analysis", "seam", "scan.json", "scan.json", "--beta", "2", "--json")
    assert seam.returncode == 0, seam.stderr
    got = json.loads(seam.stdout)
    # the same scan on both panels: no formulation ΔE; panel A is the fit of the positive angles
    fit = fit_fftg(AspecularMeasurements((15.0, 25.0, 45.0, 75.0, 110.0), np.asarray(scan["lab"][1:]))).design
    assert got["formulation_de_max"] == pytest.approx(0.0, abs=1e-9)
    assert got["paint_a"]["face"] == pytest.approx(list(fit.face), abs=1e-6)
    # a measurement without three positive 45° angles is refused with the field, exit 2, one line
    (tmp_path / "short.json").write_text(json.dumps({"geometries": ["45as15"], "lab": [[50, 0, 0]]}))
    bad = station(tmp_path, "analysis", "seam", "short.json", "scan.json", "--beta", "2")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "panel" in bad.stderr


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        ((), "COMMAND"),
        (("formulate", "x", "--type", "chrome"), "--type"),
        (("render", "--design", "d.json"), "--out"),
        (("qc", "check", "--formula", "cie1976"), "--standard"),
        (("snap", "--k", "many"), "--k"),
    ],
)
def test_a_usage_error_is_one_line_naming_the_argument(
    tmp_path: Path, argv: tuple[str, ...], named: str
) -> None:
    res = run_station(tmp_path, *argv)
    assert res.returncode == 2 and res.stdout == ""
    assert res.stderr.count("\n") == 1 and res.stderr.startswith("error: station")
    assert named in res.stderr and "--help" in res.stderr


def test_model_plot_names_an_unnamed_design_by_its_file(tmp_path: Path) -> None:
    save_design(SILVER.replace(name=""), tmp_path / "bumper.json")
    res = station(tmp_path, "model", "plot", "bumper.json", "--out", "p.png")
    assert res.returncode == 0, res.stderr
    assert "designs: bumper\n" in res.stdout and (tmp_path / "p.png").stat().st_size > 10_000


def test_a_closed_pipe_is_quiet(tmp_path: Path) -> None:
    save_design(SILVER, tmp_path / "silver.json")
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader (``| head``) has gone before anything is written
    try:
        argv = [
            sys.executable,
            "-m",
            "station.cli",
            "model",
            "eval",
            "--design",
            "silver.json",
            "--angles",
            "15,45",
        ]
        child = Child(argv, cwd=tmp_path, env=_env(tmp_path), stdout=write_end)
    finally:
        os.close(write_end)
    with child:
        assert child.finish(120) == 141
        assert child.err is not None
        assert child.err is not None and child.err.text() == "", child.err.text()


def test_no_help_text_shows_markup_or_internal_names() -> None:
    """Every command's and subcommand's --help is plain text: no reStructuredText literals or roles, no
    dotted module paths."""
    import argparse
    import re

    from station.cli import build_parser

    def walk(parser: argparse.ArgumentParser, path: str):
        yield path, parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from walk(sub, f"{path} {name}")

    seen = 0
    for path, parser in walk(build_parser(), "station"):
        text = parser.format_help()
        seen += 1
        assert "``" not in text and ":func:" not in text and ":class:" not in text, path
        assert not re.search(r"\bstation\.[a-z_]+\.[a-z_]+", text), path
    assert seen > 40


def test_help_texts_are_for_people(tmp_path: Path) -> None:
    render = station(tmp_path, "render", "--help")
    assert render.returncode == 0
    assert "``" not in render.stdout and "station.render." not in render.stdout
    assert "--design DESIGN" in render.stdout and "example: station render" in render.stdout
    seam = station(tmp_path, "analysis", "seam", "--help").stdout.split("positional arguments:")[1]
    for option in ("PANEL_A", "PANEL_B", "--lights LIGHTS", "--aspecular ASPECULAR", "--objective"):
        line = next(x for x in seam.splitlines() if x.strip().startswith(option))
        text = line.strip()[len(option) :].strip() or seam.splitlines()[seam.splitlines().index(line) + 1]
        assert len(text.strip()) > 10, (option, seam)
    assert "station measure --json" in " ".join(seam.split())  # wrapped by argparse


#: Every benchmark module under bench/ (a new one is covered without editing this list).
BENCHES = sorted(p.stem for p in (REPO / "bench").glob("*.py") if not p.stem.startswith("_"))

#: Runs ``python -m bench.NAME ARG`` for each NAME in one interpreter (imports are paid once) and prints
#: the exit status, seconds and output of each as JSON.
_HELP_DRIVER = """
import contextlib, io, json, runpy, sys, time
out = {}
for name in sys.argv[2:]:
    for arg in ("--help", "--no-such-option"):
        stdout, stderr = io.StringIO(), io.StringIO()
        sys.argv = [f"bench/{name}.py", arg]
        t0 = time.perf_counter()
        code = None
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            try:
                runpy.run_module(f"bench.{name}", run_name="__main__", alter_sys=True)
            except SystemExit as exc:
                code = exc.code
        out[f"{name} {arg}"] = [code, time.perf_counter() - t0, stdout.getvalue(), stderr.getvalue()]
print(json.dumps(out))
"""


def test_no_benchmark_starts_on_help(tmp_path: Path) -> None:
    report = REPO / "docs" / "benchmarks.md"
    before = report.stat().st_mtime_ns if report.exists() else None
    res = run([sys.executable, "-c", _HELP_DRIVER, "x", *BENCHES], timeout=240, cwd=REPO, env=_env(tmp_path))
    assert res.returncode == 0, res.stderr
    got = json.loads(res.stdout)
    assert len(BENCHES) >= 18
    for bench in BENCHES:
        code, _, stdout, _ = got[f"{bench} --help"]
        assert code == 0, bench
        # the usage comes first: nothing was measured (or printed) before the arguments were read
        assert stdout.startswith(f"usage: python -m bench.{bench}") and "rewrites" in stdout, bench
        code, _, _, stderr = got[f"{bench} --no-such-option"]
        assert code == 2 and "unrecognized arguments" in stderr, bench
    assert (report.stat().st_mtime_ns if report.exists() else None) == before


#: A module of the service proper (imported only once ``serve`` runs), as ``-X importtime`` names it.
_SERVICE_IMPORT = re.compile(r"^import time:.*\|\s+(uvicorn|station\.api)$", re.MULTILINE)


@pytest.mark.slow
def test_serve_says_what_it_does_from_the_start(tmp_path: Path) -> None:
    """Its first line comes before the service's modules are loaded (Python's import-time log, on the
    same pipe, shows the order whatever the machine's load), and each step is announced as it begins."""
    env = dict(_env(tmp_path), PYTHONUNBUFFERED="1", PYTHONPROFILEIMPORTTIME="1")
    argv = [sys.executable, "-m", "station.cli", "serve", "--port", str(free_port()), "--simulators", ""]
    with Child(argv, cwd=tmp_path, env=env, stderr=subprocess.STDOUT) as child:
        assert child.out is not None
        log = child.out.wait_for("opening the database", timeout=180)
    said = [line for line in log.splitlines() if not line.startswith("import time:")]
    assert said[0].startswith("starting the station service"), said
    service = _SERVICE_IMPORT.search(log)
    assert service is not None, log[-2000:]
    assert log.index("starting the station service") < service.start(), "the modules were loaded first"


def _on_a_terminal(
    cwd: Path,
    argv: list[str],
    *,
    interrupt_at: str | None = None,
    interrupt_within: float = 180,
    timeout: float = 180,
) -> tuple[int, str, str]:
    """Run *argv* with stderr on a pseudo-terminal (as a person's shell has it) and stdout on a pipe;
    optionally press Ctrl+C (SIGINT) once the terminal shows *interrupt_at* (within *interrupt_within*
    seconds). Returns (status, stdout, terminal). The run must end within *timeout* seconds (after the
    Ctrl+C, if any), else ``WaitTimeout``; the process and whatever it started are killed on the way out."""
    import fcntl
    import pty
    import struct
    import termios

    leader, follower = pty.openpty()
    try:
        fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # 100 columns
        child = Child(argv, cwd=cwd, env=_env(cwd), stderr=follower)
    except BaseException:
        os.close(leader)
        raise
    finally:
        os.close(follower)
    # the terminal is read while the child runs: Linux drops a closed terminal's unread output
    with child, Stream(leader, "terminal") as terminal:
        assert child.out is not None
        if interrupt_at is not None:
            terminal.wait_for(interrupt_at, interrupt_within)
            child.send_signal(signal.SIGINT)
        status = child.finish(timeout)
        terminal.wait_eof(timeout)
        return status, child.out.text(), terminal.text()


def _station_on_a_terminal(cwd: Path, *args: str, interrupt_at: str | None = None) -> tuple[int, str, str]:
    """``station ARGS`` on a terminal (:func:`_on_a_terminal`)."""
    return _on_a_terminal(cwd, [sys.executable, "-m", "station.cli", *args], interrupt_at=interrupt_at)


def test_a_terminal_run_that_hangs_fails_in_time_and_leaves_nothing_running(tmp_path: Path) -> None:
    """A command that ignores Ctrl+C and never ends: the wait fails at its deadline and the command and
    the process it started are gone (a leaked one broke a later test through a ResourceWarning)."""
    pid_file = tmp_path / "grandchild.pid"
    stubborn = (
        "import pathlib, signal, subprocess, sys, time\n"
        "signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
        "kid = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)'])\n"
        f"pathlib.Path({str(pid_file)!r}).write_text(str(kid.pid))\n"
        "print('ready', file=sys.stderr, flush=True)\n"
        "time.sleep(600)\n"
    )
    before = set(children_of_this_process())
    with pytest.raises(WaitTimeout, match="still running"):
        _on_a_terminal(tmp_path, [sys.executable, "-c", stubborn], interrupt_at="ready", timeout=2)
    assert set(children_of_this_process()) <= before
    grandchild = int(pid_file.read_text())
    wait_until(lambda: not is_running(grandchild), 10, what="the grandchild to be gone")


@pytest.mark.slow
def test_a_long_command_shows_its_steps_on_a_terminal_and_ctrl_c_cancels(tmp_path: Path) -> None:
    save_design(SILVER, tmp_path / "silver.json")
    status, out, err = _station_on_a_terminal(
        tmp_path, "measure", "sim:ma6", "--design", "silver.json", "--json"
    )
    assert status == 0, err
    assert "connecting sim:ma6" in err and "measuring" in err and "step" in err
    assert json.loads(out)["geometries"][0] == "45as-15"  # the data on stdout stays clean
    piped = station(tmp_path, "formulate", "silver.json")
    assert piped.returncode == 0 and piped.stderr == ""  # no bar when stderr is not a terminal
    status, out, err = _station_on_a_terminal(tmp_path, "formulate", "silver.json", "--closed-loop")
    assert status == 0 and "closed loop" in err, (status, err)  # its steps, on the terminal
    # Ctrl+C during a command that runs long whatever the machine (the lobe basis search, minutes): a
    # command as quick as the closed loop can finish before the key press arrives
    status, out, err = _station_on_a_terminal(
        tmp_path, "reproduce", "--figure", "2.4", interrupt_at="ch2-basis"
    )
    assert status == 130 and out == "", (status, err)
    assert "cancelled (Ctrl+C)" in err and "Traceback" not in err
