"""CxF import: the texture tags ``VENDOR|NAME|GEOMETRY`` are checked like every other value of the file."""

from __future__ import annotations

import pytest

from station.ingest.errors import CxfImportError
from station.ingest.formats.cxf import read_cxf, write_cxf
from station.ingest.formats.measurement import OBSERVERS, ImportedMeasurement, Instrument, VendorValue

_TAG = b"BYK|sparkle_grade|45as15"


@pytest.fixture(scope="module")
def written() -> bytes:
    m = ImportedMeasurement(
        sample="P1",
        geometries=("45as15", "45as45"),
        lab=((50.0, 1.0, 2.0), (40.0, 1.0, 2.0)),
        wavelengths_nm=None,
        spectra=None,
        instrument=Instrument("MA-T12", "1", "X-Rite"),
        illuminant="D65",
        observer=OBSERVERS[1],
        measured_at=None,
        texture=(VendorValue("BYK", "sparkle_grade", 2.0, "45as15"),),
    )
    data = write_cxf([m])
    assert data.count(_TAG) == 1
    return data


def test_written_tags_read_back(written: bytes) -> None:
    (m,) = read_cxf("p.cxf", written).measurements
    assert [(t.vendor, t.name, t.geometry, t.value) for t in m.texture] == [
        ("BYK", "sparkle_grade", "45as15", 2.0)
    ]


def test_a_tag_geometry_in_another_spelling_reads_in_the_domain_spelling(written: bytes) -> None:
    (m,) = read_cxf("p.cxf", written.replace(_TAG, b"BYK|sparkle_grade| 45AS15 ")).measurements
    assert m.texture[0].geometry == "45as15"


@pytest.mark.parametrize("geometry", [b"bogus", b"45as"])
def test_a_malformed_tag_geometry_is_refused(written: bytes, geometry: bytes) -> None:
    with pytest.raises(CxfImportError) as info:
        read_cxf("p.cxf", written.replace(_TAG, b"BYK|sparkle_grade|" + geometry))
    assert "p.cxf" in str(info.value)
    assert info.value.field == "sparkle_grade"


@pytest.mark.parametrize("value", [b"nan", b"inf"])
def test_a_non_finite_tag_value_is_refused_naming_the_file(written: bytes, value: bytes) -> None:
    with pytest.raises(CxfImportError) as info:
        read_cxf("p.cxf", written.replace(b'Value="2.0"', b'Value="' + value + b'"'))
    assert info.value.field == "sparkle_grade"


def test_two_values_of_one_quantity_and_geometry_are_refused(written: bytes) -> None:
    two = written.replace(
        b'<ns0:Tag Name="BYK|sparkle_grade|45as15" Value="2.0"/>',
        b'<ns0:Tag Name="BYK|sparkle_grade|45as15" Value="2.0"/>'
        b'<ns0:Tag Name="BYK|sparkle_grade|45as15" Value="3.0"/>',
    )
    assert two != written
    with pytest.raises(CxfImportError) as info:
        read_cxf("p.cxf", two)
    assert info.value.field == "sparkle_grade"
