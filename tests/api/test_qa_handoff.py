"""QA → chemist over real HTTP (a ``station serve`` process): QA's corrected paint is stored as a design the
chemist lists and formulates; QA may judge it with the compute-only formulation routes; storing a job
stays the chemist's, and the 403 says which scope is missing and who holds it."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest

from tests.serve_process import serving

REPO = Path(__file__).resolve().parents[2]
#: Both panels as scans without a paired gloss meter: gloss not measured (null); B′ takes A's gloss state.
PAINT_A = {"face": [62.0, -4.0, -38.0], "flop": [24.0, 1.0, -20.0], "travel_deg": 70.0, "gloss_gu": None}
PAINT_B = {"face": [64.0, -4.5, -36.0], "flop": [25.0, 1.0, -19.0], "travel_deg": 72.0, "gloss_gu": None}

pytestmark = pytest.mark.slow


def test_qa_corrected_paint_reaches_the_chemist_as_a_design(tmp_path: Path) -> None:
    with serving(tmp_path / "service", cwd=REPO, start_timeout_s=180) as svc:
        with httpx.Client(base_url=f"{svc.base}/api/v1", timeout=60.0) as c:
            admin = {"Authorization": f"Bearer {svc.token}"}
            auth = {}
            for role in ("qa", "chemist"):
                r = c.post("/users", json={"name": f"{role}-1", "role": role}, headers=admin)
                assert r.status_code == 201, r.text
                auth[role] = {"Authorization": f"Bearer {r.json()['token']}"}

            r = c.post(
                "/analyses/seam",
                json={"design_a": PAINT_A, "design_b": PAINT_B, "beta_deg": 6.0},
                headers=auth["qa"],
            )
            assert r.status_code == 201, r.text
            corrected = r.json()["result"]["corrected_paint"]
            assert corrected["gloss_gu"] is None  # not measured stays not measured
            r = c.post(
                "/designs",
                json={
                    "name": "door B corrected",
                    "design": corrected,
                    "note": f"seam analysis {r.json()['id']}",
                },
                headers=auth["qa"],
            )
            assert r.status_code == 201, r.text
            design_id = r.json()["id"]

            listed = c.get("/designs", headers=auth["chemist"]).json()["data"]
            assert [d["name"] for d in listed if d["id"] == design_id] == ["door B corrected"]
            for role in ("chemist", "qa"):  # QA may see whether it is formulable; nothing is stored
                r = c.post("/formulation/formulate", json={"design_id": design_id}, headers=auth[role])
                assert r.status_code == 200, (role, r.text)
                assert "matting_silica" not in r.json()["recipe"]  # no matting for a gloss nobody measured

            r = c.post("/formulation/closed-loop", json={"design_id": design_id}, headers=auth["qa"])
            assert r.status_code == 403
            assert r.json()["detail"] == "role qa lacks scope recipes:write (held by: chemist, admin)"
