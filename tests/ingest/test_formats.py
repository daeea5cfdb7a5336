"""Importers on files written by the simulator (``station measure sim:ma6 --twelve --out …``): each
format reads back the simulator's own spectra and Lab; hand-written vendor-style files read as the
format defines; every malformed case is refused by the format's typed error naming file, place, field."""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path

import numpy as np
import pytest

from station.errors import InputError
from station.ingest.errors import (
    CgatsImportError,
    CsvImportError,
    CxfImportError,
    ImportFileError,
    IngestError,
    JsonImportError,
    UnknownFormatError,
    WorkbookImportError,
)
from station.ingest.formats import (
    ImportOptions,
    VendorValue,
    lab_of,
    read_measurement_file,
    readings_from_import,
    write_measurement_file,
)
from tests.ingest.conftest import ALL_FORMATS, FORMATS

ERRORS = {
    "cxf": CxfImportError,
    "cgats": CgatsImportError,
    "csv": CsvImportError,
    "xlsx": WorkbookImportError,
}


@pytest.mark.parametrize("fmt", ALL_FORMATS)
def test_round_trip_of_simulator_files(sim_files: tuple[dict, dict[str, Path]], fmt: str) -> None:
    measured, files = sim_files
    got = read_measurement_file(files[fmt])
    assert got.format == fmt and len(got.measurements) == 1
    m = got.measurements[0]
    assert m.sample == "std panel"
    assert list(m.geometries) == measured["geometries"] and len(m.geometries) == 12
    assert m.illuminations == (45.0, 15.0)  # two illumination blocks, as an MA-T12 writes them
    assert m.wavelengths_nm == tuple(float(w) for w in range(400, 701, 10))
    # spectra to the 6 decimals written, Lab to the 4 decimals measure prints
    assert np.abs(np.asarray(m.spectra) - np.asarray(measured["spectra"])).max() <= 5e-7 + 1e-12
    assert np.asarray(m.lab) == pytest.approx(np.asarray(measured["lab"]), abs=1e-4 + 1e-9)
    assert (m.instrument.model, m.instrument.serial) == (measured["model"], measured["serial"])
    assert m.measured_at == dt.datetime.fromisoformat(measured["time"])
    assert m.illuminant == "D65" and m.observer == "CIE 1964 10 Degree Standard Observer"
    readings = readings_from_import(
        got, ImportOptions("qa", "J-7", "door"), sha256="0" * 64, fallback_time=dt.datetime.now(dt.UTC)
    )
    assert m.lab is not None
    r, r15 = readings  # one reading per illumination block, in the file's order, on the same panel
    assert (r.illumination_deg, r15.illumination_deg) == (45.0, 15.0) and r15.panel == r.panel
    assert r.geometries_deg == [-15.0, 15.0, 25.0, 45.0, 75.0, 110.0]  # the 45° block
    assert r15.geometries_deg == [-45.0, -15.0, 15.0, 25.0, 45.0, 60.0] and r15.lab == [
        list(v) for v in m.lab[6:]
    ]
    assert r.lab == [list(v) for v in m.lab[:6]]
    assert r.panel is not None and (r.panel.job, r.panel.part, r.panel.notes) == (
        "J-7",
        "door",
        "sample: std panel",
    )
    again = readings_from_import(
        got, ImportOptions("qa"), sha256="0" * 64, fallback_time=dt.datetime.now(dt.UTC)
    )
    assert again[0].client_id == r.client_id  # same bytes, same client id: a re-import is a duplicate
    lit15 = readings_from_import(got, ImportOptions("qa", illumination_deg=15), sha256="0" * 64,
                                 fallback_time=dt.datetime.now(dt.UTC))  # fmt: skip
    assert lit15 == [
        r15.model_copy(update={"panel": None})
    ]  # that block only, as in the pair (no panel asked)
    assert lit15[0].client_id != r.client_id


