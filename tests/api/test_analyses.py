"""Seam QA of two stored measurements through the service (wiring of station.analysis.seam_qa)."""

from __future__ import annotations

import numpy as np
import pytest

from station.analysis import seam_qa
from station.model import AspecularMeasurements
from tests.api.conftest import Api
from tests.ingest._readings import make_reading

V1 = "/api/v1"
# a blue metallic (fender) and a slightly lighter batch of it (bumper), Lab at 15/45/110° (D65/10°)
FENDER = [[62.0, -4.0, -38.0], [38.0, -1.0, -28.0], [22.0, 1.0, -18.0]]
BUMPER = [[63.5, -4.2, -37.0], [38.8, -1.1, -27.5], [22.4, 1.0, -17.6]]


def _measure(api: Api, i: int, lab: list[list[float]], part: str) -> int:
    panel = api.client.post(
        f"{V1}/panels", json={"job": "J-S", "part": part}, headers=api.auth("technician")
    ).json()
    body = make_reading(41, i, panel_id=panel["id"]).model_dump(mode="json") | {
        "lab": lab,
        "spectra": None,
        "wavelengths_nm": None,
        "gloss_gu": 90.0,
    }
    r = api.client.post(f"{V1}/measurements", json=body, headers=api.auth("technician"))
    assert r.status_code == 201, r.text
    return r.json()["id"]


def test_seam_qa_of_two_measured_panels(sqlite_api: Api) -> None:
    a, b = _measure(sqlite_api, 0, FENDER, "fender"), _measure(sqlite_api, 1, BUMPER, "bumper")
    req = {"measurement_a": a, "measurement_b": b, "beta_deg": 6.0, "tolerance": 2.3, "method": "cie76"}
    r = sqlite_api.client.post(f"{V1}/analyses/seam", json=req, headers=sqlite_api.auth("qa"))
    assert r.status_code == 201, r.text
    stored = r.json()
    direct = seam_qa(
        AspecularMeasurements((15.0, 45.0, 110.0), np.array(FENDER), 90.0),
        AspecularMeasurements((15.0, 45.0, 110.0), np.array(BUMPER), 90.0),
        6.0,
        tolerance=2.3,
    )
    assert stored["kind"] == "seam_qa" and stored["inputs"].items() >= req.items()
    assert stored["result"]["passed"] is direct.passed
    assert stored["result"]["seam_de_max"] == pytest.approx(max(direct.seam_de), rel=1e-9)
    assert stored["result"]["corrected_paint"]["face"] == pytest.approx(list(direct.correction.paint.face))
    from station.formulate.gamut import colorant_gamut

    gamut = stored["result"]["corrected_colorant_gamut"]  # flagged at the QA step against the colorants
    assert gamut["inside_colorant_gamut"] == colorant_gamut(direct.correction.paint).inside
    assert gamut["inside_colorant_gamut"] == (gamut["mean_de"] <= gamut["tolerance"])
    got = sqlite_api.client.get(f"{V1}/analyses/{stored['id']}", headers=sqlite_api.auth("stylist")).json()
    assert got == stored
    listed = sqlite_api.client.get(
        f"{V1}/analyses", params={"kind": "seam_qa"}, headers=sqlite_api.auth("chemist")
    )
    assert listed.json()["count"] == 1
    events = sqlite_api.client.get(
        f"{V1}/audit", params={"entity": "analysis"}, headers=sqlite_api.auth("admin")
    )
    assert events.json()["data"][0]["action"] == "analysis.seam_qa"


def test_seam_qa_refusals(sqlite_api: Api) -> None:
    a = _measure(sqlite_api, 0, FENDER, "fender")
    qa = sqlite_api.auth("qa")
    r = sqlite_api.client.post(
        f"{V1}/analyses/seam", json={"measurement_a": a, "measurement_b": 999, "beta_deg": 5.0}, headers=qa
    )
    assert r.status_code == 404
    r = sqlite_api.client.post(
        f"{V1}/analyses/seam", json={"measurement_a": a, "measurement_b": a, "beta_deg": 0.0}, headers=qa
    )
    assert r.status_code == 422
    assert r.json()["detail"][0]["ctx"]["accepted"] == "0 < |β| <= 45 degrees"
