"""An import stores what it parsed under the hash of those same bytes, even if the file changes meanwhile.

The client ids of an import come from the file's SHA-256 (importing a file again stores nothing new). If
they were taken from a second read of the path, a file rewritten between parse and hash would store the
old values under the new file's ids, and importing the new file would then store nothing: its values lost.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

import station.ingest.formats as formats
from station.ingest.formats.csv_template import write_csv
from station.ingest.formats.measurement import OBSERVERS, ImportedMeasurement, Instrument
from ui.models.imports import import_file


def _csv(l_star: float) -> str:
    m = ImportedMeasurement(
        sample="P1",
        geometries=("45as15", "45as45"),
        lab=((l_star, 1.0, 2.0), (40.0, 1.0, 2.0)),
        wavelengths_nm=None,
        spectra=None,
        instrument=Instrument("MA-T12", "1", "X-Rite"),
        illuminant="D65",
        observer=OBSERVERS[1],
        measured_at=None,
        texture=(),
    )
    return write_csv([m])


class _Receipt:
    status, measurement_id, message = "stored", None, ""


class _Catch:
    """An ingestor that keeps what it is given."""

    def __init__(self) -> None:
        self.readings: list[Any] = []

    def submit(self, reading: Any) -> _Receipt:
        self.readings.append(reading)
        return _Receipt()


def _ids(path: Path) -> list[str]:
    sink = _Catch()
    result = import_file(path, sink, None, None)  # type: ignore[arg-type]
    assert not result.error, result.error
    return [str(r.client_id) for r in sink.readings]


def test_ids_come_from_the_bytes_parsed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    old, new = tmp_path / "old.csv", tmp_path / "new.csv"
    old.write_text(_csv(50.0), encoding="utf-8")
    new.write_text(_csv(60.0), encoding="utf-8")
    expected_old, expected_new = _ids(old), _ids(new)
    assert expected_old != expected_new

    target = tmp_path / "panel.csv"
    target.write_text(_csv(50.0), encoding="utf-8")
    parse = formats.read_measurement_file

    def parse_then_rewrite(*args: Any, **kwargs: Any) -> Any:
        out = parse(*args, **kwargs)
        target.write_text(_csv(60.0), encoding="utf-8")  # the instrument software saves again
        return out

    monkeypatch.setattr(formats, "read_measurement_file", parse_then_rewrite)
    assert _ids(target) == expected_old
