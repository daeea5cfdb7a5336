"""``/api/v1/qc``: gloss readings stored and paired with colour, checks against a standard, bad input named."""

from __future__ import annotations

import datetime as dt
import math
import uuid

import pytest

from tests.api.conftest import Api
from tests.ingest._readings import T0, make_reading

V1 = "/api/v1"
STD = [[50.0, 0.0, 0.0], [40.0, 10.0, -10.0], [30.0, 5.0, 5.0]]
SMP = [[51.0, 0.0, 0.0], [40.0, 11.2, -11.2], [33.0, 9.0, 5.0]]  # ΔE*ab 1, √2.88, 5 (hand)
ANGLES = [15.0, 45.0, 110.0]


def _panel(api: Api, job: str = "J-QC", part: str = "door") -> int:
    r = api.client.post(f"{V1}/panels", json={"job": job, "part": part}, headers=api.auth("technician"))
    assert r.status_code == 201, r.text
    return r.json()["id"]


def _colour(api: Api, panel_id: int, lab: list[list[float]], minutes: float = 0.0) -> int:
    body = make_reading(21, int(minutes * 60) + len(lab), panel_id=panel_id).model_dump(mode="json")
    body |= {
        "geometries_deg": ANGLES[: len(lab)],
        "lab": lab,
        "spectra": None,
        "wavelengths_nm": None,
        "measured_at": (T0 + dt.timedelta(minutes=minutes)).isoformat(),
        "client_id": str(uuid.uuid4()),
    }
    r = api.client.post(f"{V1}/measurements", json=body, headers=api.auth("technician"))
    assert r.status_code == 201, r.text
    return r.json()["id"]


def _gloss(panel_id: int | None, minutes: float, g60: float, **kw: object) -> dict:
    body: dict[str, object] = {
        "client_id": str(uuid.uuid4()),
        "instrument": {"serial": "GL-1", "model": "gloss meter", "kind": "gloss"},
        "operator": "ana",
        "measured_at": (T0 + dt.timedelta(minutes=minutes)).isoformat(),
        "gloss_20_gu": g60 - 10.0,
        "gloss_60_gu": g60,
        "gloss_85_gu": 95.0,
        "haze_hu": 10.0,
        "doi": 85.0,
    }
    if panel_id is not None:
        body["panel_id"] = panel_id
    return body | kw


def test_gloss_only_reading_stored_once_and_paired_with_colour(api: Api) -> None:
    c, tech, qa = api.client, api.auth("technician"), api.auth("qa")
    panel = _panel(api)
    m_near = _colour(api, panel, STD, minutes=0)
    m_far = _colour(api, panel, SMP, minutes=120)
    body = _gloss(panel, 3, 90.5)
    first = c.post(f"{V1}/qc/gloss", json=body, headers=tech)
    again = c.post(f"{V1}/qc/gloss", json=body, headers=tech)
    assert (first.status_code, again.status_code) == (201, 200), first.text
    g = first.json()
    assert again.json()["id"] == g["id"]
    assert (g["gloss_20_gu"], g["gloss_60_gu"], g["gloss_85_gu"], g["haze_hu"], g["doi"]) == (
        80.5,
        90.5,
        95.0,
        10.0,
        85.0,
    )
    assert g["panel_id"] == panel and g["measurement_id"] is None
    listed = c.get(f"{V1}/qc/measurements", params={"job": "J-QC", "part": "door"}, headers=qa).json()
    assert listed["count"] == 2
    by_id = {m["id"]: m for m in listed["data"]}
    assert by_id[m_near]["gloss"]["id"] == g["id"]  # 3 min apart: paired
    assert by_id[m_far]["gloss"] is None  # 117 min apart: beyond the pairing window
    assert by_id[m_near]["job"] == "J-QC" and by_id[m_near]["part"] == "door"
    linked = c.post(f"{V1}/qc/gloss", json=_gloss(None, 200, 70.0, measurement_id=m_far), headers=tech).json()
    assert linked["panel_id"] == panel and linked["measurement_id"] == m_far
    one = c.get(f"{V1}/qc/measurements/{m_far}", headers=qa).json()
    assert one["gloss"]["id"] == linked["id"] and one["gloss"]["gloss_60_gu"] == 70.0
    gl = c.get(f"{V1}/qc/gloss", params={"panel_id": panel}, headers=qa).json()
    assert gl["count"] == 2 and [r["id"] for r in gl["data"]] == [linked["id"], g["id"]]  # newest first
    assert c.get(f"{V1}/qc/gloss/{g['id']}", headers=qa).json()["gloss_60_gu"] == 90.5
    assert c.get(f"{V1}/qc/gloss/999999", headers=qa).status_code == 404


