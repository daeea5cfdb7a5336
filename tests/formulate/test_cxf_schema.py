"""Every CxF the product writes validates against X-Rite's published CxF3 core schema (3.0.018,
read from ../shared/reference, never committed) and reads back equal: measurements,
recipes with predicted spectra, whole libraries."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pytest
import xmlschema

from station.formulate.cxf import (
    library_extras,
    library_to_cxf,
    read_cxf_objects,
    read_cxf_specs,
    read_library_cxf,
    specs_to_cxf,
)
from station.formulate.export import BINDER_NAME, export_specs, recipe_export
from station.formulate.formulation import formulate
from station.formulate.library import Library
from station.ingest.errors import ImportFileError
from station.ingest.formats import read_measurement_file, write_measurement_file
from station.ingest.formats.measurement import ImportedMeasurement, Instrument, VendorValue, build_measurement
from station.model import FaceFlopTravelGloss
from station.model.domain import ANGLES_3

WHEN = dt.datetime(2026, 3, 4, 5, 6, 7, tzinfo=dt.UTC)
DESIGN = FaceFlopTravelGloss((62.5, 38.25, 20.125), (20.0, 30.5, 12.0), 80.0, 85.0, name="Red metallic")


@pytest.fixture(scope="module")
def schema(shared_dir: Path) -> xmlschema.XMLSchema:
    """X-Rite's published CxF3 core schema (3.0.018), read from ../shared/reference (never committed)."""
    return xmlschema.XMLSchema(str(shared_dir / "reference" / "CxF3_Core.xsd"))


def _errors(schema: xmlschema.XMLSchema, data: bytes) -> list[str]:
    return [f"{e.path}: {e.reason}" for e in schema.iter_errors(data.decode("utf-8"))]


def test_the_schema_refuses_what_the_old_exports_wrote(schema: xmlschema.XMLSchema) -> None:
    """The check can fail: a TagCollection without Name and a ColorRecipe without CreationDate are refused."""
    spec, extras = _recipe()
    good = specs_to_cxf([spec], extras=[extras], created=WHEN).decode()
    assert schema.is_valid(good)
    assert not schema.is_valid(good.replace('<cc:TagCollection Name="cacad">', "<cc:TagCollection>"))
    stamp = "<cc:CreationDate>2026-03-04T05:06:07Z</cc:CreationDate>"
    recipe_at = good.index("<cc:ColorRecipe")
    assert not schema.is_valid(good[:recipe_at] + good[recipe_at:].replace(stamp, "", 1))


def _recipe():
    result = formulate(DESIGN.lab_at(np.asarray(ANGLES_3)), tuple(ANGLES_3), time_budget_s=0.3)
    return recipe_export(result, name="Red metallic match", batch_g=250.0)


def test_recipe_export_is_schema_valid_and_reads_back(schema: xmlschema.XMLSchema) -> None:
    spec, extras = _recipe()
    design_specs, _ = export_specs(DESIGN)
    data = specs_to_cxf([*design_specs, spec], extras=[None, extras], created=WHEN)
    assert _errors(schema, data) == []
    back = read_cxf_specs(data)
    assert [s.name for s in back] == ["Red metallic", "Red metallic match"]
    _, back_extras = read_cxf_objects(data)
    got = back_extras[1]
    assert got is not None and got.binder == BINDER_NAME and got.recipe_units == "g"
    assert [n for n, _ in got.recipe] == [n for n, _ in extras.recipe]
    assert np.allclose([v for _, v in got.recipe], [v for _, v in extras.recipe], atol=0.5e-6)
    assert [a for a, _ in got.spectra] == sorted(a for a, _ in extras.spectra)
    for (a, r), (b, s) in zip(got.spectra, sorted(extras.spectra), strict=True):
        assert a == b and np.max(np.abs(np.asarray(r) - np.asarray(s))) <= 0.5e-6 + 1e-12
    assert specs_to_cxf(back, extras=back_extras, created=WHEN) == data


def test_library_export_is_schema_valid_and_reads_back(
    schema: xmlschema.XMLSchema, small_library: Library
) -> None:
    sub = small_library.subset(np.arange(len(small_library)) % 12 == 0)
    data = library_to_cxf(sub, spectra=True, created=WHEN)
    assert _errors(schema, data) == []
    lib = read_library_cxf(data)
    assert lib.codes.tolist() == sub.codes.tolist()
    assert np.max(np.abs(lib.lab - sub.lab)) <= 0.5e-4 + 1e-12
    assert lib.recipes is not None and sub.recipes is not None
    assert np.max(np.abs(lib.recipes - sub.recipes)) <= 0.5e-6 + 1e-12
    assert len(library_extras(sub)) == len(sub)


def _measurement() -> ImportedMeasurement:
    def err(fld: str, accepted: str, got: object) -> ImportFileError:
        return ImportFileError("test", "m", fld, accepted, got)

    geos = ["15as-15", "15as15", "45as-15", "45as15", "45as45", "45as110"]
    rng = np.random.default_rng(5)
    lab = [
        (90.0 - 9 * k, round(1.5 - 0.2 * k, 4), -4.0 + 0.5 * k) for k in range(len(geos))
    ]  # 4 decimals: as written
    spectra = rng.uniform(0.05, 0.9, size=(len(geos), 31)).round(6).tolist()
    return build_measurement(
        sample="Panel 7 / door",
        rows=[(g, err) for g in geos],
        lab=lab,
        wavelengths_nm=[400.0 + 10 * k for k in range(31)],
        spectra=spectra,
        instrument=Instrument("MA-T12", "10442", "X-Rite"),
        illuminant="D50",
        observer="CIE 1931 2 Degree Standard Observer",
        measured_at=WHEN,
        texture=[
            VendorValue("X-Rite", "sparkle_intensity", 3.25, "15as-15"),
            VendorValue("X-Rite", "graininess", 4.5),
        ],
        err=err,
    )


def test_measurement_export_is_schema_valid_and_reimports_equal(
    schema: xmlschema.XMLSchema, tmp_path: Path
) -> None:
    m = _measurement()
    path = tmp_path / "panel.cxf"
    write_measurement_file([m], path)
    assert _errors(schema, path.read_bytes()) == []
    (back,) = read_measurement_file(path).measurements
    assert back == m


def test_an_undated_measurement_stays_undated(schema: xmlschema.XMLSchema, tmp_path: Path) -> None:
    """The schema requires a CreationDate; the placeholder written for it never reads back as a date."""
    import dataclasses

    m = dataclasses.replace(_measurement(), measured_at=None)
    path = tmp_path / "undated.cxf"
    write_measurement_file([m], path)
    assert _errors(schema, path.read_bytes()) == []
    (back,) = read_measurement_file(path).measurements
    assert back.measured_at is None and back == m
