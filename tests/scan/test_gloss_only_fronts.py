"""A gloss-only reading, and a gloss meter paired with a spectrophotometer, on the CLI and the service.

Both fronts scan through ``station.scan``: a gloss meter alone gives a gloss reading of its own
(``gloss_readings``) on the panel named, and no colour measurement; a paired meter's 60° gloss goes into
the colour measurement and its whole reading becomes a gloss reading naming that measurement. The
simulated panel's 60° gloss is set independently (a design file's ``gloss_gu``, or the gloss simulator's
default panel of 88 GU), so the stored value is checked against it within the simulator's noise. The
viewer's side is tests/ui/test_journey_technician.py (clicks on the instruments screen).
"""

from __future__ import annotations

import json
import uuid
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from sqlalchemy import create_engine, select
from sqlalchemy.orm import Session

from db.migrate import ensure_at_head
from db.models import GlossReading, Measurement, Panel
from station.model import FaceFlopTravelGloss
from station.model.design_io import save_design
from tests.serve_process import ServeProcess, ServeStartError
from tests.user_cli import run_station

pytestmark = pytest.mark.slow

V1 = "/api/v1"
SIM_DEFAULT_GLOSS_GU = 88.0  # simulators/gloss.py: the default panel's 60° gloss
NOISE_GU = 2.0  # the simulated meter's noise (0.1 GU) and linearity error, with room


def _rows(url: str) -> tuple[list[GlossReading], list[Measurement], dict[int, Panel]]:
    engine = create_engine(url)
    try:
        with Session(engine) as s:
            gloss = list(s.scalars(select(GlossReading).order_by(GlossReading.id)))
            colour = list(s.scalars(select(Measurement).order_by(Measurement.id)))
            panels = {p.id: p for p in s.scalars(select(Panel))}
            s.expunge_all()
    finally:
        engine.dispose()
    return gloss, colour, panels


def _panel(url: str, job: str) -> int:
    ensure_at_head(url)
    engine = create_engine(url)
    try:
        with Session(engine) as s:
            panel = Panel(job=job, part="roof")
            s.add(panel)
            s.commit()
            return panel.id
    finally:
        engine.dispose()


