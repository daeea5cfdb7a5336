"""CGATS layouts as instrument software writes them: ArgyllCMS ``CTI3`` with ``SPEC_`` fields, X-Rite
single-geometry 45/0 charts with ``SPECTRAL_NM`` and ``LAB_`` fields, multi-angle Lab-only tables."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import pytest

from station.ingest.formats import CgatsImportError, read_measurement_file
from station.model.domain import geometry_name

DATA = Path(__file__).parent / "data" / "cgats"
CIE1931 = "CIE 1931 2 Degree Standard Observer"


def test_argyll_ti3_spec_fields_single_geometry() -> None:
    white, black = read_measurement_file(DATA / "argyll_45_0.ti3").measurements
    assert white.geometries == black.geometries == (geometry_name(45, 45),)  # 45/0: 45° from specular
    assert white.wavelengths_nm == (400.0, 500.0, 700.0)  # SPEC_400 SPEC_500 SPEC_700
    assert white.spectra is not None and black.spectra is not None
    assert len(white.spectra) == len(black.spectra) == 1
    assert white.spectra[0] == pytest.approx((0.825, 0.881, 0.899))  # SPECTRAL_NORM "100.000000"
    assert black.spectra[0] == pytest.approx((0.0125, 0.0102, 0.0131))
    assert white.lab == ((95.10, -0.42, 2.31),) and black.lab == ((3.20, 0.15, -0.80),)
    assert (white.illuminant, white.observer) == ("D50", CIE1931)  # ICC PCS, stated by no keyword
    assert white.measured_at == dt.datetime(2026, 3, 4, 9, 12, 44, tzinfo=dt.UTC)
    assert white.instrument.model == "X-Rite i1 Pro" and white.sample == "1"


def test_xrite_single_geometry_chart_with_lab_and_spectra() -> None:
    a1, a2, a3 = read_measurement_file(DATA / "xrite_45_0.txt").measurements
    assert [m.sample for m in (a1, a2, a3)] == ["A1", "A2", "A3"]
    assert all(m.geometries == ("45as45",) for m in (a1, a2, a3))
    assert a2.lab == ((86.95, -0.31, 4.12),)
    assert a1.spectra == ((0.0512, 0.0821, 0.4410),) and a1.wavelengths_nm == (400.0, 550.0, 700.0)
    assert (a1.illuminant, a1.observer) == ("D50", CIE1931)
    assert a1.measured_at == dt.datetime(2026, 3, 4, 9, 5, tzinfo=dt.UTC)
    assert (a1.instrument.model, a1.instrument.serial, a1.instrument.manufacturer) == (
        "i1Pro 3",
        "1065432",
        "X-Rite",
    )


def test_lab_only_multi_angle_table() -> None:
    (m,) = read_measurement_file(DATA / "lab_multi_angle.txt").measurements
    assert m.sample == "Blue 2209" and m.spectra is None
    assert m.geometries == ("45as-15", "45as15", "45as25", "45as45", "45as110")
    assert m.lab is not None
    assert m.lab[0] == (41.20, -3.10, -38.40) and m.lab[-1] == (15.02, 0.21, -17.80)
    assert m.observer == "CIE 1964 10 Degree Standard Observer" and m.illuminant == "D65"


def _edited(tmp_path: Path, name: str, old: str, new: str) -> Path:
    text = (DATA / name).read_text(encoding="utf-8")
    assert old in text
    out = tmp_path / name
    out.write_text(text.replace(old, new), encoding="utf-8")
    return out


@pytest.mark.parametrize(
    ("name", "old", "new", "field"),
    [
        ("argyll_45_0.ti3", 'MEASUREMENT_GEOMETRY "45/0"\n', "", "GEOMETRY"),
        (
            "argyll_45_0.ti3",
            'MEASUREMENT_GEOMETRY "45/0"',
            'MEASUREMENT_GEOMETRY "0/45"',
            "MEASUREMENT_GEOMETRY",
        ),
        (
            "argyll_45_0.ti3",
            'MEASUREMENT_GEOMETRY "45/0"',
            'MEASUREMENT_GEOMETRY "diffuse"',
            "MEASUREMENT_GEOMETRY",
        ),
        ("argyll_45_0.ti3", 'SPECTRAL_NORM "100.000000"', 'SPECTRAL_NORM "percent"', "SPECTRAL_NORM"),
        ("argyll_45_0.ti3", "82.500", "8x.5", "SPEC_400"),
        ("xrite_45_0.txt", "LAB_L LAB_A LAB_B", "LAB_L LAB_A LAB_X", "LAB_L"),
        ("lab_multi_angle.txt", "45as25 30.10", "45as25 abc", "LAB_L"),
    ],
)
def test_bad_files_name_the_field(tmp_path: Path, name: str, old: str, new: str, field: str) -> None:
    with pytest.raises(CgatsImportError) as info:
        read_measurement_file(_edited(tmp_path, name, old, new))
    assert info.value.field == field
