"""CSV template: a per-sample texture value (``texture:V:NAME:sample``) is never dropped or overridden."""

from __future__ import annotations

import pytest

from station.ingest.errors import CsvImportError
from station.ingest.formats.csv_template import read_csv
from station.ingest.formats.measurement import ImportedFile

_HEAD = "sample,geometry,L,a,b,texture:BYK:graininess:sample\n"


def _read(body: str) -> ImportedFile:
    return read_csv("panel.csv", (_HEAD + body).encode("utf-8"))


def test_value_on_a_later_row_is_kept() -> None:
    f = _read("P1,45as15,50,1,2,\nP1,45as45,40,1,2,3.25\n")
    (m,) = f.measurements
    assert [(t.vendor, t.name, t.geometry, t.value) for t in m.texture] == [("BYK", "graininess", "", 3.25)]


def test_the_same_value_on_every_row_is_one_value() -> None:
    f = _read("P1,45as15,50,1,2,3.25\nP1,45as45,40,1,2,3.25\n")
    (m,) = f.measurements
    assert [t.value for t in m.texture] == [3.25]


def test_two_different_values_are_refused_naming_the_column_and_line() -> None:
    with pytest.raises(CsvImportError) as info:
        _read("P1,45as15,50,1,2,3.25\nP1,45as45,40,1,2,4.0\n")
    text = str(info.value)
    assert "texture:BYK:graininess:sample" in text
    assert "line 3" in text
