"""Thesis XML (§5.3.1) and CxF3: schema conformance, lossless round trips, hostile and malformed files."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
import xmlschema

from station.formulate.color_xml import (
    SCHEMA_PATH,
    colors_to_xml,
    read_color_xml,
    spec_from_design,
    spec_from_lab,
)
from station.formulate.cxf import (
    library_to_cxf,
    read_cxf_specs,
    read_library_cxf,
    specs_to_cxf,
)
from station.formulate.errors import HostileXMLError, XMLFormatError
from station.formulate.library import Library
from station.model import FaceFlopTravelGloss

WHEN = dt.datetime(2026, 3, 4, 5, 6, 7, tzinfo=dt.UTC)
DESIGN = FaceFlopTravelGloss((62.5, 38.25, 20.125), (20.0, 30.5, 12.0), 80.0, 85.0, name="Red metallic")


def _specs(small_library: Library):
    design = spec_from_design(DESIGN, five_angles=True)
    i = 130  # a metallic of the small library
    lab = {a: tuple(small_library.lab[i, j]) for j, a in enumerate(small_library.angles_deg)}
    match = spec_from_lab(
        str(small_library.codes[i]),
        lab,
        float(small_library.gloss_gu[i]),
        paint_type=str(small_library.types[i]),
        code=str(small_library.codes[i]),
        synthetic=True,
    )
    return [design, match]


def test_design_exports_both_angle_sets_at_d65_45(small_library: Library) -> None:
    data = colors_to_xml(_specs(small_library))
    specs = read_color_xml(data)
    design = specs[0]
    assert [s.angles_deg for s in design.sets] == [
        (15.0, 45.0, 110.0),
        (25.0, 45.0, 75.0),
        (15.0, 25.0, 45.0, 75.0, 110.0),
    ]
    assert np.allclose(design.lab((15.0, 45.0, 110.0)), DESIGN.lab_at([15, 45, 110]), atol=0.5e-4)
    assert np.allclose(design.lab((25.0, 45.0, 75.0)), DESIGN.lab_at([25, 45, 75]), atol=0.5e-4)
    assert design.gloss_gu == 85.0
    assert b'illuminant="D65"' in data and b'illuminationAngleDeg="45"' in data
    assert specs[1].role == "match" and specs[1].synthetic and specs[1].code == small_library.codes[130]


def test_xml_validates_against_the_xsd_in_the_repo(small_library: Library) -> None:
    schema = xmlschema.XMLSchema(str(SCHEMA_PATH))
    schema.validate(colors_to_xml(_specs(small_library)).decode())
    bad = colors_to_xml(_specs(small_library)).decode().replace('role="match"', 'role="guess"')
    assert not schema.is_valid(bad)


def test_xml_round_trip_is_lossless_and_stable(small_library: Library) -> None:
    first = colors_to_xml(_specs(small_library))
    again = colors_to_xml(read_color_xml(first))
    assert again == first


def test_cxf_design_and_match_round_trip(small_library: Library) -> None:
    specs = _specs(small_library)
    data = specs_to_cxf(specs, created=WHEN)
    back = read_cxf_specs(data)
    assert [s.name for s in back] == [s.name for s in specs]
    for a, b in zip(specs, back, strict=True):
        assert [s.angles_deg for s in a.sets] == [s.angles_deg for s in b.sets]
        for sa, sb in zip(a.sets, b.sets, strict=True):
            assert np.max(np.abs(np.asarray(sa.lab) - np.asarray(sb.lab))) <= 0.5e-4 + 1e-12
        assert (b.role, b.code, b.paint_type, b.synthetic) == (a.role, a.code, a.paint_type, a.synthetic)
    assert specs_to_cxf(back, created=WHEN) == data


def test_cxf_library_round_trip_and_colour_cxf_reads_it(small_library: Library) -> None:
    import colour_cxf

    data = library_to_cxf(small_library, created=WHEN)
    lib = read_library_cxf(data)
    assert lib.codes.tolist() == small_library.codes.tolist()
    assert lib.types.tolist() == small_library.types.tolist()
    assert lib.synthetic
    for a in small_library.angles_deg:
        assert np.max(np.abs(lib.angle_columns((a,)) - small_library.angle_columns((a,)))) <= 0.5e-4 + 1e-12
    assert library_to_cxf(lib, created=WHEN) == data
    cxf = colour_cxf.read_cxf(data)  # the reference CxF3 binding parses what we write
    objects = cxf.resources.object_collection.object_value
    assert len(objects) == len(small_library)
    specs = cxf.resources.color_specification_collection.color_specification
    assert {s.measurement_spec.geometry_choice.choice.brdfangle[0].aspecular for s in specs} == set(
        small_library.angles_deg
    )


BILLION_LAUGHS = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">]>
<colors xmlns="urn:cacad-station:color:1" version="1">&lol3;</colors>"""
XXE = b"""<?xml version="1.0"?><!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]>
<colors xmlns="urn:cacad-station:color:1" version="1">&e;</colors>"""
EXTERNAL_DTD = b"""<?xml version="1.0"?><!DOCTYPE colors SYSTEM "http://example.invalid/x.dtd">
<colors xmlns="urn:cacad-station:color:1" version="1"/>"""


