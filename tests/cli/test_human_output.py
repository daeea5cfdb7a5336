"""The CLI's text output is for people, its ``--json`` for scripts.

Every subcommand is run as a user runs it (a ``station`` subprocess in a temporary folder holding the
files the product writes itself) and its text must hold no Python dict or list repr and no float with
more than 4 decimals; a new subcommand not listed here fails :func:`test_every_subcommand_is_covered`.
The ``--json`` output is the handler's own dict, unchanged, and the text formatter's rounding, units
and recipe lines are checked against numbers worked out by hand.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
import subprocess
from pathlib import Path
from typing import Any

import pytest

from station.cli import build_parser
from station.cli._common import run_handler, to_jsonable
from station.cli._text import format_number, format_table, human_text
from station.model import FaceFlopTravelGloss
from station.model.design_io import save_design
from tests.user_cli import run_station

LAB3 = "60,20,10;50,20,10;40,20,12"
SMP3 = "61,20,10;50,21,10;40,20,13"
DB = "sqlite:///q.db"

#: One text-output run per subcommand (the leaf of ``station --help``'s tree), from the user folder of
#: :func:`folder`. ``db`` and ``users`` take their action as an argument: one run per action shown.
RUNS: dict[str, list[tuple[str, ...]]] = {
    "analysis gg-index": [("--design", "silver.json", "--light", "45", "--per-geometry")],
    "analysis trompe-loeil": [("--design", "silver.json", "--beta", "5", "--lights", "45,30")],
    "analysis seam": [("std.json", "smp.json", "--beta", "2")],
    "analysis sweep": [("--design", "silver.json", "--betas", "1,2", "--lights", "45", "--views", "0,10")],
    "booth": [("--standard", "std.cxf", "--sample", "smp.cxf")],
    "design variations": [
        (
            "--design",
            "silver.json",
        )
    ],
    "design eyedrop": [("r.png", "--face", "60,60", "--flop", "100,100")],
    "design render": [("--design", "silver.json", "--out", "dr.png")],
    "design palette": [("--design", "silver.json", "--out", "pal")],
    "design sketch-fit": [
        (
            "--art",
            "dr.png",
        )
    ],
    "library import": [("lib.csv",)],
    "library export": [("demo", "--out", "lib2.csv")],
    "library browse": [("--limit", "3")],
    "snap": [("--design", "silver.json", "--k", "3")],
    "formulate": [("silver.json",)],
    "export": [("silver.json", "--format", "cxf", "--out", "s.cxf", "--recipe")],
    "import": [("std.cxf",)],
    "instruments list": [()],
    "calibrate": [("sim:ma6", "--yes")],
    "measure": [("sim:ma6", "--design", "silver.json"), ("sim:gloss",)],
    "model from-angles": [("--angles", "15,45,110", "--lab", LAB3, "--gloss", "80")],
    "model eval": [("--design", "silver.json")],
    "model indices": [("--design", "silver.json")],
    "model gloss": [("--gu", "80")],
    "model de": [("--reference", LAB3, "--sample", SMP3, "--de", "din6175", "--angles", "15,45,110")],
    "model plot": [("silver.json", "--out", "p.png")],
    "qc verdict": [("--standard", LAB3, "--sample", SMP3, "--angles", "15,45,110")],
    "qc tolerance": [()],
    "qc check": [("--standard", "std.cxf", "--sample", "smp.cxf", "--illuminant-limits", "A=1")],
    "qc repeats": [("std.cxf", "smp.cxf")],
    "qc correlate": [("--a", "std.cxf", "--b", "smp.cxf")],
    "qc metamerism": [("--standard", "std.cxf", "--sample", "smp.cxf")],
    "qc jobs": [("--db", DB)],
    "qc search": [("--db", DB, "--job", "J1")],
    "qc standard set": [("--db", DB, "--job", "J1", "--part", "bumper", "--measurement", "1", "--replace")],
    "qc standard show": [("--db", DB, "--job", "J1", "--part", "bumper")],
    "qc summary": [("--db", DB, "--job", "J1")],
    "qc report": [("--db", DB, "--job", "J1", "--out", "rep.pdf")],
    "qc trend": [("--db", DB, "--job", "J1", "--part", "bumper", "--out", "trend.png")],
    "qc spc": [("--db", DB, "--job", "J1", "--part", "bumper", "--out", "spc.png")],
    "render": [("--design", "silver.json", "--out", "r2.png")],
    "reproduce": [("--figure", "4.4")],
    "sequence": [("silver.json", "red.json", "--steps", "4")],
    "tint": [("red-recipe.json", "--measured", "smp.json")],
    "db": [("current", "--database", DB), ("verify", "--database", DB)],
    "users": [("list", "--database", DB), ("tokens", "admin", "--database", DB)],
}

#: Subcommands whose output is not a result to format: a long-running process that prints what it is
#: doing (its lines are checked in tests/cli/test_found_cli.py) or the viewer's own screenshots.
NOT_RUN = {"serve": "runs until stopped", "viewer screenshots": "opens the viewer's windows"}

REPR = ("{'", "['", '{"', '["', "np.float64", "array(")
#: A list of numbers as Python or JSON writes it (``[90.0, 0.0]``); a figure id such as ``[4.4]`` is not.
NUMBER_LIST = re.compile(r"\[\[?-?\d+(\.\d+)?(e-?\d+)?, ")
#: A float with more than 4 decimals; the fraction of a clock time (``06:10:24.955021``) is not one.
LONG_FLOAT = re.compile(r"(?<![\d:.])\d+\.\d{5,}(?![\d])")


def _leaves(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()) -> list[str]:
    found: list[str] = []
    for action in parser._actions:  # argparse has no public walk of its subcommand tree
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += _leaves(sub, (*prefix, name)) or [" ".join((*prefix, name))]
    return found


def test_every_subcommand_is_covered() -> None:
    leaves = set(_leaves(build_parser()))
    assert leaves == set(RUNS) | set(NOT_RUN), "run each new subcommand in RUNS"


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A user folder with three designs, two scans of them (JSON and CxF), a render, a library file, the
    red design's recipe (``formulate --json``) and a database holding both scans and a scan of a third design under job J1, part bumper (the first its
    standard, so the part has the two judged samples ``qc spc`` charts) and a user — all written by
    ``station`` itself."""
    cwd = tmp_path_factory.mktemp("user")
    save_design(
        FaceFlopTravelGloss((90.0, 0.0, -2.0), (30.0, 0.0, -4.0), 60.0, 85.0, "silver"), cwd / "silver.json"
    )
    save_design(
        FaceFlopTravelGloss((60.0, 20.0, 10.0), (40.0, 22.0, 12.0), 70.0, 80.0, "red"), cwd / "red.json"
    )
    save_design(
        FaceFlopTravelGloss((50.0, -5.0, -30.0), (30.0, -4.0, -34.0), 65.0, 80.0, "blue"), cwd / "blue.json"
    )
    steps = [
        (("measure", "sim:ma6", "--design", "silver.json", "--json"), "std.json"),
        (("measure", "sim:ma6", "--design", "red.json", "--json"), "smp.json"),
        (("import", "std.json", "--out", "std.cxf"), None),
        (("import", "smp.json", "--out", "smp.cxf"), None),
        (("import", "std.cxf", "--store", DB, "--job", "J1", "--part", "bumper"), None),
        (("import", "smp.cxf", "--store", DB, "--job", "J1", "--part", "bumper"), None),
        (
            ("qc", "standard", "set", "--db", DB, "--job", "J1", "--part", "bumper", "--measurement", "1"),
            None,
        ),
        (("measure", "sim:ma6", "--design", "blue.json", "--json"), "smp2.json"),
        (("import", "smp2.json", "--store", DB, "--job", "J1", "--part", "bumper"), None),
        (("users", "add", "admin", "--role", "admin", "--database", DB), None),
        (("render", "--design", "silver.json", "--out", "r.png", "--size", "160"), None),
        (("library", "export", "demo", "--out", "lib.csv"), None),
        (("formulate", "red.json", "--json"), "red-recipe.json"),
    ]
    for argv, out in steps:
        done = run_station(cwd, *argv, env={"CACAD_DATA_DIR": str(cwd / "var")})
        assert done.returncode == 0, (argv, done.stderr)
        if out:
            (cwd / out).write_text(done.stdout)
    return cwd


