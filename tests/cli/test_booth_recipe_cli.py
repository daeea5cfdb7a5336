"""``station booth`` with a recipe on one side: formulated in a user's folder, predicted by the colorant model."""

from __future__ import annotations

import json
from pathlib import Path

import colour
import numpy as np
import pytest

from station.formulate.colorants import default_database, predict_reflectance
from station.ingest.errors import ImportFileError
from station.ingest.formats import write_measurement_file
from station.ingest.formats.measurement import Instrument, build_measurement
from station.model.colorimetry import OBSERVER_10
from station.model.spectra import WAVELENGTHS, reflectance_from_lab
from tests.user_cli import run_station

GEOMETRIES = ("45as15", "45as45", "45as110")
ANGLES = (15.0, 45.0, 110.0)
#: A red metallic per geometry, Lab D65 / 10°: the measured standard and the design formulated.
RED = [[48.0, 42.0, 22.0], [30.0, 34.0, 16.0], [18.0, 24.0, 10.0]]


def _lab(refl: np.ndarray, illuminant: str) -> np.ndarray:
    """colour-science's CIELAB under *illuminant* (its own white), CIE 1964 10°, ASTM E308."""
    cmfs = colour.MSDS_CMFS[OBSERVER_10]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11"}.get(illuminant, illuminant)]
    rows = []
    for r in refl:
        sd = colour.SpectralDistribution(dict(zip(WAVELENGTHS, r, strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308") / 100
        white = colour.sd_to_XYZ(colour.sd_ones(sd.shape), cmfs, ill, method="ASTM E308") / 100
        rows.append(colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white)))
    return np.asarray(rows)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with a measured standard (CxF3, spectra) and the recipe ``station formulate --json`` wrote."""
    tmp = tmp_path_factory.mktemp("booth_recipe")
    spectra = reflectance_from_lab(RED).round(6)

    def err(f: str, a: str, g: object) -> ImportFileError:
        return ImportFileError("test", "measured", f, a, g)

    m = build_measurement(
        sample="measured",
        rows=[(g, err) for g in GEOMETRIES],
        lab=None,
        wavelengths_nm=WAVELENGTHS.tolist(),
        spectra=spectra.tolist(),
        instrument=Instrument(model="MA-T12", serial="T1"),
        illuminant="D65",
        observer=OBSERVER_10,
        measured_at=None,
        err=err,
    )
    write_measurement_file([m], tmp / "measured.cxf")
    out = run_station(tmp, "formulate", ";".join(",".join(str(v) for v in row) for row in RED), "--json")
    assert out.returncode == 0, out.stderr
    (tmp / "recipe.json").write_text(out.stdout)
    return tmp


def test_booth_measured_standard_against_a_formulated_recipe(folder: Path) -> None:
    recipe = json.loads((folder / "recipe.json").read_text())["recipe"]
    db = default_database()
    predicted = predict_reflectance(db.vector(recipe), ANGLES, db)  # the colorant model, independently
    out = run_station(
        folder, "booth", "--standard", "measured.cxf", "--sample", "recipe.json", "--illuminants", "D65,A,F11",
        "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    by_name = {i["name"]: i for i in doc["illuminants"]}
    assert list(by_name) == ["D65", "A", "F11"]
    for name in ("D65", "A", "F11"):
        rows = by_name[name]["per_geometry"]
        assert [g["geometry"] for g in rows] == list(GEOMETRIES)
        expected = _lab(predicted, name)
        got = np.array([g["sample_lab"] for g in rows])
        np.testing.assert_allclose(got, expected, atol=1e-6, rtol=0)
    # the recipe was formulated for the standard's D65 Lab: small ΔE00 in daylight, not zero
    d65 = [g["dE00"] for g in by_name["D65"]["per_geometry"]]
    assert max(d65) < 3.0


def test_booth_two_recipes_at_the_standard_angle_set(folder: Path) -> None:
    out = run_station(folder, "booth", "--standard", "recipe.json", "--sample", "recipe.json", "--json")
    assert out.returncode == 0, out.stderr
    for ill in json.loads(out.stdout)["illuminants"]:
        assert [g["geometry"] for g in ill["per_geometry"]] == list(GEOMETRIES)
        assert all(g["dE00"] == 0.0 for g in ill["per_geometry"])


def test_booth_refuses_a_file_neither_measurement_nor_recipe(folder: Path) -> None:
    (folder / "notes.json").write_text('{"colour": "red"}')
    (folder / "bad_recipe.json").write_text('{"recipe": {"unobtainium": 0.1}}')
    for name in ("notes.json", "bad_recipe.json"):
        out = run_station(folder, "booth", "--standard", "measured.cxf", "--sample", name, "--json")
        assert out.returncode == 2, out.stderr
        assert name in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
        assert out.stdout == ""
