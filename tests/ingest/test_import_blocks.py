"""Both illumination blocks of an MA-T12-style file, and its vendor texture values, stored through
``station import --store`` on SQLite and PostgreSQL: one measurement per block on the same panel, the
texture values vendor-tagged and equal to the file's, the hash chain intact, a re-import a duplicate,
and QC judging the 45° block only (the 15° rows are neither samples nor standards)."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import pytest
from sqlalchemy import select
from sqlalchemy.pool import NullPool

from db.engine import make_engine, make_sessionmaker
from db.models import Measurement
from station.ingest.formats import VendorValue, read_measurement_file, write_measurement_file
from station.ingest.formats.measurement import ImportedMeasurement
from station.model.domain import parse_geometry
from tests.user_cli import run_station

JOB, PART = "J-12", "door"
#: Lab offsets of the sample file per illumination block (ΔL*): the 45° block's is what QC must see.
SHIFT = {45.0: 0.5, 15.0: 3.0}


def _shifted(m: ImportedMeasurement, name: str) -> ImportedMeasurement:
    """*m* renamed, each Lab moved by its block's ΔL* (:data:`SHIFT`)."""
    assert m.lab is not None
    lab = tuple(
        (L + SHIFT[parse_geometry(g)[0]], a, b) for g, (L, a, b) in zip(m.geometries, m.lab, strict=True)
    )
    return dataclasses.replace(m, sample=name, lab=lab)


@pytest.fixture
def files(tmp_path: Path, sim_files: tuple[dict[str, object], dict[str, Path]]) -> tuple[Path, Path]:
    """The simulator's two-block CGATS file with vendor texture values, and a sample file beside it."""
    (m,) = read_measurement_file(sim_files[1]["cgats"]).measurements
    assert m.illuminations == (45.0, 15.0)
    vendor = "X-Rite"
    texture = (
        VendorValue(vendor, "sparkle_intensity", 4.25, "45as15"),
        VendorValue(vendor, "sparkle_intensity", 6.5, "45as-15"),
        VendorValue(vendor, "sparkle_intensity", 3.125, "15as15"),
        VendorValue(vendor, "graininess", 2.75, ""),  # per sample (diffuse light)
    )
    std = dataclasses.replace(
        m, instrument=dataclasses.replace(m.instrument, manufacturer=vendor), texture=texture
    )
    write_measurement_file([std], tmp_path / "std.cgats")
    write_measurement_file([_shifted(std, "trial 1")], tmp_path / "smp.cgats")
    return tmp_path / "std.cgats", tmp_path / "smp.cgats"


def _args(cwd: Path, url: str, name: str, *extra: str) -> list[str]:
    return ["import", name, "--store", url, "--outbox", str(cwd / "outbox.sqlite3"),
            "--job", JOB, "--part", PART, *extra, "--json"]  # fmt: skip


def _import(cwd: Path, url: str, name: str, *extra: str) -> dict:
    """``station import`` as a user runs it, from *cwd* (a process of its own)."""
    res = run_station(cwd, *_args(cwd, url, name, *extra), env={"CACAD_OPERATOR": "qa"})
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def _main(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str]:
    """``station ARGS`` in this process (the checks that need no process of their own)."""
    from station.cli import main

    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out + captured.err


def _rows(url: str) -> list[Measurement]:
    engine = make_engine(url, poolclass=NullPool)
    try:
        with make_sessionmaker(engine)() as session:
            rows = list(session.scalars(select(Measurement).order_by(Measurement.id)))
            session.expunge_all()
    finally:
        engine.dispose()
    return rows


