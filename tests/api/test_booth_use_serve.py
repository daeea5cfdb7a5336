"""The booth where the chemist and QA use it, over real HTTP (``station serve`` on a loopback port):
formulation ranked by metamerism index, QC illuminant rows (check, summary, PDF report) and the seam
analysis under an illuminant, each with its 422 naming the field.

The metameric pair (equal under D65, different under A) is stored as two measurements with spectra;
the service's indices are checked against colour-science's computation from the same spectra.
"""

from __future__ import annotations

import datetime as dt
import uuid
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from station.model.spectra import WAVELENGTHS, reflectance_to_lab
from tests.qc.test_illuminant_rows import _mi_cs, _pair
from tests.serve_process import ServeStartError, serving

REPO = Path(__file__).resolve().parents[2]
V1 = "/api/v1"
ANGLES = [15.0, 45.0, 110.0]


def _post_reading(
    http: httpx.Client, auth: dict[str, str], spectra: np.ndarray, part: str, day: int, notes: str
) -> int:
    """Store one reading on the panel named by (job, part, *notes*): another *notes*, another panel."""
    body: dict[str, Any] = {
        "client_id": str(uuid.uuid4()),
        "instrument": {"serial": "SIM-BOOTH-1", "model": "MA6", "kind": "multiangle"},
        "panel": {"job": "J-BOOTH", "part": part, "notes": notes},
        "operator": "ana",
        "measured_at": (dt.datetime(2026, 12, 1, 8, tzinfo=dt.UTC) + dt.timedelta(days=day)).isoformat(),
        "geometries_deg": ANGLES,
        "lab": reflectance_to_lab(spectra).round(6).tolist(),
        "wavelengths_nm": WAVELENGTHS.tolist(),
        "spectra": spectra.tolist(),
        "gloss_gu": 88.0,
    }
    r = http.post(f"{V1}/measurements", json=body, headers=auth)
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


def _loc(r: httpx.Response) -> list[str]:
    assert r.status_code == 422, r.text
    return [str(x) for x in r.json()["detail"][0]["loc"]]


def test_booth_use_over_http(tmp_path: Path) -> None:
    std, smp = _pair()
    mi_a = _mi_cs(std, smp, "A")
    try:
        with serving(tmp_path, cwd=REPO, start_timeout_s=120) as svc:
            auth = {"Authorization": f"Bearer {svc.token}"}
            with httpx.Client(base_url=svc.base, timeout=120) as http:
                # formulation ranked by metamerism index
                design = {"lab": [[60.0, 10.0, -30.0], [45.0, 8.0, -25.0], [30.0, 5.0, -18.0]]}
                r = http.post(
                    f"{V1}/formulation/formulate",
                    json=design | {"illuminants": ["A", "F11"], "candidates": 3},
                    headers=auth,
                )
                assert r.status_code == 200, r.text
                ranking = r.json()["metamerism_ranking"]
                assert ranking["illuminants"] == ["A", "F11"]
                ranks = ranking["candidates"]
                assert [c["rank"] for c in ranks] == list(range(1, len(ranks) + 1))
                ok = [round(c["worst_index"], 2) for c in ranks if c["formulable"]]
                assert ok == sorted(ok)
                bad = http.post(
                    f"{V1}/formulation/formulate", json=design | {"illuminants": ["A", "Q7"]}, headers=auth
                )
                assert _loc(bad)[-1] == "illuminants[1]"

                # QC: a metameric pair stored with spectra, judged with illuminant rows; the trial on a
                # panel of its own (a standard's repeats, same panel and instrument, are no samples)
                std_id = _post_reading(http, auth, std, "door", 0, "standard panel")
                smp_id = _post_reading(http, auth, smp, "door", 1, "trial panel")
                check = {
                    "standard": {"measurement_id": std_id},
                    "sample": {"measurement_id": smp_id},
                    "formula": "cie2000",
                }
                tight = http.post(
                    f"{V1}/qc/check",
                    json=check | {"illuminant_limits": {"A": float(mi_a.min()) - 0.01}},
                    headers=auth,
                )
                assert tight.status_code == 200, tight.text
                out = tight.json()
                assert out["verdict"] == "fail" and out["d65_verdict"] == "pass"
                rows = out["illuminants"]["rows"]
                np.testing.assert_allclose([x["metamerism_index"] for x in rows], mi_a, atol=1e-6)
                assert [x["verdict"] for x in rows] == ["fail"] * 3
                loose = http.post(
                    f"{V1}/qc/check",
                    json=check | {"illuminant_limits": {"A": float(mi_a.max()) + 0.01}},
                    headers=auth,
                )
                assert loose.json()["verdict"] == "pass"
                assert (
                    _loc(
                        http.post(
                            f"{V1}/qc/check", json=check | {"illuminant_limits": {"Q7": 1.0}}, headers=auth
                        )
                    )[-1]
                    == "Q7"
                )
                put = http.put(
                    f"{V1}/qc/jobs/J-BOOTH/standards/door", json={"measurement_id": std_id}, headers=auth
                )
                assert put.status_code == 200, put.text
                limits = {"illuminant_limits": f"A={float(mi_a.min()) - 0.01}", "formula": "cie2000"}
                summary = http.get(f"{V1}/qc/jobs/J-BOOTH/summary", params=limits, headers=auth)
                assert summary.status_code == 200, summary.text
                assert summary.json()["counts"] == {"pass": 0, "warn": 0, "fail": 1}
                pdf = http.get(f"{V1}/qc/jobs/J-BOOTH/report.pdf", params=limits, headers=auth)
                assert pdf.status_code == 200 and pdf.content[:5] == b"%PDF-"
                bad_q = http.get(
                    f"{V1}/qc/jobs/J-BOOTH/report.pdf", params={"illuminant_limits": "A=oops"}, headers=auth
                )
                assert "illuminant_limits" in _loc(bad_q)

                # seam QA under A: the metameric pair seams under A, not under D65
                seam = {"measurement_a": std_id, "measurement_b": smp_id, "beta_deg": 5.0}
                d65 = http.post(f"{V1}/analyses/seam", json=seam, headers=auth)
                assert d65.status_code == 201, d65.text
                under_a = http.post(f"{V1}/analyses/seam", json=seam | {"illuminant": "A"}, headers=auth)
                assert under_a.status_code == 201, under_a.text
                rep_d65, rep_a = d65.json()["result"], under_a.json()["result"]
                assert rep_d65["illuminant"] == "D65" and rep_a["illuminant"] == "A"
                assert rep_d65["formulation_de_max"] < 1e-3 < 0.5 < rep_a["formulation_de_max"]
                assert (
                    _loc(http.post(f"{V1}/analyses/seam", json=seam | {"illuminant": "Q7"}, headers=auth))[-1]
                    == "illuminant"
                )
    except ServeStartError as exc:
        pytest.fail(str(exc))
