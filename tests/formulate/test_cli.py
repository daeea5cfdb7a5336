"""CLI: station library|snap|formulate|export, JSON output and exit statuses."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.cli import main
from station.formulate.color_xml import read_color_xml
from station.formulate.cxf import read_cxf_specs
from station.formulate.demo import demo_library
from station.formulate.library import Library
from station.formulate.library_csv import read_library_csv, write_library_csv
from station.formulate.snap import brute_force
from tests.user_cli import run_station

LAB = "60,30,10;40,28,12;20,20,10"


def _run(capsys, *argv: str) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_snap_json_matches_brute_force_and_writes_png(capsys, tmp_path) -> None:
    png = tmp_path / "view.png"
    out = _run(
        capsys, "snap", "--library", "demo", "--lab", LAB, "--k", "4", "--de", "din6175", "--png", str(png)
    )
    lib = demo_library()
    rows, sums, _ = brute_force(
        lib.angle_columns(), np.array([[60, 30, 10], [40, 28, 12], [20, 20, 10.0]]), 4, "din6175"
    )
    assert [m["code"] for m in out["matches"]] == lib.codes[rows].tolist()
    assert [m["sum_de"] for m in out["matches"]] == sums.tolist()
    assert all(len(m["de_per_angle"]) == 3 for m in out["matches"])
    assert isinstance(out["warnings"], list) and out["synthetic"] is True
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_library_import_export_browse(capsys, tmp_path, small_library: Library) -> None:
    src = tmp_path / "lib.csv"
    write_library_csv(small_library, src)
    out = _run(capsys, "library", "import", str(src), "--out", str(tmp_path / "lib.cxf"))
    assert out["paints"] == len(small_library) and out["format"] == "cxf"
    out = _run(capsys, "library", "import", str(tmp_path / "lib.cxf"), "--out", str(tmp_path / "back.csv"))
    assert read_library_csv(tmp_path / "back.csv").codes.tolist() == small_library.codes.tolist()
    out = _run(
        capsys,
        "library",
        "browse",
        "--library",
        str(src),
        "--filter",
        "type=metallic,pearl",
        "--filter",
        "flop=5:;group=red",
        "--limit",
        "3",
    )
    assert out["shown"] <= 3 and out["matched"] >= out["shown"]
    for p in out["paints"]:
        assert p["type"] in ("metallic", "pearl") and p["indices"]["flop"] >= 5 and p["group"][2] == "red"
    out = _run(capsys, "library", "export", "demo", "--out", str(tmp_path / "demo.csv"))
    assert out["paints"] == 6000 and out["synthetic"]


def test_formulate_and_closed_loop(capsys) -> None:
    lib = demo_library()
    lab = lib.angle_columns()[4321] + 0.8
    text = ";".join(",".join(f"{v:.4f}" for v in row) for row in lab)
    out = _run(capsys, "formulate", text, "--closed-loop", "--batch", "250")
    assert out["formulable"] and out["mean_de"] <= 1.0 and len(out["de_per_angle"]) == 3
    assert out["synthetic_colorants"] is True
    batch = out["batch"]  # grams for a 250 g batch: fraction × 250, binder the rest
    assert batch["total_g"] == 250.0
    for name, frac in out["recipe"].items():
        assert batch["colorants_g"][name] == pytest.approx(250.0 * frac)
    assert batch["binder_g"] == pytest.approx(250.0 * (1.0 - sum(out["recipe"].values())))
    assert out["closed_loop"]["status"] == "converged" and out["closed_loop"]["corrections"] <= 3


def test_formulate_with_a_type_starts_from_that_types_nearest_paints(tmp_path) -> None:
    lib = demo_library()
    lab = np.array([[60, 30, 10], [40, 28, 12], [20, 20, 10.0]])
    run = run_station(tmp_path, "formulate", LAB, "--type", "pearl", "--json")
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    pearls = np.flatnonzero(lib.types == "pearl")
    rows, sums, _ = brute_force(lib.angle_columns()[pearls], lab, 3, "cie2000")
    assert [m["code"] for m in out["matches"]] == lib.codes[pearls[rows]].tolist()
    assert {m["type"] for m in out["matches"]} == {"pearl"} and out["types"] == ["pearl"]
    np.testing.assert_allclose([m["sum_de"] for m in out["matches"]], sums, atol=1e-9)
    bad = run_station(tmp_path, "formulate", LAB, "--type", "chrome")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--type" in bad.stderr


@pytest.mark.parametrize("fmt", ["xml", "cxf"])
def test_export_design_and_match(capsys, tmp_path, fmt: str) -> None:
    path = tmp_path / f"out.{fmt}"
    out = _run(capsys, "export", LAB, "--format", fmt, "--out", str(path), "--five-angles")
    specs = read_color_xml(path) if fmt == "xml" else read_cxf_specs(path)
    assert [s.role for s in specs] == ["design", "match"]
    assert specs[1].code == out["match"] and specs[1].synthetic
    assert [s.angles_deg for s in specs[0].sets][:2] == [(15.0, 45.0, 110.0), (25.0, 45.0, 75.0)]


@pytest.mark.parametrize(
    "argv",
    [
        ["snap", "--lab", "60,30,10;40,28,12"],
        ["snap", "--lab", "60,30,10;40,28,12;20,20,x"],
        ["snap", "--lab", LAB, "--k", "0"],
        ["snap", "--lab", LAB, "--library", "nope.txt"],
        ["library", "browse", "--filter", "flop=abc"],
        ["library", "browse", "--filter", "colour=red"],
        ["formulate", LAB, "--batch", "-3"],
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, argv: list[str]) -> None:
    assert main([*argv, "--json"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1


def test_formulate_shows_the_recipes_side_by_side(capsys) -> None:
    silver = "90,2,-5;50,1,-3;30,0.5,-1"
    out = _run(
        capsys, "formulate", silver, "--max-colorants", "4", "--recipes", "2", "--scale-resolution", "0.5"
    )
    assert 1 <= len(out["recipes"]) <= 2
    for r in out["recipes"]:
        assert r["colorants"] <= 4 and r["batch_g"] == 1000.0
        assert all(abs(g / 0.5 - round(g / 0.5)) < 1e-6 for g in r["grams"].values())
        assert {"mean_de", "mean_de_unrounded", "metamerism_index", "cost_per_kg"} <= set(r)
    assert out["recipe"] == out["recipes"][0]["recipe"]
    assert (
        main(["formulate", silver, "--max-colorants", "4", "--recipes", "2", "--scale-resolution", "0.5"])
        == 0
    )
    text = capsys.readouterr().out
    assert "dE00 rounded" in text and "dE00 unrounded" in text and "MI F11" in text and "#1" in text
    first = out["recipes"][0]
    for name, grams in first["grams"].items():  # the table shows the JSON's grams
        row = next(line for line in text.splitlines() if line.startswith(f"{name} (g)"))
        assert f"{grams:.1f}" in row


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (("--max-colorants", "0"), "--max-colorants"),
        (("--max-colorants", "11"), "--max-colorants"),
        (("--scale-resolution", "0"), "--scale-resolution"),
        (("--recipes", "0"), "--recipes"),
    ],
)
def test_formulate_refuses_out_of_range_selection_options(capsys, argv: tuple[str, ...], named: str) -> None:
    assert main(["formulate", "90,2,-5;50,1,-3;30,0.5,-1", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and named in err
