"""A part's SPC over real HTTP (``station serve`` on a loopback port): ``GET /qc/jobs/{job}/spc`` and its
``spc.png`` answer what ``station qc spc`` prints and draws for the same database, panels averaged with
the dirty reading left out, the drift flagged before the first fail, and each bad option answered 422
naming the field.

Independent expectations: ΔE00 of the hand-averaged panel means by colour-science, the individuals chart's
centre and limits from their closed form (x̄ ± 3·MR̄/1.128 over the baseline), Cpk = (USL − x̄)/3σ̂.
"""

from __future__ import annotations

import datetime as dt
import json
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import colour
import httpx
import numpy as np
import pytest

from db.engine import default_database_url
from station.model.domain import QC_DE_LIMIT
from tests.processes import run
from tests.serve_process import serve_env, serving

REPO = Path(__file__).resolve().parents[2]
V1 = "/api/v1"
JOB = "J-SPC-HTTP"
PART = "hood"
ANGLES = [15.0, 45.0, 110.0]
STD = np.array([[55.0, -1.0, 2.0], [50.0, -0.5, 1.0], [45.0, 0.0, 0.5]])
#: ΔL* of each sample panel (oldest first): five steady panels, then a slow rise that ends in a fail.
DLS = (0.10, 0.13, 0.09, 0.12, 0.11, 0.25, 0.40, 0.60, 0.85, 1.30)
#: Every panel is read twice (ΔL and ΔL + 0.02); this panel also once over a speck of dirt (ΔL + 4).
DIRTY_PANEL = 2
BASELINE = 5

Served = tuple[httpx.Client, dict[str, str], Path]


def _post(http: httpx.Client, auth: dict[str, str], lab: np.ndarray, notes: str, minute: int) -> int:
    body = {
        "client_id": str(uuid.uuid4()),
        "instrument": {"serial": "SIM-SPC-1", "model": "MA6", "kind": "multiangle"},
        "panel": {"job": JOB, "part": PART, "notes": notes},
        "operator": "ana",
        "measured_at": (
            dt.datetime(2026, 11, 3, 8, tzinfo=dt.UTC) + dt.timedelta(minutes=minute)
        ).isoformat(),
        "geometries_deg": ANGLES,
        "lab": lab.tolist(),
    }
    r = http.post(f"{V1}/measurements", json=body, headers=auth)
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Served]:
    """A running service with the job stored: the standard panel read once, each sample panel twice or
    three times; the data folder (its SQLite database) for the CLI."""
    data = tmp_path_factory.mktemp("qc-spc-http")
    with serving(data, cwd=REPO, start_timeout_s=120) as svc:
        auth = {"Authorization": f"Bearer {svc.token}"}
        with httpx.Client(base_url=svc.base, timeout=120) as http:
            std_id = _post(http, auth, STD, "standard panel", 0)
            for i, dl in enumerate(DLS):
                offsets = [dl, dl + 0.02] + ([dl + 4.0] if i == DIRTY_PANEL else [])
                for k, d in enumerate(offsets):
                    _post(http, auth, STD + [d, 0.0, 0.0], f"panel {i + 1}", 10 * (i + 1) + k)
            r = http.put(
                f"{V1}/qc/jobs/{JOB}/standards/{PART}", json={"measurement_id": std_id}, headers=auth
            )
            assert r.status_code == 200, r.text
            yield http, auth, svc.data_dir


def _get(served: Served, path: str, **params: str) -> httpx.Response:
    http, auth, _data = served
    query = {"part": PART, "formula": "cie2000", "average_panels": "true", **params}
    return http.get(f"{V1}/qc/jobs/{JOB}/{path}", params=query, headers=auth)


def _expected_de() -> np.ndarray:
    """ΔE00 (panels × geometries) of each panel's mean of its two clean readings against the standard."""
    means = [STD + [dl + 0.01, 0.0, 0.0] for dl in DLS]
    return np.array([colour.delta_E(STD, m, method="CIE 2000") for m in means])


def _cli(data: Path, *extra: str) -> dict[str, Any]:
    cmd = [sys.executable, "-m", "station.cli", "qc", "spc", "--job", JOB, "--part", PART]
    cmd += ["--formula", "cie2000", "--average-panels", "--baseline", str(BASELINE), "--json"]
    cmd += ["--db", default_database_url(data), *extra]
    done = run(cmd, cwd=REPO, env=serve_env(), timeout=120)
    assert done.returncode == 0, done.stderr
    out: dict[str, Any] = json.loads(done.stdout)
    return out


