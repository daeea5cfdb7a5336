"""Instruments through the service with real simulator subprocesses (MA6 spectro + gloss meter on ptys)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import colour
import numpy as np
import pytest

from tests.api.conftest import Api, make_api

V1 = "/api/v1"


@pytest.fixture(scope="module")
def sim_api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Api]:
    tmp = tmp_path_factory.mktemp("sim")
    yield from make_api(f"sqlite:///{tmp / 'station.sqlite3'}", Path(tmp), simulators=("ma6", "gloss"))


def _ids(api: Api) -> dict[str, str]:
    insts = api.client.get(f"{V1}/instruments", headers=api.auth("technician")).json()
    return {i["kind"]: i["id"] for i in insts}


def test_simulators_are_attached(sim_api: Api) -> None:
    insts = sim_api.client.get(f"{V1}/instruments", headers=sim_api.auth("qa")).json()
    assert {i["kind"] for i in insts} == {"spectro", "gloss"}
    assert all(i["simulated"] for i in insts)


def test_measure_with_gloss_stores_lab_from_spectra(sim_api: Api) -> None:
    ids = _ids(sim_api)
    r = sim_api.client.post(
        f"{V1}/instruments/{ids['spectro']}/measure",
        params={"gloss_instrument_id": ids["gloss"]},
        json={},
        headers=sim_api.auth("technician"),
    )
    assert r.status_code == 201, r.text
    m = r.json()["measurement"]
    assert 0 < m["gloss_gu"] <= 100 and m["gloss_geometry_deg"] == 60
    # Lab recomputed independently with colour-science: D65, CIE 1964 10°, 400-700 nm / 10 nm
    shape = colour.SpectralShape(400, 700, 10)
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    for curve, lab in zip(m["spectra"], m["lab"], strict=True):
        sd = colour.SpectralDistribution(dict(zip(m["wavelengths_nm"], curve, strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, d65) / 100.0
        white = colour.sd_to_XYZ(colour.sd_ones(shape), cmfs, d65) / 100.0
        expected = colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white))
        np.testing.assert_allclose(lab, expected, atol=0.05)


def test_instrument_errors(sim_api: Api) -> None:
    ids = _ids(sim_api)
    c, tech = sim_api.client, sim_api.auth("technician")
    r = c.post(f"{V1}/instruments/{ids['spectro']}/measure", json={"illumination_deg": 15}, headers=tech)
    assert r.status_code == 422 and "one of [45]" in r.json()["detail"][0]["ctx"]["accepted"]
    assert c.post(f"{V1}/instruments/{ids['gloss']}/measure", json={}, headers=tech).status_code == 422
    assert (
        c.post(f"{V1}/instruments/{ids['spectro']}/measure", json={"panel_id": 777}, headers=tech).status_code
        == 404
    )
    assert (
        c.post(f"{V1}/instruments/connect", json={"address": "ma6@/dev/ttyUSB97"}, headers=tech).status_code
        == 404
    )
    cal = c.post(
        f"{V1}/instruments/{ids['gloss']}/calibrate", json={"reference": "black glass"}, headers=tech
    )
    assert cal.status_code == 200 and cal.json()["passed"] is True
    events = c.get(f"{V1}/audit", params={"entity": "calibration"}, headers=sim_api.auth("admin")).json()
    assert events["data"][0]["action"] == "instrument.calibrate"


def test_measure_with_a_client_id_is_idempotent(sim_api: Api) -> None:
    import uuid

    ids = _ids(sim_api)
    c, tech = sim_api.client, sim_api.auth("technician")
    url = f"{V1}/instruments/{ids['spectro']}/measure"

    def count() -> int:
        return c.get(f"{V1}/measurements", headers=sim_api.auth("qa")).json()["count"]

    before = count()
    cid = str(uuid.uuid4())
    first = c.post(url, json={"client_id": cid}, headers=tech)
    assert first.status_code == 201 and first.json()["status"] == "stored", first.text
    again = c.post(url, json={"client_id": cid}, headers=tech)  # a retry: nothing measured, nothing stored
    assert again.status_code == 200 and again.json()["status"] == "duplicate"
    assert again.json()["measurement"] == first.json()["measurement"]
    assert first.json()["measurement"]["client_id"] == cid == again.json()["client_id"]
    assert count() == before + 1
    # the Idempotency-Key header does the same (any key: a non-UUID key is hashed to one)
    keyed = [c.post(url, json={}, headers={**tech, "Idempotency-Key": "scan-0042"}) for _ in range(2)]
    assert [r.status_code for r in keyed] == [201, 200]
    assert keyed[0].json()["client_id"] == keyed[1].json()["client_id"]
    assert count() == before + 2
    clash = c.post(url, json={"client_id": cid}, headers={**tech, "Idempotency-Key": str(uuid.uuid4())})
    assert clash.status_code == 422 and "Idempotency-Key" in clash.text


def test_gloss_meter_alone_and_joined_stores_full_gloss_readings(sim_api: Api) -> None:
    ids = _ids(sim_api)
    c, tech, qa = sim_api.client, sim_api.auth("technician"), sim_api.auth("qa")
    panel = c.post(f"{V1}/panels", json={"job": "J-GL", "part": "hood"}, headers=tech).json()["id"]
    alone = c.post(
        f"{V1}/qc/gloss/measure", json={"instrument_id": ids["gloss"], "panel_id": panel}, headers=tech
    )
    assert alone.status_code == 201, alone.text
    g = alone.json()
    assert g["panel_id"] == panel and g["measurement_id"] is None
    assert (
        all(0 <= g[k] <= 2000 for k in ("gloss_20_gu", "gloss_60_gu", "gloss_85_gu")) and 0 <= g["doi"] <= 100
    )
    r = c.post(
        f"{V1}/instruments/{ids['spectro']}/measure",
        params={"gloss_instrument_id": ids["gloss"]},
        json={"panel_id": panel},
        headers=tech,
    )
    assert r.status_code == 201, r.text
    m, gid = r.json()["measurement"], r.json()["gloss_reading_id"]
    joined = c.get(f"{V1}/qc/gloss/{gid}", headers=qa).json()
    assert joined["measurement_id"] == m["id"] and joined["panel_id"] == panel
    assert joined["gloss_60_gu"] == m["gloss_gu"]  # the measurement's 60° value is the same reading's
    view = c.get(f"{V1}/qc/measurements/{m['id']}", headers=qa).json()
    assert view["gloss"]["id"] == gid  # the linked reading wins over the gloss-only one taken just before
    wrong = c.post(f"{V1}/qc/gloss/measure", json={"instrument_id": ids["spectro"]}, headers=tech)
    assert wrong.status_code == 422 and wrong.json()["detail"][0]["loc"][-1] == "instrument_id"
    missing = c.post(f"{V1}/qc/gloss/measure", json={"instrument_id": "gloss-none"}, headers=tech)
    assert missing.status_code == 404
