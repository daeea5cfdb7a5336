"""``/api/v1/booth`` with a stored formulation job's recipe on one side (predicted by the colorant model).

Over real HTTP (``station serve`` on a loopback port, the demo library): a closed-loop job is stored, then
the booth compares a stored measurement with its recipe; Lab per geometry and illuminant against
colour-science's computation from the colorant model's predicted spectra. In-process: a job without a
recipe is refused with 422 naming the field.
"""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import Any

import colour
import httpx
import numpy as np
import pytest

from station.formulate.colorants import default_database, predict_reflectance
from station.model.colorimetry import OBSERVER_10
from station.model.spectra import WAVELENGTHS, reflectance_from_lab
from tests.api.conftest import Api
from tests.serve_process import ServeStartError, serving

REPO = Path(__file__).resolve().parents[2]
V1 = "/api/v1"
ANGLES = [15.0, 45.0, 110.0]
#: A red metallic per geometry, Lab D65 / 10°.
RED = [[48.0, 42.0, 22.0], [30.0, 34.0, 16.0], [18.0, 24.0, 10.0]]
DESIGN = {"name": "red", "face": RED[0], "flop": RED[2], "travel_deg": 60.0, "gloss_gu": 85.0}


def _lab(refl: np.ndarray, illuminant: str) -> np.ndarray:
    """colour-science's Lab (ASTM E308, 10°) relative to the illuminant's own white."""
    cmfs = colour.MSDS_CMFS[OBSERVER_10]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11"}.get(illuminant, illuminant)]
    rows = []
    for r in refl:
        sd = colour.SpectralDistribution(dict(zip(WAVELENGTHS, r, strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308") / 100
        white = colour.sd_to_XYZ(colour.sd_ones(sd.shape), cmfs, ill, method="ASTM E308") / 100
        rows.append(colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white)))
    return np.asarray(rows)


def _measurement(spectra: np.ndarray) -> dict[str, Any]:
    return {
        "client_id": str(uuid.uuid4()),
        "instrument": {"serial": "SIM-BOOTH-1", "model": "MA6", "kind": "multiangle"},
        "panel": {"job": "J-RECIPE", "part": "door"},
        "operator": "ana",
        "measured_at": "2026-12-01T08:00:00+00:00",
        "geometries_deg": ANGLES,
        "lab": RED,
        "wavelengths_nm": WAVELENGTHS.tolist(),
        "spectra": spectra.tolist(),
    }


def test_booth_measurement_against_a_stored_recipe_over_http(tmp_path: Path) -> None:
    spectra = reflectance_from_lab(RED).round(6)
    try:
        with serving(tmp_path, cwd=REPO, start_timeout_s=120) as svc:
            auth = {"Authorization": f"Bearer {svc.token}"}
            with httpx.Client(base_url=svc.base + V1, timeout=120) as http:
                d = http.post("/designs", json={"name": "red", "design": DESIGN}, headers=auth)
                assert d.status_code == 201, d.text
                job = http.post("/formulation/closed-loop", json={"design_id": d.json()["id"]}, headers=auth)
                assert job.status_code == 201, job.text
                recipe_id = job.json()["recipe_id"]
                stored = http.get(f"/recipes/{recipe_id}", headers=auth).json()["recipe"]
                m = http.post("/measurements", json=_measurement(spectra), headers=auth)
                assert m.status_code == 201, m.text
                body = {
                    "standard_measurement_id": m.json()["id"],
                    "sample_recipe_id": recipe_id,
                    "illuminants": ["D65", "A", "F11"],
                }
                r = http.post("/booth", json=body, headers=auth)
                assert r.status_code == 200, r.text
                db = default_database()
                predicted = predict_reflectance(db.vector(stored), tuple(ANGLES), db)
                for ill in r.json()["illuminants"]:
                    rows = ill["per_geometry"]
                    assert [g["geometry"] for g in rows] == ["45as15", "45as45", "45as110"]
                    got = np.array([g["sample_lab"] for g in rows])
                    np.testing.assert_allclose(got, _lab(predicted, ill["name"]), atol=1e-6, rtol=0)
                    std = np.array([g["standard_lab"] for g in rows])
                    np.testing.assert_allclose(std, _lab(spectra, ill["name"]), atol=1e-6, rtol=0)
                # the recipe on the standard side, both sides recipes (15/45/110°)
                both = {"standard_recipe_id": recipe_id, "sample_recipe_id": recipe_id}
                r = http.post("/booth", json=both, headers=auth)
                assert r.status_code == 200, r.text
                assert all(g["dE00"] == 0.0 for i in r.json()["illuminants"] for g in i["per_geometry"])
                missing = http.post("/booth", json=body | {"sample_recipe_id": 999_999}, headers=auth)
                assert missing.status_code == 404 and "sample_recipe_id" in missing.text, missing.text
                two = http.post(
                    "/booth",
                    json=body | {"sample": {"geometries": ["45as15"], "spectra": [[0.5] * 31]}},
                    headers=auth,
                )
                assert two.status_code == 422 and "exactly one" in two.text, two.text
    except ServeStartError as exc:
        pytest.fail(str(exc))


def test_booth_refuses_a_job_without_a_usable_recipe(sqlite_api: Api) -> None:
    from sqlalchemy import select

    from db.models import DesignVersion, FormulationJob

    c = sqlite_api.client
    d = c.post(f"{V1}/designs", json={"name": "red", "design": DESIGN}, headers=sqlite_api.auth("stylist"))
    assert d.status_code == 201, d.text
    with c.app.state.sessions() as session:  # type: ignore[attr-defined]
        dv = session.scalars(select(DesignVersion).where(DesignVersion.design_id == d.json()["id"])).one()
        jobs = [
            FormulationJob(
                design_version_id=dv.id, state="failed", target={}, recipe={"candidates": [], "recipe": rc}
            )
            for rc in (None, {"unobtainium": 0.1})
        ]
        session.add_all(jobs)
        session.commit()
        ids = [j.id for j in jobs]
    spectra = {"geometries": ["45as15"], "spectra": [[0.5] * 31], "wavelengths_nm": WAVELENGTHS.tolist()}
    for job_id, words in zip(ids, ("no recipe", "unobtainium"), strict=True):
        r = c.post(
            f"{V1}/booth",
            json={"standard": spectra, "sample_recipe_id": job_id},
            headers=sqlite_api.auth("qa"),
        )
        assert r.status_code == 422 and "sample_recipe_id" in r.text and words in r.text, r.text
    r = c.post(
        f"{V1}/booth", json={"standard": spectra, "sample_recipe_id": 999_999}, headers=sqlite_api.auth("qa")
    )
    assert r.status_code == 404 and "sample_recipe_id" in r.text, r.text