def test_spc_numbers_are_the_library_s(served: Served, tmp_path: Path) -> None:
    r = _get(served, "spc", baseline=str(BASELINE))
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["samples"] == len(DLS) and out["baseline"] == BASELINE and out["chart"] == "individuals"
    de = _expected_de()
    for j, g in enumerate(out["geometries"]):
        x = de[:, j]
        base = x[:BASELINE]
        sigma = float(np.abs(np.diff(base)).mean()) / 1.128
        chart = g["chart"]
        assert chart["points"] == pytest.approx(x.tolist(), abs=1e-9)  # the dirty reading is left out
        assert chart["centre"] == pytest.approx(float(base.mean()), abs=1e-12)
        assert chart["ucl"] == pytest.approx(float(base.mean()) + 3 * sigma, abs=1e-12)
        cap = g["capability"]
        assert cap["usl"] == QC_DE_LIMIT
        assert cap["cpk"] == pytest.approx((QC_DE_LIMIT - float(base.mean())) / (3 * sigma), rel=1e-9)
        fails = [i for i, v in enumerate(x) if v > QC_DE_LIMIT]
        assert g["first_fail"] == (fails[0] if fails else None)
        # WE2 (2 of 3 beyond 2σ, high side) first completes at the second rising panel, before any fail
        z = (x - float(base.mean())) / sigma
        assert z[BASELINE] > 2 and z[BASELINE + 1] > 2 and np.all(z[:BASELINE] < 2)
        first_drift = min(p for h in g["drift"] for p in h["points"])
        assert first_drift == BASELINE + 1 and g["drift_before_fail"] is True
        assert "WE2" in [h["rule"] for h in g["drift"] if first_drift in h["points"]]
    assert fails == [len(DLS) - 1]  # at 110° (the last geometry) only the last panel fails
    # the CLI on the same database prints the same answer, and draws the same chart
    png = tmp_path / "spc.png"
    cli = _cli(served[2], "--out", str(png))
    assert cli.pop("written") == str(png)
    assert cli == out
    r = _get(served, "spc.png", baseline=str(BASELINE))
    assert r.status_code == 200 and r.headers["content-type"] == "image/png"
    assert r.content == png.read_bytes()


def test_spc_xbar_r_subgroups(served: Served) -> None:
    r = _get(served, "spc", subgroup="2")
    assert r.status_code == 200, r.text
    chart = r.json()["geometries"][1]["chart"]
    x = _expected_de()[:, 1].reshape(-1, 2)
    r_bar = float(np.ptp(x, axis=1).mean())
    assert chart["kind"] == "xbar" and chart["points"] == pytest.approx(x.mean(axis=1).tolist(), abs=1e-9)
    assert chart["ucl"] == pytest.approx(float(x.mean()) + 1.880 * r_bar, abs=1e-12)  # A₂(2) = 1.880


#: A tolerance set tighter than the default, as ``station qc tolerance --json`` writes one.
TOLERANCE = {"formula": "cie2000", "geometries": [{"aspecular_deg": a, "de": 0.5} for a in ANGLES]}


def test_a_tolerance_set_in_the_body(served: Served, tmp_path: Path) -> None:
    http, auth, data = served
    body = {"tolerance": TOLERANCE, "average_panels": True}
    r = http.post(f"{V1}/qc/jobs/{JOB}/summary", json=body, headers=auth)
    assert r.status_code == 200, r.text
    out = r.json()
    samples = out["parts"][0]["samples"]
    de = _expected_de()
    verdicts = ["fail" if x.max() > 0.5 else "warn" if x.max() > 0.4 else "pass" for x in de]  # warn at 80 %
    assert [s["qc"]["verdict"] for s in samples] == verdicts and verdicts.count("fail") == 3
    assert {g["limit"] for s in samples for g in s["qc"]["per_geometry"]} == {0.5}
    r = http.post(f"{V1}/qc/jobs/{JOB}/spc", json={**body, "part": PART, "baseline": BASELINE}, headers=auth)
    assert r.status_code == 200, r.text
    spc = r.json()
    assert {g["capability"]["usl"] for g in spc["geometries"]} == {0.5}
    # the CLI with the same set as a file prints the same
    tol = tmp_path / "tol.json"
    tol.write_text(json.dumps(TOLERANCE))
    assert _cli(data, "--tolerance", str(tol)) == spc
    bad = {**body, "tolerance": {**TOLERANCE, "limit": 1}}
    for path, extra in (("summary", {}), ("spc", {"part": PART})):
        r = http.post(f"{V1}/qc/jobs/{JOB}/{path}", json={**bad, **extra}, headers=auth)
        assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "tolerance", "limit"], r.text
    r = http.post(f"{V1}/qc/jobs/{JOB}/summary", json={"average_panels": True}, headers=auth)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "tolerance"], r.text


@pytest.mark.parametrize(
    ("params", "field"),
    [
        ({"baseline": "1"}, "baseline"),
        ({"baseline": str(len(DLS) + 1)}, "baseline"),
        ({"baseline": "abc"}, "baseline"),
        ({"subgroup": "11"}, "subgroup"),
        ({"subgroup": "0"}, "subgroup"),
        ({"part": "wing"}, "part"),
        ({"keep_outliers": "true", "average_panels": "false"}, "keep_outliers"),
    ],
)
def test_bad_options_name_the_field(served: Served, params: dict[str, str], field: str) -> None:
    for path in ("spc", "spc.png"):
        r = _get(served, path, **params)
        assert r.status_code == 422, r.text
        assert r.json()["detail"][0]["loc"][-1] == field, r.text
