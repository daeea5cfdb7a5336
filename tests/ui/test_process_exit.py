"""A viewer test process that drew a GL view ends with status 0 (tests/ui/conftest.py's deferred deletes):
before, such a process crashed at interpreter exit (SIGSEGV, status 139) after reporting its results,
and its Xvfb was left running."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from tests.processes import run

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.gl
def test_a_viewer_process_that_drew_a_gl_view_exits_with_status_0() -> None:
    done = run(
        [
            sys.executable,
            "-m",
            "pytest",
            "tests/ui/test_view.py::test_drag_orbits_and_wheel_zooms",
            "-q",
            "-n",
            "0",
            "-p",
            "no:cacheprovider",
        ],
        cwd=ROOT,
        timeout=300,
    )
    assert "1 passed" in done.stdout, done.stdout[-2000:] + done.stderr[-2000:]
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
