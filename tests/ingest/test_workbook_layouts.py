"""MA-T12 workbooks in the layout of real exports: a title row and an ``Illuminant/Observer`` row above
the ``Spectral Data`` header, ``Sample Name`` | ``Date/Time`` | ``Geometry`` | 400 … 700 nm (header in
row 3, geometry in column C, 31 bands in D:AH), a ``Texture Data`` sheet and a ``Texture Images`` sheet.
Fixtures are built here with openpyxl; expectations come from the values written."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import openpyxl
import pytest

from station.ingest.formats import (
    VendorValue,
    WorkbookImportError,
    read_measurement_file,
    write_measurement_file,
)
from station.ingest.formats.cxf import write_cxf

GEOMETRIES = [f"15as{a}" for a in (-60, -45, -30, -20, 0, 30)] + [
    f"45as{a}" for a in (-15, 15, 25, 45, 75, 110)
]
WL = list(range(400, 701, 10))
WHEN = {"Trial A": dt.datetime(2026, 3, 4, 10, 15, 2), "Trial B": dt.datetime(2026, 3, 4, 10, 17, 40)}


def _curves(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.02, 0.95, size=(len(GEOMETRIES), len(WL))).round(4)


def _workbook(
    path: Path, conditions: str | None = "D50/2°", texture: bool = True, dates: object = None
) -> Path:
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "Spectral Data"
    ws.append(["X-Rite MA-T12 Spectral Data"])
    ws.append(["Illuminant/Observer", conditions] if conditions is not None else [])
    ws.append(["Sample Name", "Date/Time", "Geometry", *WL])
    for k, sample in enumerate(WHEN):
        for g, curve in zip(GEOMETRIES, _curves(k), strict=True):
            when = WHEN[sample] if dates is None else dates
            ws.append([sample, when, g, *curve.tolist()])
    if texture:
        tx = wb.create_sheet("Texture Data")
        tx.append(["Sample Name", "Geometry", "Sparkle Intensity", "Sparkle Area", "Graininess"])
        for k, sample in enumerate(WHEN):
            tx.append([sample, "15as-60", 2.5 + k, 11.0 + k, 3.25 + k])
            tx.append([sample, "45as-15", 4.5 + k, 21.0 + k, None])
    img = wb.create_sheet("Texture Images")
    for r, g in enumerate(("15as-60", "15as-45", "15as-30", "45as-15", "45as15", "45as45"), start=2):
        img.cell(r, 1).value = g
    wb.save(path)
    return path


def test_real_layout_reads_dates_conditions_and_texture(tmp_path: Path) -> None:
    a, b = read_measurement_file(_workbook(tmp_path / "ma-t12.xlsx")).measurements
    assert [a.sample, b.sample] == ["Trial A", "Trial B"]
    assert a.geometries == tuple(GEOMETRIES) and a.wavelengths_nm == tuple(float(w) for w in WL)
    assert a.spectra is not None and b.spectra is not None
    assert np.array_equal(a.spectra, _curves(0)) and np.array_equal(b.spectra, _curves(1))
    assert a.measured_at == WHEN["Trial A"].replace(tzinfo=dt.UTC)
    assert b.measured_at == WHEN["Trial B"].replace(tzinfo=dt.UTC)
    assert (a.illuminant, a.observer) == ("D50", "CIE 1931 2 Degree Standard Observer")
    assert set(b.texture) == {
        VendorValue("X-Rite", "sparkle_intensity", 3.5, "15as-60"),
        VendorValue("X-Rite", "sparkle_area", 12.0, "15as-60"),
        VendorValue("X-Rite", "sparkle_intensity", 5.5, "45as-15"),
        VendorValue("X-Rite", "sparkle_area", 22.0, "45as-15"),
        VendorValue("X-Rite", "graininess", 4.25, ""),  # per sample: graininess is measured in diffuse light
    }


def test_the_date_survives_an_export(tmp_path: Path) -> None:
    """The date of the workbook, not a placeholder, is what a CxF export and a workbook round trip write."""
    imported = read_measurement_file(_workbook(tmp_path / "ma-t12.xlsx")).measurements
    cxf = tmp_path / "export.cxf"
    write_cxf(imported, cxf)
    assert [m.measured_at for m in read_measurement_file(cxf).measurements] == [
        WHEN["Trial A"].replace(tzinfo=dt.UTC),
        WHEN["Trial B"].replace(tzinfo=dt.UTC),
    ]
    out = tmp_path / "again.xlsx"
    write_measurement_file(imported, out)
    assert [m.measured_at for m in read_measurement_file(out).measurements] == [
        m.measured_at for m in imported
    ]


def test_iso_text_dates_and_the_label_value_form(tmp_path: Path) -> None:
    f = _workbook(
        tmp_path / "iso.xlsx", conditions="D65 / 10", texture=False, dates="2026-03-04T09:00:00+01:00"
    )
    a, _ = read_measurement_file(f).measurements
    assert a.measured_at == dt.datetime(2026, 3, 4, 8, 0, tzinfo=dt.UTC)
    assert (a.illuminant, a.observer) == ("D65", "CIE 1964 10 Degree Standard Observer") and a.texture == ()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"conditions": "F12/10°"}, "illuminant"),  # read, then refused: not an illuminant the store keeps
        ({"conditions": "D65/4°"}, "observer"),
        ({"conditions": "daylight"}, "Illuminant/Observer"),
        ({"dates": "yesterday"}, "Date/Time"),
    ],
)
def test_unsupported_or_unreadable_values_are_refused(tmp_path: Path, kwargs: dict, field: str) -> None:
    with pytest.raises(WorkbookImportError) as info:
        read_measurement_file(_workbook(tmp_path / "bad.xlsx", **kwargs))
    assert info.value.field == field, str(info.value)


def test_texture_for_an_unknown_sample_is_refused(tmp_path: Path) -> None:
    f = _workbook(tmp_path / "tex.xlsx")
    wb = openpyxl.load_workbook(f)
    wb["Texture Data"].cell(2, 1).value = "Trial Z"
    wb.save(f)
    with pytest.raises(WorkbookImportError) as info:
        read_measurement_file(f)
    assert (info.value.field, info.value.where) == ("Sample", "sheet 'Texture Data'")