ARGYLL_STYLE = """CTI3   # a comment after the file type
DESCRIPTOR "Argyll-style \"\"multi-angle\"\" export"
ORIGINATOR "spectro"
MANUFACTURER "BYK-Gardner"
INSTRUMENTATION "BYK-mac i"
KEYWORD "SERIAL_NUMBER"
SERIAL_NUMBER "1234 567"
MEASUREMENT_SOURCE "Illumination=D50 ObserverAngle=2"
SPECTRAL_NORM "100"
CREATED "2026-11-23T08:30:00Z"
KEYWORD "ILLUMINATION_ANGLE"
KEYWORD "ASPECULAR_ANGLE"
NUMBER_OF_FIELDS 9
BEGIN_DATA_FORMAT
SAMPLE_ID SAMPLE_NAME ILLUMINATION_ANGLE ASPECULAR_ANGLE
SPECTRAL_NM400 SPECTRAL_NM550 SPECTRAL_NM700 SPARKLE_INTENSITY GRAININESS
END_DATA_FORMAT
NUMBER_OF_SETS 3
BEGIN_DATA
1 "door #1" 45 15 50.0 60.0 70.0 4.5 3.1   # three bands only: spectra without Lab
2 "door #1" 45 45 10.0 12.0 14.0 "" 3.1
3 "door #1" 45 110 5.0 6.0 7.0 "" 3.1
END_DATA
"""


def test_cgats_as_the_format_defines(tmp_path: Path) -> None:
    f = tmp_path / "byk.txt"
    f.write_text(ARGYLL_STYLE, encoding="utf-8")
    (m,) = read_measurement_file(f).measurements
    assert m.sample == "door #1"  # '#' inside quotes is text, outside it starts a comment
    assert m.geometries == ("45as15", "45as45", "45as110")
    assert m.spectra == ((0.5, 0.6, 0.7), (0.1, 0.12, 0.14), (0.05, 0.06, 0.07))  # percent → factor
    assert m.wavelengths_nm == (400.0, 550.0, 700.0) and m.lab is None
    assert (m.illuminant, m.observer) == ("D50", "CIE 1931 2 Degree Standard Observer")
    assert m.instrument.serial == "1234 567" and m.instrument.manufacturer == "BYK-Gardner"
    assert set(m.texture) == {
        VendorValue("BYK-Gardner", "sparkle_intensity", 4.5, "45as15"),
        VendorValue("BYK-Gardner", "graininess", 3.1, ""),
    }
    # Lab from three bands is refused: spectra-only files need the product grid
    with pytest.raises(ImportFileError, match=r"wavelengths_nm: expected .*400–700 nm"):
        lab_of(m, lambda fl, acc, got: ImportFileError("byk.txt", "", fl, acc, got))


def test_texture_never_compares_across_vendors() -> None:
    byk = VendorValue("BYK-Gardner", "sparkle_grade", 4.0, "45as15")
    xrite = VendorValue("X-Rite", "sparkle_grade", 3.0, "45as15")
    assert byk.difference(VendorValue("BYK-Gardner", "sparkle_grade", 3.25, "45as15")) == 0.75
    with pytest.raises(InputError, match="same vendor"):
        byk.difference(xrite)
    with pytest.raises(InputError, match="vendor name"):
        VendorValue(" ", "graininess", 1.0)


def test_csv_spectra_only_computes_lab(sim_files: tuple[dict, dict[str, Path]], tmp_path: Path) -> None:
    measured, files = sim_files
    lines = files["csv"].read_text(encoding="utf-8").splitlines()
    header = lines[1].split(",")
    keep = [i for i, h in enumerate(header) if h not in ("L", "a", "b")]
    text = "\n".join(",".join(row.split(",")[i] for i in keep) for row in lines[1:]) + "\n"
    f = tmp_path / "nolab.csv"
    f.write_text(text, encoding="utf-8")
    (m,) = read_measurement_file(f).measurements
    assert m.lab is None
    lab = lab_of(m, lambda fl, acc, got: ImportFileError("nolab.csv", "", fl, acc, got))
    assert lab == pytest.approx(np.asarray(measured["lab"]), abs=2e-3)  # from spectra rounded to 1e-6


