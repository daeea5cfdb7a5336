"""Library files keep every field: CSV and CxF3 round trips (synthetic flag, recipes, spectra, creation
date), the thesis XML read as a library, ColorSnap's type filter against brute force, and the CLI run
as a user runs it (a subprocess in a folder that is not the repository)."""

from __future__ import annotations

import datetime as dt
import io
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from station.formulate.color_xml import colors_to_xml, spec_from_lab
from station.formulate.colorants import default_database, predict_reflectance
from station.formulate.cxf import (
    ObjectExtras,
    library_to_cxf,
    read_cxf_objects,
    read_library_cxf,
    records_to_cxf,
)
from station.formulate.errors import FormulateInputError, XMLFormatError
from station.formulate.library import Library
from station.formulate.library_csv import read_library_csv, write_library_csv
from station.formulate.library_io import read_library_file
from station.formulate.snap import color_snap
from station.model.spectra import WAVELENGTHS, reflectance_to_lab
from tests.user_cli import run_station

WHEN = dt.datetime(2026, 5, 6, 7, 8, 9, tzinfo=dt.UTC)


def _csv(lib: Library) -> str:
    buf = io.StringIO()
    write_library_csv(lib, buf)
    return buf.getvalue()


def test_csv_round_trip_keeps_synthetic_and_recipes(small_library: Library) -> None:
    assert small_library.synthetic and small_library.recipes is not None
    text = _csv(small_library)
    assert text.splitlines()[0].endswith(",synthetic,recipe")
    back = read_library_csv(io.StringIO(text))
    assert back.synthetic is True
    assert back.colorant_names == small_library.colorant_names
    # recipes written to 6 decimals: the round trip is within half a unit of the last one
    assert np.max(np.abs(back.recipes - small_library.recipes)) <= 0.5e-6 + 1e-12
    assert _csv(back) == text  # export(import(export(x))) is byte-identical


def test_csv_of_a_measured_library_stays_measured(small_library: Library) -> None:
    measured = Library(
        "lab",
        small_library.codes,
        small_library.types,
        small_library.gloss_gu,
        small_library.angles_deg,
        small_library.lab,
    )
    text = _csv(measured)
    assert "synthetic" not in text.splitlines()[0] and "recipe" not in text.splitlines()[0]
    assert read_library_csv(io.StringIO(text)).synthetic is False


@pytest.mark.parametrize(
    ("cell", "column"),
    [
        ("maybe", "synthetic"),
        ("white_tio2", "recipe"),
        ("white_tio2=1.5", "recipe"),
        ("a=0.1;a=0.2", "recipe"),
    ],
)
def test_csv_bad_extra_cells_name_row_and_column(cell: str, column: str) -> None:
    head = "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110,synthetic,recipe\n"
    row = ["P-1", "solid", "90", "50", "0", "0", "50", "0", "0", "50", "0", "0", "true", "a=0.1"]
    row[12 if column == "synthetic" else 13] = cell
    with pytest.raises(FormulateInputError, match=f"row 2.*{column}"):
        read_library_csv(io.StringIO(head + ",".join(row) + "\n"))


def test_cxf_library_carries_recipes_and_spectra_that_reproduce_its_lab(small_library: Library) -> None:
    import colour_cxf

    lib = small_library.subset(np.arange(0, len(small_library), 12))
    data = library_to_cxf(lib, spectra=True, created=WHEN)
    back = read_library_cxf(data)
    assert back.synthetic and back.colorant_names == lib.colorant_names
    assert back.recipes is not None and lib.recipes is not None and lib.colorant_names is not None
    assert np.max(np.abs(back.recipes - lib.recipes)) <= 0.5e-6 + 1e-12
    _, extras = read_cxf_objects(data)
    assert all(x is not None and x.recipe_units == "fraction" for x in extras)
    # independent check: the written spectra, integrated by colour-science (station.model.spectra), give
    # the library's Lab at every angle to the file's precision
    for i, extra in enumerate(extras):
        assert extra is not None
        angles = [a for a, _ in extra.spectra]
        assert sorted(angles) == sorted(lib.angles_deg)
        for a, refl in extra.spectra:
            lab = reflectance_to_lab(np.asarray(refl))
            assert np.max(np.abs(lab - lib.lab[i, lib.angles_deg.index(a)])) < 2e-3
    doc = colour_cxf.read_cxf(data)  # the reference CxF3 binding reads the recipe and the spectra
    obj = doc.resources.object_collection.object_value[0]
    recipe = obj.device_color_values.choice[0]
    names = {c.name: c.value for c in recipe.colorant}
    want = {n: v for n, v in zip(lib.colorant_names, lib.recipes[0], strict=True) if round(v, 6) > 0}
    assert names.keys() == want.keys()
    assert all(abs(names[n] - want[n]) <= 0.5e-6 + 1e-12 for n in want)
    spectra = [c for c in obj.color_values.choice if type(c).__name__ == "ReflectanceSpectrum"]
    assert len(spectra) == len(lib.angles_deg) and len(spectra[0].value) == WAVELENGTHS.size


def test_cxf_creation_date_is_the_export_time(small_library: Library) -> None:
    before = dt.datetime.now(dt.UTC).replace(microsecond=0)
    text = library_to_cxf(small_library.subset(np.arange(2))).decode()
    after = dt.datetime.now(dt.UTC)
    stamp = text.split("<cc:CreationDate>")[1].split("<")[0]
    when = dt.datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=dt.UTC)
    assert before <= when <= after
    assert "2009-01-01" not in text


