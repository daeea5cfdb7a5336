"""Repeat readings of one sample in one CGATS.17 file: the writer gives each its own ``SAMPLE_ID`` under
the shared ``SAMPLE_NAME``, and the reader gives them back as separate readings (it refused the file,
"at most 12 geometries per sample", when it grouped the rows by name alone)."""

from __future__ import annotations

from pathlib import Path

import pytest

from station.ingest.formats import read_measurement_file, write_measurement_file
from station.ingest.formats.measurement import ImportedMeasurement
from tests.readings import lab_reading

GEOMETRIES = ("45as15", "45as45", "45as110")


def _reading(sample: str, dl: float) -> ImportedMeasurement:
    return lab_reading(sample, GEOMETRIES, [[60.0 - 10 * i + dl, -1.0, 2.0] for i in range(len(GEOMETRIES))])


@pytest.mark.parametrize("names", [("T1", "T1", "T1", "S2"), ("T1", "S2", "T1", "S2")])
def test_repeats_of_one_sample_come_back_one_by_one(tmp_path: Path, names: tuple[str, ...]) -> None:
    written = [_reading(n, 0.1 * k) for k, n in enumerate(names)]
    write_measurement_file(written, tmp_path / "repeats.cgats")
    back = read_measurement_file(tmp_path / "repeats.cgats").measurements
    assert [m.sample for m in back] == list(names)
    assert [m.lab for m in back] == [m.lab for m in written]


def test_one_reading_per_name_is_grouped_by_name(tmp_path: Path) -> None:
    """A file whose ``SAMPLE_ID`` numbers every row (not every reading) stays one reading per name."""
    rows = [f'{k + 1} "T1" {g} {50 - k:.1f} 0 0' for k, g in enumerate(GEOMETRIES)]
    text = "\n".join(
        ["CGATS.17", 'KEYWORD "SAMPLE_NAME"', 'KEYWORD "GEOMETRY"', "NUMBER_OF_FIELDS 6", "BEGIN_DATA_FORMAT",
         "SAMPLE_ID SAMPLE_NAME GEOMETRY LAB_L LAB_A LAB_B", "END_DATA_FORMAT", "NUMBER_OF_SETS 3",
         "BEGIN_DATA", *rows, "END_DATA", ""]
    )  # fmt: skip
    (tmp_path / "rows.cgats").write_text(text, encoding="utf-8")
    (m,) = read_measurement_file(tmp_path / "rows.cgats").measurements
    assert m.geometries == GEOMETRIES and m.lab is not None and [v[0] for v in m.lab] == [50.0, 49.0, 48.0]
