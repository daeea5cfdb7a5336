"""The command line answers at once: ``station --help``, ``station --version`` and every ``station X
--help`` import nothing beyond the standard library, NumPy and the product's own light modules (no
colour-science, SciPy, Matplotlib, SQLAlchemy, FastAPI, Qt or GL). The timing against a bare
``import numpy`` is in ``bench/cli_start.py``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from tests.processes import run

REPO = Path(__file__).resolve().parents[2]
#: Third-party packages the start-up path may load.
ALLOWED = {"numpy"}

_PROBE = """
import json, sys
from station.cli import build_parser, main

commands = {commands}
for argv in commands:
    try:
        main(argv)
    except SystemExit:
        pass
ours = {{"station", "__main__", "__editable___cacad_station_0_1_0_finder", "_distutils_hack"}}
# a library submodule the product defers (station.lazy.defer_submodule) is a stand-in, not an import
top = {{m.split(".")[0] for m, mod in sys.modules.items() if type(mod).__name__ != "_DeferredSubmodule"}}
foreign = sorted(t for t in top if t not in sys.stdlib_module_names and t not in ours and not t.startswith("_"))
print(json.dumps(foreign), file=sys.stderr)
"""


def _foreign(commands: list[list[str]]) -> list[str]:
    done = run([sys.executable, "-c", _PROBE.format(commands=commands)], cwd=REPO, timeout=120)
    assert done.stderr.strip(), done.stdout[-2000:]
    return list(json.loads(done.stderr.strip().splitlines()[-1]))


def _subcommands() -> list[str]:
    from station.cli import build_parser

    parser = build_parser()
    action = next(a for a in parser._actions if a.dest == "command")  # argparse has no public API for it
    assert action.choices is not None
    return sorted(action.choices)


@pytest.mark.parametrize("argv", [["--help"], ["--version"]])
def test_the_top_level_answers_without_heavy_imports(argv: list[str]) -> None:
    assert set(_foreign([argv])) <= ALLOWED


def test_every_subcommand_help_answers_without_heavy_imports() -> None:
    names = _subcommands()
    assert {"analysis", "booth", "design", "qc", "render", "serve", "viewer"} <= set(names)
    assert set(_foreign([[name, "--help"] for name in names])) <= ALLOWED


def test_the_probe_sees_a_heavy_import() -> None:
    """The check can fail: running a command that does load the model shows colour-science."""
    foreign = _foreign([["model", "de", "--reference", "50,0,0", "--sample", "51,0,0", "--de", "cie76"]])
    assert "colour" in foreign


def test_database_and_user_commands_load_no_colour_science(tmp_path: Path) -> None:
    """``station db`` and ``station users`` reach the database (SQLAlchemy) without the service's
    application or the colour stack (colour-science, SciPy, Matplotlib: seconds of start-up)."""
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    foreign = set(
        _foreign(
            [
                ["db", "upgrade", "--database", url],
                ["db", "current", "--database", url],
                ["users", "add", "ana", "--database", url],
                ["users", "list", "--database", url],
            ]
        )
    )
    assert (tmp_path / "station.sqlite3").is_file()
    assert "sqlalchemy" in foreign, foreign
    assert not foreign & {"colour", "scipy", "matplotlib"}, foreign


def test_model_and_qc_commands_load_no_colour_science(tmp_path: Path) -> None:
    """Commands that evaluate the model, judge Lab values against a tolerance or render a design compute
    with NumPy alone (the product's Lab, sRGB and CIEDE2000 formulae): they load no colour-science, SciPy
    or Matplotlib."""
    lab3 = "60,20,10;50,20,10;40,20,12"
    smp3 = "61,20,10;50,21,10;40,20,13"
    design = ["--face", "90,0,-2", "--flop", "30,0,-4", "--travel", "60"]
    foreign = set(
        _foreign(
            [
                ["model", "eval", *design],
                ["model", "from-angles", "--angles", "15,45,110", "--lab", lab3, "--gloss", "80"],
                ["qc", "tolerance"],
                ["qc", "verdict", "--standard", lab3, "--sample", smp3, "--angles", "15,45,110"],
                ["design", "variations", *design],
                ["design", "render", *design, "--size", "32", "--out", str(tmp_path / "d.png")],
            ]
        )
    )
    assert (tmp_path / "d.png").is_file()
    assert not foreign & {"colour", "scipy", "matplotlib"}, foreign