def test_cli_stores_a_gloss_meter_alone_as_a_gloss_reading_of_the_panel(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    panel_id = _panel(url, "J-CLI-G")
    design = tmp_path / "panel.json"
    save_design(FaceFlopTravelGloss((60.0, 0.0, 0.0), (30.0, 0.0, 0.0), 60.0, 70.0), design)
    cid = str(uuid.uuid4())
    args = ("measure", "sim:gloss", "--design", str(design), "--store", url, "--panel", str(panel_id))
    first = run_station(tmp_path, *args, "--client-id", cid, "--json")
    assert first.returncode == 0, first.stderr
    printed = json.loads(first.stdout)
    again = run_station(tmp_path, *args, "--client-id", cid, "--json")  # a retry: nothing measured again
    assert again.returncode == 0, again.stderr
    assert [printed["stored"]["status"], json.loads(again.stdout)["stored"]["status"]] == [
        "stored",
        "duplicate",
    ]
    gloss, colour, _panels = _rows(url)
    assert colour == [] and len(gloss) == 1
    row = gloss[0]
    assert str(row.client_id) == cid and row.panel_id == panel_id and row.measurement_id is None
    assert row.id == printed["stored"]["gloss_reading_id"]
    assert row.gloss_60_gu == pytest.approx(70.0, abs=NOISE_GU)  # the design's gloss, not the code's
    assert [row.gloss_20_gu, row.gloss_60_gu, row.gloss_85_gu] == [
        printed["gloss_gu"][k] for k in ("20", "60", "85")
    ]


def test_cli_pairs_a_gloss_meter_with_the_colour_reading(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    r = run_station(tmp_path, "measure", "sim:ma6", "--gloss", "sim:gloss", "--store", url, "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    gloss, colour, _panels = _rows(url)
    assert len(colour) == 1 and len(gloss) == 1
    assert (
        colour[0].id == out["stored"]["measurement_id"] and gloss[0].id == out["stored"]["gloss_reading_id"]
    )
    assert gloss[0].measurement_id == colour[0].id  # the gloss reading names the measurement taken with it
    assert colour[0].gloss_gu == gloss[0].gloss_60_gu == out["gloss_gu"]
    assert colour[0].gloss_gu == pytest.approx(SIM_DEFAULT_GLOSS_GU, abs=NOISE_GU)
    bad = run_station(tmp_path, "measure", "sim:ma6", "--gloss", "sim:ma3")
    assert bad.returncode == 2 and "--gloss" in bad.stderr and "gloss meter" in bad.stderr


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ServeProcess, dict[str, str], str]]:
    tmp = tmp_path_factory.mktemp("scan-serve")
    url = f"sqlite:///{tmp / 'station.sqlite3'}"
    svc = ServeProcess(tmp / "data", ("--no-demo-library", "--simulators", "ma6,gloss", "--database", url))
    try:
        svc.start()
    except ServeStartError as exc:
        pytest.fail(str(exc))
    try:
        admin = {"Authorization": f"Bearer {svc.token}"}
        r = httpx.post(
            f"{svc.base}{V1}/users", json={"name": "tech", "role": "technician"}, headers=admin, timeout=30
        )
        assert r.status_code == 201, r.text
        yield svc, {"Authorization": f"Bearer {r.json()['token']}"}, url
    finally:
        svc.stop()


def _ids(svc: ServeProcess, tech: dict[str, str]) -> dict[str, str]:
    insts = httpx.get(f"{svc.base}{V1}/instruments", headers=tech, timeout=30).json()
    return {i["kind"]: i["id"] for i in insts}


def test_service_stores_a_gloss_meter_alone_as_a_gloss_reading_of_the_panel(served) -> None:
    svc, tech, url = served
    panel = httpx.post(
        f"{svc.base}{V1}/panels", json={"job": "J-API-G", "part": "roof"}, headers=tech, timeout=30
    )
    assert panel.status_code == 201, panel.text
    panel_id = panel.json()["id"]
    ids = _ids(svc, tech)
    r = httpx.post(
        f"{svc.base}{V1}/qc/gloss/measure",
        json={"instrument_id": ids["gloss"], "panel_id": panel_id},
        headers=tech,
        timeout=60,
    )
    assert r.status_code == 201, r.text
    gloss, colour, _panels = _rows(url)
    mine = [g for g in gloss if g.panel_id == panel_id]
    assert [g.id for g in mine] == [r.json()["id"]] and mine[0].measurement_id is None
    assert mine[0].gloss_60_gu == pytest.approx(SIM_DEFAULT_GLOSS_GU, abs=NOISE_GU)
    assert [m for m in colour if m.panel_id == panel_id] == []  # no colour measurement made of it


def test_service_pairs_a_gloss_meter_with_the_colour_reading(served) -> None:
    svc, tech, url = served
    ids = _ids(svc, tech)
    r = httpx.post(
        f"{svc.base}{V1}/instruments/{ids['spectro']}/measure",
        params={"gloss_instrument_id": ids["gloss"]},
        json={},
        headers=tech,
        timeout=60,
    )
    assert r.status_code == 201, r.text
    body = r.json()
    gloss, colour, _panels = _rows(url)
    row = next(g for g in gloss if g.id == body["gloss_reading_id"])
    m = next(c for c in colour if c.id == body["measurement"]["id"])
    assert row.measurement_id == m.id and m.gloss_gu == row.gloss_60_gu
    assert m.gloss_gu == pytest.approx(SIM_DEFAULT_GLOSS_GU, abs=NOISE_GU)
    # a retry under the same key measures nothing again and adds no gloss reading
    key = {"Idempotency-Key": "scan-paired-1", **tech}
    url_m = f"{svc.base}{V1}/instruments/{ids['spectro']}/measure"
    q = {"gloss_instrument_id": ids["gloss"]}
    codes = [httpx.post(url_m, params=q, json={}, headers=key, timeout=60).status_code for _ in range(2)]
    assert codes == [201, 200]
    after, _colour, _p = _rows(url)
    assert len(after) == len(gloss) + 1
