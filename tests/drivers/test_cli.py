"""``station instruments list`` / ``calibrate`` / ``measure`` end to end (simulators as subprocesses)."""

from __future__ import annotations

import json

import numpy as np

from station.cli import main
from station.model import FaceFlopTravelGloss
from station.model.angles import flake_equivalent_aspecular
from station.model.design_io import save_design
from station.model.difference import delta_e


def run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_list_json(capsys):
    rc, out, _ = run(capsys, "instruments", "list", "--json")
    assert rc == 0
    data = json.loads(out)
    assert {"sim:ma6", "sim:ma3", "sim:gloss"} <= {d["address"] for d in data["devices"]}


def test_measure_sim_ma6_json_with_design(capsys, tmp_path):
    design = FaceFlopTravelGloss(
        face=(60.0, -20.0, -30.0), flop=(30.0, -10.0, -35.0), travel_deg=60.0, gloss_gu=90.0
    )
    path = save_design(design, tmp_path / "blue.json")
    rc, out, err = run(capsys, "measure", "sim:ma6", "--design", str(path), "--panel", "P-17", "--json")
    assert rc == 0, err
    data = json.loads(out)
    assert data["panel"] == "P-17"
    assert data["geometries"] == ["45as-15", "45as15", "45as25", "45as45", "45as75", "45as110"]
    assert np.asarray(data["spectra"]).shape == (6, 31)
    de = delta_e(
        np.asarray(data["lab"]),
        design.lab_at(flake_equivalent_aspecular([-15, 15, 25, 45, 75, 110])),
        method="cie2000",
    )
    assert float(de.max()) < 0.15
    assert data["gloss_gu"] is None and data["serial"] == "600123"


def test_measure_sim_gloss_json(capsys):
    rc, out, err = run(capsys, "measure", "sim:gloss", "--json")
    assert rc == 0, err
    data = json.loads(out)
    assert set(data["gloss_gu"]) == {"20", "60", "85"}
    assert data["geometries"] == [] and data["lab"] == []


def test_measure_typed_error_and_bad_input(capsys):
    rc, _, err = run(capsys, "measure", "sim:ma9")
    assert rc == 2 and "sim:ma6" in err
    rc, _, err = run(capsys, "calibrate", "/dev/ttyACM0", "--design", "x.json")
    assert rc == 2
    rc, _, err = run(capsys, "measure", "/dev/does-not-exist")
    assert rc == 1 and "does-not-exist" in err


def test_measure_store_goes_through_the_ingestor_once(capsys, tmp_path, monkeypatch):
    """``--store``: the reading lands once in the database (a retry under the same client id adds nothing);
    the default database is the one ``station serve`` uses; a bad panel or a gloss reading is refused."""
    import uuid

    from sqlalchemy import create_engine, select
    from sqlalchemy.orm import Session

    from db.models import Measurement
    from station.model.spectra import reflectance_to_lab

    monkeypatch.setenv("CACAD_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("CACAD_DATABASE_URL", raising=False)
    cid = str(uuid.uuid4())
    for expected in ("stored", "duplicate"):
        rc, out, err = run(capsys, "measure", "sim:ma6", "--store", "--client-id", cid, "--json")
        assert rc == 0, err
        stored = json.loads(out)["stored"]
        assert stored["status"] == expected and stored["client_id"] == cid
    url = f"sqlite:///{tmp_path / 'data' / 'station.sqlite3'}"
    engine = create_engine(url)
    with Session(engine) as s:
        rows = s.scalars(select(Measurement)).all()
    engine.dispose()
    assert [str(r.client_id) for r in rows] == [cid] and rows[0].id == stored["measurement_id"]
    # Lab recomputed here from the stored spectra (the record's Lab is the model's, not the driver's)
    np.testing.assert_allclose(rows[0].lab, reflectance_to_lab(np.asarray(rows[0].spectra)), atol=1e-3)
    assert (tmp_path / "data" / "measure-outbox.sqlite3").exists()
    other = tmp_path / "other.sqlite3"
    rc, out, err = run(capsys, "measure", "sim:ma6", "--store", f"sqlite:///{other}", "--json")
    assert rc == 0 and json.loads(out)["stored"]["status"] == "stored", err
    rc, _, err = run(capsys, "measure", "sim:ma6", "--store", "--panel", "P-17")
    assert rc == 2 and "--panel" in err


def test_measure_store_keeps_a_gloss_only_reading(capsys, tmp_path):
    """A gloss meter's reading is stored whole (20/60/85 GU, haze, DOI) on its panel, once per client id
    (an unknown panel is refused by ``store_gloss``: tests/ingest/test_gloss.py, tests/api/test_routes_qc.py)."""
    import uuid

    from sqlalchemy import create_engine, select
    from sqlalchemy.orm import Session

    from db.models import GlossReading, Panel

    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    from db.migrate import ensure_at_head

    ensure_at_head(url)
    engine = create_engine(url)
    with Session(engine) as s:
        panel = Panel(job="J-G", part="roof")
        s.add(panel)
        s.commit()
        panel_id = panel.id
    cid = str(uuid.uuid4())
    answers = []
    for _ in range(2):
        rc, out, err = run(
            capsys,
            "measure",
            "sim:gloss",
            "--store",
            url,
            "--panel",
            str(panel_id),
            "--client-id",
            cid,
            "--json",
        )
        assert rc == 0, err
        answers.append(json.loads(out))
    assert [a["stored"]["status"] for a in answers] == ["stored", "duplicate"]
    with Session(engine) as s:
        rows = s.scalars(select(GlossReading)).all()
    engine.dispose()
    assert len(rows) == 1 and str(rows[0].client_id) == cid and rows[0].panel_id == panel_id
    printed = answers[0]
    assert [rows[0].gloss_20_gu, rows[0].gloss_60_gu, rows[0].gloss_85_gu] == [
        printed["gloss_gu"][k] for k in ("20", "60", "85")
    ]
    assert rows[0].haze_hu == printed["haze_hu"] and rows[0].doi == printed["doi"]