def test_both_blocks_and_texture_stored_and_qc_uses_the_45_block(
    tmp_path: Path,
    database_url: str,
    files: tuple[Path, Path],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from station.api.services.measurements import get_measurement
    from station.qc.errors import QcInputError
    from station.qc.jobs import job_summary, set_standard
    from station.qc.readings import reading_from_measurement

    std_file, smp_file = files
    url = database_url
    (m,) = read_measurement_file(std_file).measurements  # what the file says, read independently
    out = _import(tmp_path, url, std_file.name)
    assert [(r["status"], r["illumination_deg"]) for r in out["stored"]] == [
        ("stored", 45.0),
        ("stored", 15.0),
    ]
    assert out["measurements"][0]["texture"] == [t.to_dict() for t in m.texture]

    rows = _rows(url)
    assert [r.illumination_deg for r in rows] == [45.0, 15.0] and rows[0].panel_id == rows[1].panel_id
    assert m.lab is not None
    for row in rows:  # each block: its aspecular angles and the file's Lab, in the file's order
        idx = [i for i, g in enumerate(m.geometries) if parse_geometry(g)[0] == row.illumination_deg]
        assert row.geometries_deg == [parse_geometry(m.geometries[i])[1] for i in idx]
        assert row.lab == [list(m.lab[i]) for i in idx]
    # texture: each geometry's value with its block, the per-sample graininess with the 45° block
    stored = [(r.illumination_deg, t) for r in rows for t in r.texture or []]
    assert sorted((t["vendor"], t["name"], t["geometry"], t["value"]) for _, t in stored) == sorted(
        (t.vendor, t.name, t.geometry, t.value) for t in m.texture
    )
    assert {(ill, t["geometry"]) for ill, t in stored} == {
        (45.0, "45as15"),
        (45.0, "45as-15"),
        (45.0, ""),
        (15.0, "15as15"),
    }

    # the chain holds both rows; a re-import stores nothing new
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("CACAD_OPERATOR", "qa")
    code, text = _main(capsys, "db", "verify", "--database", url)
    assert code == 0, text
    code, text = _main(capsys, *_args(tmp_path, url, std_file.name))
    again = json.loads(text)
    assert [r["status"] for r in again["stored"]] == ["duplicate", "duplicate"]
    assert [r["measurement_id"] for r in again["stored"]] == [r.id for r in rows]
    code, text = _main(capsys, *_args(tmp_path, url, smp_file.name, "--illumination", "15"))
    only15 = json.loads(text)
    assert [(r["status"], r["illumination_deg"]) for r in only15["stored"]] == [("stored", 15.0)]
    code, text = _main(capsys, *_args(tmp_path, url, smp_file.name))  # both: the 15° block is there
    assert [r["status"] for r in json.loads(text)["stored"]] == ["stored", "duplicate"]
    rows = _rows(url)
    assert [r.illumination_deg for r in rows] == [45.0, 15.0, 15.0, 45.0]
    assert rows[2].texture == [
        {"vendor": "X-Rite", "name": "sparkle_intensity", "geometry": "15as15", "value": 3.125}
    ]
    code, text = _main(capsys, "db", "verify", "--database", url)
    assert code == 0, text

    std45, std15, smp15, smp45 = rows
    engine = make_engine(url, poolclass=NullPool)
    try:
        with make_sessionmaker(engine).begin() as session:
            public = get_measurement(session=session, measurement_id=std15.id)  # the API's output schema
            assert public.illumination_deg == 15.0 and public.texture is not None
            assert [t.model_dump() for t in public.texture] == std15.texture
            with pytest.raises(QcInputError, match="illumination"):
                set_standard(session, JOB, PART, measurement_id=std15.id)
            with pytest.raises(QcInputError, match="illumination"):
                reading_from_measurement(session.get(Measurement, smp15.id))  # type: ignore[arg-type]
            set_standard(session, JOB, PART, measurement_id=std45.id)
        with make_sessionmaker(engine)() as session:
            summary = job_summary(session, JOB, formula="cie76")
    finally:
        engine.dispose()
    (part,) = summary.parts
    assert part.unjudged == () and [s.row.measurement_id for s in part.samples] == [smp45.id]
    (sample,) = part.samples
    per = sample.verdict.per_geometry
    assert [g.aspecular_deg for g in per] == std45.geometries_deg == smp45.geometries_deg
    # ΔE*ab of a pure ΔL* shift is |ΔL*|: the 45° block's 0.5, never the 15° block's 3.0
    expected = [math.dist(a, b) for a, b in zip(std45.lab, smp45.lab, strict=True)]
    assert [g.de for g in per] == pytest.approx(expected, abs=1e-9)
    assert expected == pytest.approx([SHIFT[45.0]] * 6, abs=1e-6)


def test_an_import_that_names_no_block_of_the_file_stores_nothing(
    tmp_path: Path,
    database_url: str,
    files: tuple[Path, Path],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    code, text = _main(capsys, *_args(tmp_path, database_url, files[0].name, "--illumination", "25"))
    assert code == 2 and text.count("\n") == 1
    assert "illumination_deg" in text and "[15.0, 45.0]" in text
    code, text = _main(capsys, *_args(tmp_path, database_url, files[0].name, "--illumination", "90"))
    assert code == 2 and "--illumination" in text and "0 < degrees < 90" in text
    assert _rows(database_url) == []


@pytest.mark.parametrize(
    ("geometry", "words"),
    [("45as33", "texture"), ("bogus", "texture.geometry"), ("45AS15", None)],
)
def test_texture_geometries_are_checked_against_the_sample(
    sim_files: tuple[dict[str, object], dict[str, Path]], geometry: str, words: str | None
) -> None:
    """A texture value at a geometry the sample lacks, or a malformed one, is refused naming texture."""
    import datetime as dt

    from station.ingest.errors import ImportFileError
    from station.ingest.formats import ImportedFile
    from station.ingest.formats.records import ImportOptions, readings_from_import

    (m,) = read_measurement_file(sim_files[1]["cgats"]).measurements
    bad = dataclasses.replace(m, texture=(VendorValue("X-Rite", "sparkle", 1.0, geometry),))
    imported = ImportedFile("cgats", "tex.cgats", (bad,))
    kw = {"sha256": "1" * 64, "fallback_time": dt.datetime.now(dt.UTC)}
    if words is None:  # any spelling of a geometry of the sample is stored in the domain's
        r45, r15 = readings_from_import(imported, ImportOptions("qa"), **kw)  # type: ignore[arg-type]
        assert (
            r45.texture is not None
            and [t.geometry for t in r45.texture] == ["45as15"]
            and r15.texture is None
        )
        return
    with pytest.raises(ImportFileError, match=words) as err:
        readings_from_import(imported, ImportOptions("qa"), **kw)  # type: ignore[arg-type]
    assert "tex.cgats" in str(err.value) and "measurement 1" in str(err.value)
