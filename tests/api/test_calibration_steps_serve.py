"""Calibration step by step over real HTTP (``station serve`` with an MA6 and a gloss meter simulated): each
step's prompt is readable before it runs, the instrument's own state between steps is the protocol's (a
zero leaves it needing its white tile), the records are stored once the last step passes, and a cancelled
session, an ended one and bad input answer with the status and the field named."""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from station.scan.calibration import STEP_PROMPTS
from tests.serve_process import serving

REPO = Path(__file__).resolve().parents[2]
V1 = "/api/v1"
Client = tuple[httpx.Client, dict[str, str], dict[str, str]]


@pytest.fixture(scope="module")
def svc(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Client]:
    data = tmp_path_factory.mktemp("cal-http")
    with serving(data, "--no-demo-library", "--simulators", "ma6,gloss", cwd=REPO, start_timeout_s=120) as s:
        auth = {"Authorization": f"Bearer {s.token}"}
        with httpx.Client(base_url=s.base, timeout=120) as http:
            insts = http.get(f"{V1}/instruments", headers=auth).json()
            yield http, auth, {i["kind"]: i["id"] for i in insts}


def _needed(c: Client, kind: str) -> str | None:
    http, auth, ids = c
    insts = {i["id"]: i for i in http.get(f"{V1}/instruments", headers=auth).json()}
    return insts[ids[kind]]["calibration_needed"]


def test_step_by_step_with_prompts_and_state_between(svc: Client) -> None:
    http, auth, ids = svc
    body = {"instrument_id": ids["spectro"], "gloss_instrument_id": ids["gloss"], "reference": "W-17"}
    r = http.post(f"{V1}/instruments/calibrations", json=body, headers=auth)
    assert r.status_code == 201, r.text
    session = r.json()
    sid = session["id"]
    order = [(s["device"], s["step"]) for s in session["steps"]]
    spectro, gloss = ids["spectro"], ids["gloss"]
    assert order == [(spectro, "zero"), (spectro, "white"), (spectro, "verify"), (gloss, "gloss")]
    assert session["state"] == "waiting" and session["records"] == []
    for i, (device, step) in enumerate(order, start=1):
        now = http.get(f"{V1}/instruments/calibrations/{sid}", headers=auth).json()
        nxt = now["next"]
        assert (nxt["index"], nxt["device"], nxt["step"]) == (i, device, step)
        assert nxt["title"] == STEP_PROMPTS[step][0]  # black trap, white tile, verification tile, standard
        assert nxt["prompt"].startswith(f"Step {i} of 4") and device in nxt["prompt"]
        assert [s["status"] for s in now["steps"]] == ["passed"] * (i - 1) + ["pending"] * (5 - i)
        r = http.post(f"{V1}/instruments/calibrations/{sid}/step", headers=auth)
        assert r.status_code == 200, r.text
        if step == "zero":
            # the protocol: a zero invalidates the white calibration on the instrument itself
            assert r.json()["state"] == "waiting" and _needed(svc, "spectro") == "white"
    done = r.json()
    assert done["state"] == "calibrated" and done["calibrated"] is True and done["next"] is None
    steps = {rec["steps"][-1]: rec for rec in done["records"]}
    assert steps["verify"]["steps"] == ["zero", "white", "verify"] and steps["gloss"]["steps"] == ["gloss"]
    assert all(rec["passed"] for rec in done["records"])
    assert _needed(svc, "spectro") is None
    again = http.post(f"{V1}/instruments/calibrations/{sid}/step", headers=auth)
    assert again.status_code == 409 and "calibrated" in again.json()["detail"]
    events = http.get(f"{V1}/audit", params={"entity": "calibration"}, headers=auth).json()["data"]
    audited = {str(e["entity_id"]) for e in events if e["action"] == "instrument.calibrate"}
    assert audited >= {str(rec["record_id"]) for rec in done["records"]}


def test_cancel_after_the_zero_leaves_the_instrument_needing_calibration(svc: Client) -> None:
    http, auth, ids = svc
    r = http.post(f"{V1}/instruments/calibrations", json={"instrument_id": ids["spectro"]}, headers=auth)
    sid = r.json()["id"]
    assert [s["step"] for s in r.json()["steps"]] == ["zero", "white", "verify"]
    assert http.post(f"{V1}/instruments/calibrations/{sid}/step", headers=auth).status_code == 200
    r = http.post(f"{V1}/instruments/calibrations/{sid}/cancel", headers=auth)
    assert r.status_code == 200 and r.json()["state"] == "cancelled" and r.json()["next"] is None
    assert _needed(svc, "spectro") == "white"
    assert http.post(f"{V1}/instruments/calibrations/{sid}/step", headers=auth).status_code == 409
    assert http.post(f"{V1}/instruments/calibrations/{sid}/cancel", headers=auth).status_code == 409


@pytest.mark.parametrize(
    ("body", "status", "loc"),
    [
        ({"instrument_id": "GLOSS"}, 422, "instrument_id"),  # the gloss meter in the spectro's place
        ({"instrument_id": "SPECTRO", "gloss_instrument_id": "SPECTRO"}, 422, "gloss_instrument_id"),
        ({"instrument_id": "Bad Id"}, 422, "instrument_id"),
        ({"instrument_id": "SPECTRO", "extra": 1}, 422, "extra"),
        ({"instrument_id": "ma6-nothing"}, 404, None),
    ],
)
def test_bad_starts(svc: Client, body: dict[str, object], status: int, loc: str | None) -> None:
    http, auth, ids = svc
    named = {"GLOSS": ids["gloss"], "SPECTRO": ids["spectro"]}
    body = {k: named.get(v, v) if isinstance(v, str) else v for k, v in body.items()}
    r = http.post(f"{V1}/instruments/calibrations", json=body, headers=auth)
    assert r.status_code == status, r.text
    if loc is not None:
        assert r.json()["detail"][0]["loc"][-1] == loc


def test_unknown_session_is_404(svc: Client) -> None:
    http, auth, _ids = svc
    r = http.get(f"{V1}/instruments/calibrations/{uuid.uuid4()}", headers=auth)
    assert r.status_code == 404
    r = http.get(f"{V1}/instruments/calibrations/not-a-uuid", headers=auth)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][-1] == "session_id"


def test_a_failing_white_tile_ends_the_session_naming_the_step() -> None:
    """The session behind the routes, on a real MA3 simulator whose white calibration fails: the session
    reads ``failed`` naming step 2 (white tile), stores nothing, and refuses another step (409)."""
    from station.api.calibration_sessions import CalibrationSessions
    from station.api.errors import ConflictError
    from station.api.schemas.instruments import CalibrationPublic
    from station.drivers import CalibrationResult
    from station.scan import open_device

    stored: list[str] = []

    def store(name: str, _result: CalibrationResult, _reference: str) -> CalibrationPublic:
        stored.append(name)  # nothing passed every step: never called
        raise AssertionError(name)

    sessions = CalibrationSessions()
    with open_device("sim:ma3", faults=["cal-failure@WC"]) as device:
        first = sessions.start([device], "W-17")
        sid = first.id
        assert sessions.step(sid, store).state == "waiting"
        failed = sessions.step(sid, store)
        assert failed.state == "failed" and failed.next is None and not failed.calibrated
        assert "step 2 of 3 (white tile)" in (failed.error or "")
        assert [s.status for s in failed.steps] == ["passed", "failed", "pending"]
        with pytest.raises(ConflictError):
            sessions.step(sid, store)
        assert device.instrument.status().needed == "white"
    assert stored == [] and sessions.read(sid).state == "failed"
