"""CxF3 layouts as vendors and colour-cxf write them: several BRDFAngles in one ColorSpecification,
single-angle 45/0 specifications, and colour-cxf's own test resources (tests/ingest/data/README.md)."""

from __future__ import annotations

from pathlib import Path

import colour_cxf
import numpy as np
import pytest
import xmlschema
from colour_cxf import cxf3

from station.ingest.formats import CxfImportError, read_measurement_file
from station.model.domain import geometry_name

DATA = Path(__file__).parent / "data"
SIX = DATA / "six_angles_one_spec.cxf"


@pytest.fixture(scope="module")
def schema(shared_dir: Path) -> xmlschema.XMLSchema:
    """X-Rite's published CxF3 core schema (3.0.018), read from ../shared/reference (never committed)."""
    return xmlschema.XMLSchema(str(shared_dir / "reference" / "CxF3_Core.xsd"))


def _reference(path: Path) -> tuple[cxf3.CxF, dict[str, cxf3.ColorSpecification]]:
    doc = colour_cxf.read_cxf(path.read_bytes())
    specs = {s.id: s for s in doc.resources.color_specification_collection.color_specification}
    return doc, specs


@pytest.mark.parametrize(
    "name", ["six_angles_one_spec.cxf", "colour_cxf/sample.cxf", "colour_cxf/geometry_edge_cases.cxf"]
)
def test_fixtures_are_schema_valid(schema: xmlschema.XMLSchema, name: str) -> None:
    schema.validate(str(DATA / name))


def test_six_brdf_angles_in_one_specification_read_in_order_and_by_notation() -> None:
    doc, specs = _reference(SIX)
    angles = specs["MA6"].measurement_spec.geometry_choice.choice.brdfangle
    expected_order = [geometry_name(a.illumination_angle, a.aspecular) for a in angles]
    by_notation = dict(zip((a.notation for a in angles), expected_order, strict=True))
    silver, red = read_measurement_file(SIX).measurements
    objects = doc.resources.object_collection.object_value
    # object 1: unnamed values take the BRDFAngles in order (colour-cxf's parse is the reference)
    labs = [v for v in objects[0].color_values.choice if isinstance(v, cxf3.ColorCielab)]
    spectra = [v for v in objects[0].color_values.choice if isinstance(v, cxf3.ReflectanceSpectrum)]
    assert (
        list(silver.geometries)
        == expected_order
        == ["45as-15", "45as15", "45as25", "45as45", "45as75", "45as110"]
    )
    assert silver.lab is not None and silver.spectra is not None
    assert np.array_equal(silver.lab, [(v.l, v.a, v.b) for v in labs])
    assert np.array_equal(silver.spectra, [v.value for v in spectra])
    assert silver.wavelengths_nm == tuple(float(w) for w in range(400, 701, 10))
    assert silver.lab[0] == (118.42, -1.05, -3.87)  # the file's first ColorCIELab, at 45as-15
    # object 2: values named by Notation, in shuffled order
    named = [v for v in objects[1].color_values.choice if isinstance(v, cxf3.ColorCielab)]
    assert red.lab is not None
    got = dict(zip(red.geometries, red.lab, strict=True))
    assert got == {by_notation[v.name]: (v.l, v.a, v.b) for v in named}
    assert list(red.geometries) == expected_order  # named values in shuffled order: stored in BRDFAngle order
    assert got["45as110"] == (21.47, 21.88, 10.52) and red.spectra is None
    assert (silver.illuminant, silver.observer) == ("D65", "CIE 1964 10 Degree Standard Observer")
    assert (silver.instrument.model, silver.instrument.serial, silver.instrument.manufacturer) == (
        "MA-T6",
        "10442",
        "X-Rite",
    )


def test_colour_cxf_sample_reads_as_45_0_single_geometry() -> None:
    path = DATA / "colour_cxf" / "sample.cxf"
    doc, specs = _reference(path)
    single = specs["CS1"].measurement_spec.geometry_choice.choice
    assert (single.illumination_angle, single.measurement_angle) == (45.0, 0.0)
    imported = read_measurement_file(path).measurements
    objects = doc.resources.object_collection.object_value
    assert len(imported) == len(objects) == 144
    for m, obj in zip(imported, objects, strict=True):
        lab = next(v for v in obj.color_values.choice if isinstance(v, cxf3.ColorCielab))
        sp = next(v for v in obj.color_values.choice if isinstance(v, cxf3.ReflectanceSpectrum))
        assert m.geometries == ("45as45",)  # 45° illumination viewed at the normal: 45° from specular
        assert m.sample == obj.name
        assert m.lab == ((lab.l, lab.a, lab.b),)
        assert m.spectra == (tuple(sp.value),)
        assert m.wavelengths_nm == tuple(380.0 + 10 * k for k in range(len(sp.value)))
        assert (m.illuminant, m.observer) == ("D50", "CIE 1931 2 Degree Standard Observer")
    assert imported[0].lab == ((17.64167, 1.076669, 0.3338588),)  # the file's first object, as printed


def test_colour_cxf_unicode_names_survive() -> None:
    path = DATA / "colour_cxf" / "unicode_special_characters.cxf"
    doc, _ = _reference(path)
    imported = read_measurement_file(path).measurements
    names = [o.name for o in doc.resources.object_collection.object_value]
    assert [m.sample for m in imported] == [n.strip() for n in names]
    assert all(m.geometries == ("45as45",) for m in imported)


def test_one_value_for_several_angles_is_refused_naming_the_field() -> None:
    with pytest.raises(CxfImportError) as info:
        read_measurement_file(DATA / "colour_cxf" / "geometry_edge_cases.cxf")
    assert info.value.field == "ColorSpecification"
    assert "one ColorCIELab per BRDFAngle" in str(info.value) and "(3," in str(info.value)


def _edited(tmp_path: Path, old: str, new: str, count: int = 1) -> Path:
    text = SIX.read_text(encoding="utf-8")
    assert old in text
    out = tmp_path / "edited.cxf"
    out.write_text(text.replace(old, new, count), encoding="utf-8")
    return out


def test_out_of_plane_azimuth_is_refused(tmp_path: Path) -> None:
    f = _edited(tmp_path, "<Aspecular>25</Aspecular>", "<Aspecular>25</Aspecular><Azimuth>30</Azimuth>")
    with pytest.raises(CxfImportError) as info:
        read_measurement_file(f)
    assert info.value.field == "Azimuth" and "30" in str(info.value)


def test_a_missing_unnamed_value_is_refused(tmp_path: Path) -> None:
    first_lab = SIX.read_text(encoding="utf-8").split("\n")
    line = next(x for x in first_lab if "<ColorCIELab" in x)
    with pytest.raises(CxfImportError) as info:
        read_measurement_file(_edited(tmp_path, line + "\n", ""))
    assert info.value.field == "ColorSpecification" and "got 5" in str(info.value)


def test_zero_forty_five_is_refused_naming_the_angle(tmp_path: Path) -> None:
    text = (DATA / "colour_cxf" / "sample.cxf").read_text(encoding="utf-8")
    old = "<cc:IlluminationAngle>45.0</cc:IlluminationAngle>"
    assert old in text
    f = tmp_path / "zero45.cxf"
    text = text.replace(old, "<cc:IlluminationAngle>0.0</cc:IlluminationAngle>")
    text = text.replace("<cc:MeasurementAngle>0.0<", "<cc:MeasurementAngle>45.0<")
    f.write_text(text, encoding="utf-8")
    with pytest.raises(CxfImportError) as info:
        read_measurement_file(f)
    assert info.value.field == "IlluminationAngle" and "0/45" in str(info.value)
