"""Workbooks are read as a stream within bounds: a few-MB ``.xlsx`` holding a million cells, or
declaring a sheet of 1 048 576 × 16 384 cells, is refused naming the bound, in bounded memory and
time; a zip whose parts unpack past the bounds is refused before it is parsed."""

from __future__ import annotations

import io
import json
import os
import sys
import zipfile
from pathlib import Path

import openpyxl
import pytest

from station.ingest.errors import WorkbookImportError
from station.ingest.formats import read_measurement_file
from station.ingest.formats.workbook import (
    MAX_SHARED_STRINGS_BYTES,
    MAX_WORKBOOK_BYTES,
    MAX_WORKBOOK_CELLS,
    MAX_WORKBOOK_XML_BYTES,
    SHEET,
)
from tests.processes import run

REPO = Path(__file__).resolve().parents[2]
#: Address space the reading child may use, bytes: the whole-workbook load of a million cells needs
#: several times this, the streaming read a small part of it.
CHILD_ADDRESS_SPACE = 3 << 30
#: Most the child's peak resident memory may grow while it reads the workbook, KiB.
MAX_GROWTH_KIB = 200 * 1024


def _workbook(path: Path, sheet_xml: bytes | None = None, extra: dict[str, bytes] | None = None) -> Path:
    """An MA-T12-style workbook with a header row; *sheet_xml* replaces the sheet's ``<sheetData>``
    body (and may carry a ``<dimension>``), *extra* adds or replaces zip members."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = SHEET
    ws.append(["Sample", "Geometry", "L*", "a*", "b*"])
    buf = io.BytesIO()
    wb.save(buf)
    with (
        zipfile.ZipFile(io.BytesIO(buf.getvalue())) as src,
        zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as dst,
    ):
        for info in src.infolist():
            data = src.read(info.filename)
            if info.filename == "xl/worksheets/sheet1.xml" and sheet_xml is not None:
                head, _, rest = data.partition(b"</sheetData>")
                data = head + sheet_xml + b"</sheetData>" + rest
            if extra and info.filename in extra:
                data = extra.pop(info.filename)
            dst.writestr(info.filename, data)
        for name, data in (extra or {}).items():
            dst.writestr(name, data)
    return path


def _read_in_child(path: Path) -> dict[str, object]:
    """Read *path* in a child process with a bounded address space; what happened, as a dict."""
    code = f"""
import json, resource, sys
resource.setrlimit(resource.RLIMIT_AS, ({CHILD_ADDRESS_SPACE}, {CHILD_ADDRESS_SPACE}))
from station.ingest.errors import ImportFileError
from station.ingest.formats import read_measurement_file
import openpyxl
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
out = {{}}
try:
    read_measurement_file(sys.argv[1])
    out["result"] = "read"
except ImportFileError as exc:
    out.update(result="refused", field=exc.field, accepted=exc.accepted, message=str(exc))
except MemoryError:
    out["result"] = "MemoryError"
out["growth_kib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
print(json.dumps(out))
"""
    env = dict(os.environ, PYTHONPATH=str(REPO), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    res = run([sys.executable, "-c", code, str(path)], timeout=120, env=env)
    assert res.returncode == 0, res.stderr[-2000:]
    return dict(json.loads(res.stdout))


def test_a_million_cells_are_refused_in_bounded_memory(tmp_path: Path) -> None:
    cols = 40
    rows = MAX_WORKBOOK_CELLS // cols + 10
    row = b"<row>" + b"<c><v>0.5</v></c>" * cols + b"</row>"
    path = _workbook(tmp_path / "million.xlsx", row * rows)
    assert path.stat().st_size < 1 << 20  # small on disk: the bomb is in the cells
    out = _read_in_child(path)
    assert out["result"] == "refused" and out["field"] == "cells", out
    assert f"at most {MAX_WORKBOOK_CELLS} cells" in str(out["accepted"])
    assert int(str(out["growth_kib"])) < MAX_GROWTH_KIB, out


def test_a_declared_giant_sheet_is_refused(tmp_path: Path) -> None:
    """One cell at XFD1048576 and a dimension of the whole sheet: padding and skipped rows count."""
    body = b'<row r="1048576"><c r="XFD1048576"><v>1</v></c></row>'
    path = _workbook(tmp_path / "giant.xlsx", body)
    with zipfile.ZipFile(path) as zf:
        sheet = zf.read("xl/worksheets/sheet1.xml")
    sheet = sheet.replace(b'<dimension ref="A1:E1"/>', b'<dimension ref="A1:XFD1048576"/>')
    path = _workbook(tmp_path / "giant2.xlsx", None, {"xl/worksheets/sheet1.xml": sheet})
    out = _read_in_child(path)
    assert out["result"] == "refused" and out["field"] == "cells", out
    assert int(str(out["growth_kib"])) < MAX_GROWTH_KIB, out


def test_unpacked_size_bounds(tmp_path: Path) -> None:
    strings = b"<sst>" + b"<si><t>x</t></si>" * (MAX_SHARED_STRINGS_BYTES // 16 + 1) + b"</sst>"
    path = _workbook(tmp_path / "strings.xlsx", None, {"xl/sharedStrings.xml": strings})
    with pytest.raises(WorkbookImportError, match=f"sharedStrings: expected at most {MAX_SHARED_STRINGS_BYTES} bytes unpacked"):  # fmt: skip
        read_measurement_file(path)
    filler = b" " * (MAX_WORKBOOK_XML_BYTES + 1)
    path = _workbook(tmp_path / "unpacked.xlsx", None, {"xl/filler.xml": filler})
    with pytest.raises(WorkbookImportError, match=f"xlsx: expected at most {MAX_WORKBOOK_XML_BYTES} bytes unpacked"):  # fmt: skip
        read_measurement_file(path)


def test_file_size_bound(tmp_path: Path) -> None:
    path = tmp_path / "big.xlsx"
    path.write_bytes(b"PK\x03\x04" + os.urandom(MAX_WORKBOOK_BYTES))
    with pytest.raises(WorkbookImportError, match=f"file: expected at most {MAX_WORKBOOK_BYTES} bytes"):
        read_measurement_file(path)


def test_padding_counts_against_the_cell_bound(tmp_path: Path) -> None:
    """Few cells, each at the sheet's last column: the rows read padded count, so the read stops."""
    rows = MAX_WORKBOOK_CELLS // 16384 + 2
    body = b"".join(b'<row r="%d"><c r="XFD%d"><v>1</v></c></row>' % (r, r) for r in range(2, rows + 2))
    path = _workbook(tmp_path / "wide.xlsx", body)
    with pytest.raises(
        WorkbookImportError, match=f"cells: expected at most {MAX_WORKBOOK_CELLS} cells"
    ) as exc:
        read_measurement_file(path)
    assert "sheet 'Spectral Data' row" in str(exc.value)