def _mutate(fmt: str, text: str, case: str) -> str | bytes:
    """A malformed copy of the simulator file *text* for *case*."""
    if case == "truncated":
        return text[: len(text) * 2 // 3]
    if case == "encoding":
        return text.replace("std panel", "std pan\xe9l").encode("latin-1")
    if fmt == "cxf":
        first_l = text.index("<ns0:L>") + len("<ns0:L>")
        end_l = text.index("</ns0:L>", first_l)
        if case == "missing":
            return text.replace("<ns0:L>", "<ns0:X>", 1).replace("</ns0:L>", "</ns0:X>", 1)
        if case == "nan":
            return text[:first_l] + "NaN" + text[end_l:]
        if case == "range":
            return text[:first_l] + "250.0" + text[end_l:]
        if case == "duplicate":  # the second geometry's specification renamed to the first's
            return text.replace("CS45as15-", "CS45as-15-")
    lines = text.splitlines()
    if fmt == "cgats":
        data = lines.index("BEGIN_DATA") + 1
        cells = lines[data].split(" ")  # id, '"std', 'panel"', geometry, L, a, b, spectra…
        if case == "missing":
            fmt_line = lines.index("BEGIN_DATA_FORMAT") + 1
            lines[fmt_line] = lines[fmt_line].replace(" GEOMETRY", " GEO")
        elif case == "nan":
            cells[5] = "nan"
        elif case == "range":
            cells[4] = "-5.0"
        elif case == "duplicate":
            cells[3] = lines[data + 1].split(" ")[3]
        lines[data] = " ".join(cells)
    else:
        cells = lines[2].split(",")
        if case == "missing":
            lines[1] = lines[1].replace(",geometry,", ",geom,")
        elif case == "nan":
            cells[3] = "NaN"
        elif case == "range":
            cells[4] = "151"
        elif case == "duplicate":
            cells[1] = lines[3].split(",")[1]
        lines[2] = ",".join(cells)
    return "\n".join(lines) + "\n"


EXPECT = {  # case → (place pattern, field pattern) in the one-line message
    "truncated": (r"line \d+", r"(xml|END_DATA|row|spectra|measured_at)"),
    "encoding": (r"line \d+", r"encoding"),
    "missing": (r"", r"(L|GEOMETRY|geometry|xml)"),
    "nan": (r"", r"(lab\.[Lab]|a finite number)"),
    "range": (r"", r"lab\.[Lab]"),
    "duplicate": (r"", r"geometry"),
}


@pytest.mark.parametrize("case", list(EXPECT))
@pytest.mark.parametrize("fmt", FORMATS)
def test_malformed_files_are_refused(
    sim_files: tuple[dict, dict[str, Path]], tmp_path: Path, fmt: str, case: str
) -> None:
    _, files = sim_files
    bad = _mutate(fmt, files[fmt].read_text(encoding="utf-8"), case)
    f = tmp_path / f"bad-{case}.{fmt}"
    if isinstance(bad, bytes):
        f.write_bytes(bad)
    else:
        f.write_text(bad, encoding="utf-8")
    with pytest.raises(ERRORS[fmt]) as info:
        read_measurement_file(f)
    err = info.value
    assert isinstance(err, InputError) and isinstance(err, IngestError)  # CLI exit 2, ingest hierarchy
    msg = str(err)
    assert f.name in msg and "\n" not in msg
    place, fld = EXPECT[case]
    assert err.where and (not place or re.search(place, err.where)), msg
    assert re.search(fld, err.field + " " + err.accepted), msg


def test_hostile_and_unknown_files(tmp_path: Path) -> None:
    xxe = tmp_path / "xxe.cxf"
    xxe.write_text(
        '<?xml version="1.0"?><!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]>'
        '<cc:CxF xmlns:cc="http://colorexchangeformat.com/CxF3-core">&e;</cc:CxF>',
        encoding="utf-8",
    )
    with pytest.raises(CxfImportError, match="DOCTYPE"):
        read_measurement_file(xxe)
    other = tmp_path / "notes.bin"
    other.write_bytes(b"\x00\x01hello")
    with pytest.raises(UnknownFormatError, match=r"notes\.bin"):
        read_measurement_file(other)
    empty = tmp_path / "empty.cxf"
    empty.write_text(
        '<cc:CxF xmlns:cc="http://colorexchangeformat.com/CxF3-core"><cc:Resources/></cc:CxF>',
        encoding="utf-8",
    )
    with pytest.raises(CxfImportError, match="Object"):
        read_measurement_file(empty)


def test_out_of_range_angle_and_count_mismatch(tmp_path: Path) -> None:
    text = (
        "CGATS.17\nNUMBER_OF_SETS 2\nBEGIN_DATA_FORMAT\nSAMPLE_ID GEOMETRY LAB_L LAB_A LAB_B\nEND_DATA_FORMAT\n"
        "BEGIN_DATA\nA 45as15 50 1 2\nEND_DATA\n"
    )
    f = tmp_path / "count.cgats"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(CgatsImportError, match=r"NUMBER_OF_SETS: expected the number of data rows \(1\), got 2 \(count.cgats, line 2\)"):  # fmt: skip
        read_measurement_file(f)
    f.write_text(text.replace("NUMBER_OF_SETS 2\n", "").replace("45as15", "45by15"), encoding="utf-8")
    with pytest.raises(CgatsImportError, match=r"GEOMETRY: expected a name like .* line 6"):
        read_measurement_file(f)


@pytest.mark.parametrize("src", ALL_FORMATS)
def test_every_format_converts_to_every_other(
    sim_files: tuple[dict, dict[str, Path]], tmp_path: Path, src: str
) -> None:
    _, files = sim_files
    original = read_measurement_file(files[src]).measurements
    for dst in ALL_FORMATS:
        path = tmp_path / f"converted.{dst}"
        assert write_measurement_file(original, path) == dst
        (back,) = read_measurement_file(path).measurements
        (m,) = original
        assert (back.geometries, back.lab, back.spectra, back.wavelengths_nm) == (
            m.geometries, m.lab, m.spectra, m.wavelengths_nm,
        )  # fmt: skip
        assert (back.instrument, back.measured_at, back.illuminant, back.observer) == (
            m.instrument, m.measured_at, m.illuminant, m.observer,
        )  # fmt: skip


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("<ns0:L>", "<ns0:L>abc", "ColorCielab.l"),
        ("<ns0:Aspecular>-15", "<ns0:Aspecular>x", "Brdfangle.aspecular"),
        ("<ns0:Illuminant>D65", "<ns0:Illuminant>D99", "Illuminant.value"),
        ('StartWL="400"', 'StartWL="a"', "ReflectanceSpectrum.start_wl"),
    ],
)
def test_cxf_values_of_the_wrong_type(
    sim_files: tuple[dict, dict[str, Path]], tmp_path: Path, old: str, new: str, field: str
) -> None:
    text = sim_files[1]["cxf"].read_text(encoding="utf-8")
    assert old in text
    f = tmp_path / "typed.cxf"
    f.write_text(text.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(CxfImportError) as info:
        read_measurement_file(f)
    assert info.value.field == field and "typed.cxf" in str(info.value)


@pytest.mark.parametrize("fmt", ALL_FORMATS)
def test_random_damage_is_accepted_or_refused_by_a_typed_error(
    sim_files: tuple[dict, dict[str, Path]], tmp_path: Path, fmt: str
) -> None:
    """300 files with random bytes replaced, deleted or cut: never an untyped exception."""
    data = sim_files[1][fmt].read_bytes()
    rng = np.random.default_rng(20261201)
    outcomes = {"accepted": 0, "refused": 0}
    for k in range(300):
        b = bytearray(data)
        for _ in range(int(rng.integers(1, 4))):
            i = int(rng.integers(0, len(b)))
            op = int(rng.integers(0, 3))
            if op == 0:
                b[i] = int(rng.choice(list(b' ,;"#<>/=-.0123456789abcxyzN\n\xff')))
            elif op == 1:
                del b[i : i + int(rng.integers(1, 40))]
            else:
                del b[i:]
        f = tmp_path / f"d{k}.{fmt}"
        f.write_bytes(bytes(b))
        try:
            read_measurement_file(f)
        except ImportFileError as exc:
            assert f.name in str(exc) and "\n" not in str(exc)
            outcomes["refused"] += 1
        else:
            outcomes["accepted"] += 1
    assert outcomes["refused"] > 100  # most damage is caught, and each refusal was typed


def _edit_workbook(src: Path, dst: Path, edit: str) -> None:
    import openpyxl

    wb = openpyxl.load_workbook(src)
    ws = wb["Spectral Data"]
    if edit == "missing":
        ws.cell(1, 2).value = "Geo"
    elif edit == "nan":
        ws.cell(3, 3).value = "nan"
    elif edit == "range":
        ws.cell(2, 3).value = 250.0
    elif edit == "duplicate":
        ws.cell(3, 2).value = ws.cell(2, 2).value
    elif edit == "sheet":
        ws.title = "Data"
    elif edit == "text":
        ws.cell(4, 10).value = "n/a"
    wb.save(dst)


@pytest.mark.parametrize(
    ("edit", "where", "field"),
    [
        ("missing", "sheet 'Spectral Data'", "Geometry"),
        ("nan", "sheet 'Spectral Data' row 3", "lab.L"),
        ("range", "sheet 'Spectral Data' row 2", "lab.L"),
        ("duplicate", "sheet 'Spectral Data' row 3", "geometry"),
        ("sheet", "workbook", "sheet"),
        ("text", "sheet 'Spectral Data' row 4", "440 nm"),  # column 10: Sample, Geometry, L, a, b, 400…440
        ("truncated", "workbook", "xlsx"),
    ],
)
def test_malformed_workbooks_are_refused(
    sim_files: tuple[dict, dict[str, Path]], tmp_path: Path, edit: str, where: str, field: str
) -> None:
    f = tmp_path / f"bad-{edit}.xlsx"
    if edit == "truncated":
        data = sim_files[1]["xlsx"].read_bytes()
        f.write_bytes(data[: len(data) // 2])
    else:
        _edit_workbook(sim_files[1]["xlsx"], f, edit)
    with pytest.raises(WorkbookImportError) as info:
        read_measurement_file(f)
    assert (info.value.where, info.value.field) == (where, field), str(info.value)
    assert f.name in str(info.value)


def test_station_json_documents_read_back(sim_files: tuple[dict, dict[str, Path]], tmp_path: Path) -> None:
    """What ``station measure --json`` and ``station import --json`` print is itself importable."""
    import json

    measured, files = sim_files
    f = tmp_path / "measure.json"
    f.write_text(json.dumps(measured), encoding="utf-8")
    (m,) = read_measurement_file(f).measurements
    (ref,) = read_measurement_file(files["cxf"]).measurements
    assert (m.geometries, m.lab, m.measured_at, m.instrument.serial) == (
        ref.geometries, ref.lab, ref.measured_at, ref.instrument.serial,
    )  # fmt: skip
    assert (
        np.abs(np.asarray(m.spectra) - np.asarray(ref.spectra)).max() <= 5e-7 + 1e-12
    )  # unrounded vs 6 decimals
    doc = {"measurements": [dict(ref.to_dict(), sample="copy")]}
    f.write_text(json.dumps(doc), encoding="utf-8")
    (copy,) = read_measurement_file(f).measurements
    assert (copy.sample, copy.lab, copy.spectra) == ("copy", ref.lab, ref.spectra)
    for text, where, fld in (
        ('{"geometries": ["45as15"], "lab": [[50, 1, NaN]]}', "document", "json"),
        ('{"geometries": ["45as15"], "lab": [[50, 1', "line 1", "json"),
        ('{"lab": [[50, 1, 2]]}', "$", "geometries"),
        ('{"geometries": ["45as15"], "lab": [[50, 1, "2"]]}', "$.lab[0]", "lab"),
        ('{"measurements": [{"geometries": ["45as15", "45as15"], "lab": [[50, 1, 2], [50, 1, 2]]}]}',
         "$.measurements[0].geometries[1]", "geometry"),
    ):  # fmt: skip
        f.write_text(text, encoding="utf-8")
        with pytest.raises(JsonImportError) as info:
            read_measurement_file(f)
        assert (info.value.where, info.value.field) == (where, fld), str(info.value)