def test_gloss_refusals_name_the_field_and_store_nothing(api: Api) -> None:
    c, tech = api.client, api.auth("technician")
    panel = _panel(api)
    cases = [
        (_gloss(panel, 0, 90.0, gloss_20_gu=None, gloss_60_gu=None, gloss_85_gu=None), 422, "gloss_60_gu"),
        (_gloss(panel, 0, 90.0, gloss_60_gu=-2.0), 422, "gloss_60_gu"),
        (_gloss(panel, 0, 90.0, doi=150.0), 422, "doi"),
        (_gloss(panel, 0, 90.0, gloss_85_gu="95"), 422, "gloss_85_gu"),
        (_gloss(999_999, 0, 90.0), 404, "panel_id 999999"),
        (_gloss(None, 0, 90.0, measurement_id=999_999), 404, "measurement_id 999999"),
    ]
    for body, code, words in cases:
        r = c.post(f"{V1}/qc/gloss", json=body, headers=tech)
        assert r.status_code == code, (words, r.text)
        assert words in r.text
    assert (
        c.post(f"{V1}/qc/gloss", json=_gloss(panel, 0, 90.0), headers=api.auth("stylist")).status_code == 403
    )
    assert c.get(f"{V1}/qc/gloss", headers=tech).json()["count"] == 0


def _de76(a: list[float], b: list[float]) -> float:
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b, strict=True)))


def test_check_inline_and_stored_against_hand_values(api: Api) -> None:
    c, qa = api.client, api.auth("qa")
    panel = _panel(api)
    std_id = _colour(api, panel, STD)
    body = {
        "standard": {"measurement_id": std_id},
        "sample": {"geometries_deg": ANGLES, "lab": SMP},
        "formula": "cie76",
        "de_limit": 2.0,
    }
    r = c.post(f"{V1}/qc/check", json=body, headers=qa)
    assert r.status_code == 200, r.text
    out = r.json()
    de = [_de76(s, p) for s, p in zip(STD, SMP, strict=True)]
    assert [g["dE"] for g in out["per_geometry"]] == pytest.approx(de, abs=1e-9)
    # limit 2, warn band from 0.8 × 2 = 1.6: 1 passes, √2.88 = 1.697 warns, 5 fails
    assert [g["verdict"] for g in out["per_geometry"]] == ["pass", "warn", "fail"]
    assert out["verdict"] == "fail" and out["worst_geometry"] == "45as110"
    assert out["mean_de"] == pytest.approx(sum(de) / 3) and out["max_de"] == pytest.approx(5.0)
    assert out["per_geometry"][2]["dL"] == pytest.approx(3.0) and out["standard_measurement_id"] == std_id
    assert "110" in out["reason"]
    # a sample at two of the three angles is judged on those two only
    two = body | {"sample": {"geometries_deg": ANGLES[:2], "lab": SMP[:2]}}
    out2 = c.post(f"{V1}/qc/check", json=two, headers=api.auth("technician")).json()
    assert [g["aspecular_deg"] for g in out2["per_geometry"]] == [15.0, 45.0] and out2["verdict"] == "warn"


def test_check_refusals_name_the_field(api: Api) -> None:
    c, qa = api.client, api.auth("qa")
    good = {
        "standard": {"geometries_deg": ANGLES, "lab": STD},
        "sample": {"geometries_deg": ANGLES, "lab": SMP},
    }
    cases = [
        (good | {"formula": "cmc"}, 422, "formula"),
        (good | {"de_limit": 0}, 422, "de_limit"),
        (
            good | {"sample": {"measurement_id": 1, "lab": SMP, "geometries_deg": ANGLES}},
            422,
            "measurement_id",
        ),
        (good | {"sample": {"geometries_deg": ANGLES, "lab": SMP[:2]}}, 422, "lab"),
        (good | {"sample": {"geometries_deg": [25.0], "lab": [SMP[0]]}}, 422, "sample.geometries_deg"),
        (good | {"sample": {"measurement_id": 999_999}}, 404, "sample.measurement_id"),
        (
            good | {"tolerance": {"geometries": [{"geometry": "45as15", "de": 1}], "bogus": 1}},
            422,
            "tolerance.bogus",
        ),
        (good | {"tolerance": {"geometries": [{"geometry": "45as15", "de": 1}]}}, 422, "angles"),
        (good | {"tolerance": {"geometries": []}, "formula": "cie76"}, 422, "tolerance"),
        (good | {"formula": "audi2000"}, 422, "audi2000"),
    ]
    for body, code, words in cases:
        r = c.post(f"{V1}/qc/check", json=body, headers=qa)
        assert r.status_code == code, (words, r.text)
        assert words in r.text, (words, r.text)