@pytest.mark.parametrize("data", [BILLION_LAUGHS, XXE, EXTERNAL_DTD])
@pytest.mark.parametrize("reader", [read_color_xml, read_cxf_specs])
def test_hostile_xml_is_refused(data: bytes, reader) -> None:
    with pytest.raises(HostileXMLError):
        reader(data)


def test_huge_and_deep_files_are_refused(tmp_path) -> None:
    big = tmp_path / "big.xml"
    big.write_bytes(b"<colors>" + b" " * (2 << 20) + b"</colors>")
    with pytest.raises(HostileXMLError, match="bytes"):
        read_color_xml(big)
    deep = b"<a>" * 100 + b"</a>" * 100
    with pytest.raises(HostileXMLError, match="depth"):
        read_color_xml(deep)


def _one(lab_lines: str, gloss: str = "85.0", angles: str = "15 45 110", extra: str = "") -> bytes:
    return (
        '<colors xmlns="urn:cacad-station:color:1" version="1"><color name="x" role="design"' + extra + ">"
        '<conditions illuminant="D65" observer="CIE 1964 10 Degree Standard Observer" illuminationAngleDeg="45"/>'
        f'<gloss geometryDeg="60" unit="GU">{gloss}</gloss><measurementSet angles="{angles}">{lab_lines}'
        "</measurementSet></color></colors>"
    ).encode()


LABS3 = "".join(f'<lab aspecularDeg="{a}" L="50" a="1" b="2"/>' for a in (15, 45, 110))


@pytest.mark.parametrize(
    ("data", "field"),
    [
        (b"<colors", "file"),
        (b'<colors xmlns="urn:other" version="1"/>', "root"),
        (_one(LABS3[: LABS3.rindex("<lab")]), "color[0]/measurementSet[0]"),
        (_one(LABS3, gloss="abc"), "color[0]/gloss@value"),
        (_one(LABS3, gloss="150"), "color[0]/gloss@value"),
        (_one(LABS3.replace('L="50"', 'L="-3"', 1)), "color[0]/measurementSet[0]/lab@L"),
        (_one(LABS3, angles="15 45 75"), "color[0]/measurementSet[0]@angles"),
        (_one(LABS3, extra=' type="matte"'), "color[0]@type"),
        (_one(LABS3.replace("110", "30")), "color[0]/measurementSet[0]@angles"),
    ],
)
def test_malformed_xml_names_the_field(data: bytes, field: str) -> None:
    with pytest.raises(XMLFormatError) as err:
        read_color_xml(data)
    assert err.value.field == field
    assert not isinstance(err.value, HostileXMLError)


def test_valid_minimal_file_reads() -> None:
    (spec,) = read_color_xml(_one(LABS3))
    assert spec.sets[0].angles_deg == (15.0, 45.0, 110.0)
    assert spec.gloss_gu == 85.0