def _text_problems(stdout: str) -> list[str]:
    problems = [f"repr {r!r}" for r in REPR if r in stdout]
    problems += [f"number list {m.group()}" for m in NUMBER_LIST.finditer(stdout)]
    return problems + [f"long float {m.group()}" for m in LONG_FLOAT.finditer(stdout)]


@pytest.mark.slow
@pytest.mark.parametrize(
    "argv", [(*name.split(), *args) for name, runs in RUNS.items() for args in runs], ids=" ".join
)
def test_text_output_is_for_people(folder: Path, argv: tuple[str, ...]) -> None:
    done: subprocess.CompletedProcess[str] = run_station(
        folder, *argv, env={"CACAD_DATA_DIR": str(folder / "var")}
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip()
    assert _text_problems(done.stdout) == [], done.stdout


def test_the_checker_catches_raw_prints() -> None:
    raw = "recipe: {'white': 0.003076536001588692}\nlab: [[90.0, 0.0]]\nx: np.float64(1.5)\nd: [\"a\"]\n"
    assert len(_text_problems(raw)) == 5
    fine = "expires: 2027-03-05T06:10:24.955021+00:00\nmean: 0.1213\n[4.4] seam ΔE: ours 4.52e-07\n"
    assert _text_problems(fine) == []


#: Commands of every module whose results the text formatter prints, run in this process.
JSON_RUNS = [
    ("model", "from-angles", "--angles", "15,45,110", "--lab", LAB3, "--gloss", "80"),
    ("model", "eval", "--face", "90,0,-2", "--flop", "30,0,-4", "--travel", "60"),
    ("model", "gloss", "--gu", "80"),
    ("model", "de", "--reference", LAB3, "--sample", SMP3),
    ("qc", "tolerance", "--formula", "cie2000", "--lc", "2:1"),
    ("qc", "verdict", "--standard", LAB3, "--sample", SMP3, "--angles", "15,45,110"),
    ("snap", "--lab", LAB3, "--k", "3"),
    ("formulate", LAB3),
    ("sequence", LAB3, SMP3, "--steps", "3"),
    ("design", "variations", "--face", "60,20,10", "--flop", "40,22,12", "--travel", "70"),
    ("analysis", "gg-index", "--face", "90,0,-2", "--flop", "30,0,-4", "--travel", "60", "--light", "45"),
    ("instruments", "list"),
]


@pytest.mark.parametrize("argv", JSON_RUNS, ids=" ".join)
def test_json_is_the_handlers_dict(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, argv: tuple[str, ...]
) -> None:
    """``--json`` prints the handler's own dict, byte for byte as ``json.dumps`` writes it: one line,
    every key in its order and every number to its last digit."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("STATION_CACHE_DIR", str(tmp_path / "cache"))
    args = build_parser().parse_args([*argv, "--json"])
    returned: list[dict[str, Any]] = []

    def handler(ns: argparse.Namespace) -> dict[str, Any]:
        returned.append(args.handler(ns))
        return returned[-1]

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert run_handler(handler, args) == 0
    assert out.getvalue() == json.dumps(to_jsonable(returned[0])) + "\n"
    assert json.loads(out.getvalue()).keys() == returned[0].keys()


def test_numbers_rounded_with_units_from_their_keys() -> None:
    assert format_number("travel_deg", 59.98123) == "59.98°"
    assert format_number("gloss_gu", 85.04) == "85.0 GU"
    assert format_number("mean_de", 0.12134) == "0.12"
    assert format_number("face", -7.1e-09) == "0.00"  # no "-0.00"
    assert format_number("binder_g", 819.23645) == "819.24 g"
    assert format_number("temperature_c", 29.5) == "29.5 °C"
    assert format_number("c", 1.0) == "1"  # a one-word key names no unit
    assert format_number("resolution_deg", 1e-6) == "1.00e-06°"  # not rounded to zero
    assert format_number("specular_albedo", 0.10012345) == "0.1001"
    assert format_number("coat_peak_exponent", 168034.2) == "1.68e+05"


def test_recipe_one_colorant_a_line_in_percent_and_grams() -> None:
    recipe = {"white_tio2": 0.003076536001588692, "alu_bright": 0.010400032500923266}
    batch = {"colorants_g": {k: v * 1000 for k, v in recipe.items()}, "binder_g": 986.5, "total_g": 1000.0}
    text = human_text({"recipe": recipe, "batch": batch})
    lines = text.splitlines()
    assert lines[0] == "recipe: (%, g per batch)"
    assert lines[1].split() == ["white_tio2", "0.31", "%", "3.08", "g"]
    assert lines[2].split() == ["alu_bright", "1.04", "%", "10.40", "g"]
    assert "binder_g: 986.50 g" in text and "total_g: 1000.00 g" in text
    assert human_text({"recipe": recipe}).splitlines()[1].split() == ["white_tio2", "0.31", "%"]


def test_lab_rows_are_a_table_labelled_by_geometry() -> None:
    text = human_text(
        {"geometries": ["45as15", "45as110"], "lab": [[90.00987, -0.0219, -1.98], [30.0, 0.0, -4.0]]}
    )
    lines = text.splitlines()
    assert lines[2].split() == ["L*", "a*", "b*"]
    assert lines[3].split() == ["45as15", "90.01", "-0.02", "-1.98"]
    assert lines[4].split() == ["45as110", "30.00", "0.00", "-4.00"]
    # the numbers of one column end in the same place
    assert len({len(line) for line in lines[3:]}) == 1


def test_rows_of_dicts_are_an_aligned_table() -> None:
    text = human_text(
        {"devices": [{"address": "sim:ma6", "family": "ma6"}, {"address": "sim:gloss", "family": "gloss"}]}
    )
    assert text.splitlines() == [
        "devices:",
        "  address    family",
        "  sim:ma6       ma6",
        "  sim:gloss   gloss",
    ]
    assert format_table([["a", "1"], ["bbb", "22"]], ["x", "y"]) == "x     y\na     1\nbbb  22"
