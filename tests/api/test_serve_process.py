"""The test tooling that starts ``station serve`` gives up on a silent child at its deadline."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.serve_process import ServeProcess, ServeStartError

REPO = Path(__file__).resolve().parents[2]

#: Imported by the child's interpreter before anything else: it blocks without printing a line.
_SILENT = "import select\nselect.select([], [], [])\n"


def test_silent_child_is_given_up_and_killed_at_the_deadline(tmp_path: Path) -> None:
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(_SILENT)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(site), str(REPO), env.get("PYTHONPATH", "")) if p)
    svc = ServeProcess(tmp_path / "data", ("--no-demo-library",), env=env, cwd=REPO, start_timeout_s=3)
    with pytest.raises(ServeStartError, match="did not start in 3 s"):
        svc.start()  # blocked in readline for ever before the reader thread
    assert svc.proc is not None
    assert svc.proc.wait(10) is not None  # killed and reaped, nothing left behind


def test_child_that_exits_early_is_reported_with_its_status(tmp_path: Path) -> None:
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text("import os\nprint('no service today', flush=True)\nos._exit(3)\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(site), str(REPO), env.get("PYTHONPATH", "")) if p)
    svc = ServeProcess(tmp_path / "data", env=env, cwd=REPO, start_timeout_s=30)
    with pytest.raises(ServeStartError, match=r"exited \(3\)[\s\S]*no service today"):
        svc.start()