def test_cxf_extras_refuse_bad_spectra_and_recipes() -> None:
    with pytest.raises(XMLFormatError, match="31 finite values"):
        ObjectExtras(spectra=((15.0, (0.5,) * 30),))
    with pytest.raises(XMLFormatError, match="amount"):
        ObjectExtras(recipe=(("white", -1.0),))
    good = records_to_cxf(
        [("P", {15.0: (50.0, 0.0, 0.0)}, {})],
        "x",
        [
            ObjectExtras(
                spectra=((15.0, (0.5,) * 31),), recipe=(("binder", 60.0), ("white", 40.0)), binder="binder"
            )
        ],
        WHEN,
    )
    assert b'isBase="true"' in good and b'Units="g"' in good
    truncated = good.replace(b" 0.500000</cc:ReflectanceSpectrum>", b"</cc:ReflectanceSpectrum>")
    with pytest.raises(XMLFormatError, match="31 values"):
        read_cxf_objects(truncated)


def _thesis_xml(path: Path) -> None:
    specs = [
        spec_from_lab(
            "Red metallic",
            {15: (62, 38, 20), 45: (40, 30, 16), 110: (20, 20, 12), 25: (55, 35, 19), 75: (28, 24, 14)},
            85,
            role="design",
            code="R-1",
        ),
        spec_from_lab(
            "Grey", {a: (50.0, 0.0, 0.0) for a in (15, 25, 45, 75, 110)}, 60, role="measured", code="G-1"
        ),
        spec_from_lab(
            "Pearl",
            {a: (70.0 - a / 10, 2.0, -5.0) for a in (15, 25, 45, 75, 110)},
            90,
            role="match",
            paint_type="pearl",
            code="P-1",
            synthetic=True,
        ),
    ]
    path.write_bytes(colors_to_xml(specs))


def test_thesis_xml_reads_as_a_library(tmp_path: Path) -> None:
    _thesis_xml(tmp_path / "colours.xml")
    lib = read_library_file(tmp_path / "colours.xml")
    assert lib.codes.tolist() == ["R-1", "G-1", "P-1"]
    assert lib.types.tolist() == ["metallic", "solid", "pearl"]  # typed by Lab spread, then by the file
    assert lib.angle_columns()[0].tolist() == [[62, 38, 20], [40, 30, 16], [20, 20, 12]]
    assert lib.synthetic is False  # only one colour says synthetic


def test_unknown_xml_is_refused_naming_the_root(tmp_path: Path) -> None:
    (tmp_path / "x.xml").write_text('<?xml version="1.0"?><palette xmlns="urn:other"/>')
    with pytest.raises(XMLFormatError, match="root"):
        read_library_file(tmp_path / "x.xml")


@pytest.mark.parametrize("types", [("metallic",), ("solid", "pearl")])
def test_type_filter_equals_brute_force_over_those_paints(
    small_library: Library, types: tuple[str, ...]
) -> None:
    target = np.array([[55.0, 10.0, -20.0], [40.0, 8.0, -16.0], [25.0, 5.0, -10.0]])
    got = color_snap(small_library, target, k=5, method="cie76", types=types)
    rows = np.flatnonzero(np.isin(small_library.types, types))
    sums = np.linalg.norm(small_library.angle_columns()[rows] - target, axis=-1).sum(axis=1)
    want = rows[np.lexsort((rows, sums))[:5]]
    assert [m.index for m in got.matches] == want.tolist()
    assert all(small_library.types[m.index] in types for m in got.matches)
    assert [m.code for m in got.matches] == small_library.codes[want].tolist()


def test_type_filter_refuses_a_type_the_library_lacks(small_library: Library) -> None:
    solids = small_library.subset(small_library.types == "solid")
    with pytest.raises(FormulateInputError, match=r"type.*a type the library holds: solid"):
        color_snap(solids, np.full((3, 3), 50.0), types=["metallic"])


def _station(cwd: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *argv, timeout=120)


def test_cli_from_a_user_folder(tmp_path: Path) -> None:
    _thesis_xml(tmp_path / "colours.xml")
    run = _station(tmp_path, "library", "import", "colours.xml", "--out", "colours.csv", "--json")
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["paints"] == 3
    assert read_library_csv(tmp_path / "colours.csv").types.tolist() == ["metallic", "solid", "pearl"]
    run = _station(
        tmp_path,
        "snap",
        "--library",
        "demo",
        "--lab",
        "90,0,0;60,0,0;30,0,0",
        "--type",
        "metallic",
        "--k",
        "3",
        "--json",
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["types"] == ["metallic"] and {m["type"] for m in out["matches"]} == {"metallic"}
    run = _station(
        tmp_path,
        "export",
        "60,30,10;40,28,12;20,20,10",
        "--format",
        "cxf",
        "--out",
        "d.cxf",
        "--recipe",
        "--json",
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    recipe = out["recipe"]
    _, extras = read_cxf_objects(tmp_path / "d.cxf")
    assert extras[:2] == [None, None] and extras[2] is not None
    # grams for the default 1000 g batch: colorant i = 1000 c_i, binder = 1000 (1 − Σ c_i)
    grams = {k: 1000.0 * v for k, v in recipe.items()} | {"binder": 1000.0 * (1.0 - sum(recipe.values()))}
    assert extras[2].recipe_units == "g" and extras[2].binder == "binder"
    assert dict(extras[2].recipe) == pytest.approx(grams, abs=0.5e-6)
    assert out["batch_g"] == pytest.approx(grams, abs=0.5e-6)
    db = default_database()
    refl = predict_reflectance(db.vector(recipe), (15.0,), db)[0]
    # 6 decimals in the file, and the recipe omits fractions under 1e-6 (FormulationResult.recipe)
    assert np.max(np.abs(np.asarray(dict(extras[2].spectra)[15.0]) - refl)) <= 1e-5
    (tmp_path / "bad.xml").write_text("<nope/>")
    run = _station(tmp_path, "library", "import", "bad.xml")
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1 and "root" in run.stderr
