"""A job's summary over real HTTP (``station serve`` on a loopback port): the outliers left out of a panel's
mean with their robust z, ``keep_outliers``, the texture verdict within one vendor (ΔS, ΔG) and the ΔE
limit used at each geometry, each bad option answered 422 naming the field.

Expectations are computed here independently: ΔE00 with colour-science on the hand-averaged Lab, the
robust z from its definition (Iglewicz & Hoaglin's modified z-score over the readings' distance to the
median reading), the texture bands from the tolerance's closed form.
"""

from __future__ import annotations

import datetime as dt
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import colour
import httpx
import numpy as np
import pytest

from station.model.domain import QC_DE_LIMIT, QC_OUTLIER_SCALE_FLOOR, QC_WARN_FRACTION
from tests.serve_process import serving

REPO = Path(__file__).resolve().parents[2]
V1 = "/api/v1"
JOB = "J-QC-HTTP"
ANGLES = [15.0, 45.0, 110.0]
STD = np.array([[92.0, -1.0, 2.0], [60.0, -0.5, 1.0], [35.0, 0.0, 0.5]])
#: ΔL* of the sample panel's five repeat readings; the fourth was taken over a speck of dirt.
DLS = (0.10, 0.12, 0.08, 4.0, 0.11)
DIRTY = 3
#: Texture (one vendor): the standard's and the sample's sparkle intensity at 15° and graininess.
STD_TEX = {"sparkle intensity": 5.0, "graininess": 3.0}
SMP_TEX = {"sparkle intensity": 5.9, "graininess": 3.2}
DS, DG = 1.0, 0.5


def _texture(values: dict[str, float]) -> list[dict[str, Any]]:
    geometry = {"sparkle intensity": "45as15", "graininess": ""}
    return [{"vendor": "BYK", "name": n, "geometry": geometry[n], "value": v} for n, v in values.items()]


def _post(http: httpx.Client, auth: dict[str, str], lab: np.ndarray, notes: str, hour: int, tex: Any) -> int:
    body = {
        "client_id": str(uuid.uuid4()),
        "instrument": {"serial": "SIM-QC-1", "model": "MA6", "kind": "multiangle"},
        "panel": {"job": JOB, "part": "fender", "notes": notes},
        "operator": "ana",
        "measured_at": (dt.datetime(2026, 11, 2, 8, tzinfo=dt.UTC) + dt.timedelta(hours=hour)).isoformat(),
        "geometries_deg": ANGLES,
        "lab": lab.tolist(),
        "texture": tex,
    }
    r = http.post(f"{V1}/measurements", json=body, headers=auth)
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


@pytest.fixture(scope="module")
def job(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[httpx.Client, dict[str, str], list[int]]]:
    """A running service with the job stored: the standard panel read once, the sample panel five times."""
    with serving(tmp_path_factory.mktemp("qc-http"), cwd=REPO, start_timeout_s=120) as svc:
        auth = {"Authorization": f"Bearer {svc.token}"}
        with httpx.Client(base_url=svc.base, timeout=120) as http:
            std_id = _post(http, auth, STD, "standard panel", 0, _texture(STD_TEX))
            ids = [
                _post(http, auth, STD + [dl, 0.0, 0.0], "panel 1", 1 + i, _texture(SMP_TEX))
                for i, dl in enumerate(DLS)
            ]
            r = http.put(
                f"{V1}/qc/jobs/{JOB}/standards/fender", json={"measurement_id": std_id}, headers=auth
            )
            assert r.status_code == 200, r.text
            yield http, auth, ids


def _summary(job: tuple[httpx.Client, dict[str, str], list[int]], **params: str) -> httpx.Response:
    http, auth, _ids = job
    return http.get(f"{V1}/qc/jobs/{JOB}/summary", params={"formula": "cie2000", **params}, headers=auth)


def _robust_z() -> np.ndarray:
    """The modified z-score of each reading's ΔE*ab to the median reading (pure ΔL* offsets: |ΔL − median|)."""
    d = np.abs(np.array(DLS) - np.median(DLS))
    s = max(1.4826 * float(np.median(np.abs(d - np.median(d)))), QC_OUTLIER_SCALE_FLOOR)
    return (d - np.median(d)) / s


def _band(delta: float, limit: float) -> str:
    return "fail" if abs(delta) > limit else "warn" if abs(delta) > QC_WARN_FRACTION * limit else "pass"


def test_outliers_left_out_with_their_robust_z(job: tuple[httpx.Client, dict[str, str], list[int]]) -> None:
    ids = job[2]
    r = _summary(job, average_panels="true")
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["averaged"] is True and out["outliers_kept"] is False
    (part,) = out["parts"]
    (sample,) = part["samples"]
    assert sample["measurement_ids"] == ids and sample["left_out"] == [ids[DIRTY]]
    (left,) = sample["left_out_readings"]
    z = _robust_z()
    assert left["measurement_id"] == ids[DIRTY] and left["robust_z"] == pytest.approx(z[DIRTY], rel=1e-9)
    assert left["de_to_centre"] == pytest.approx(DLS[DIRTY] - np.median(DLS), abs=1e-9)
    kept = np.mean([STD + [dl, 0, 0] for i, dl in enumerate(DLS) if i != DIRTY], axis=0)
    de = colour.delta_E(STD, kept, method="CIE 2000")
    assert sample["qc"]["max_de"] == pytest.approx(float(np.max(de)), abs=1e-9)
    for g, d in zip(sample["qc"]["per_geometry"], de, strict=True):
        assert g["dE"] == pytest.approx(float(d), abs=1e-9) and g["limit"] == QC_DE_LIMIT
    assert sample["overall"] == sample["qc"]["verdict"] == "pass"
    assert "gloss" in sample and sample["gloss"] is None  # the service's pairing, beside the core's fields

    r = _summary(job, average_panels="true", keep_outliers="true")
    sample = r.json()["parts"][0]["samples"][0]
    assert sample["left_out"] == [] and sample["left_out_readings"] == []
    every = np.mean([STD + [dl, 0, 0] for dl in DLS], axis=0)
    assert sample["qc"]["max_de"] == pytest.approx(float(np.max(colour.delta_E(STD, every, "CIE 2000"))))
    assert float(np.max(colour.delta_E(STD, every, "CIE 2000"))) > 3 * float(np.max(de))  # it moves the mean


def test_texture_verdict_within_one_vendor(job: tuple[httpx.Client, dict[str, str], list[int]]) -> None:
    r = _summary(job, average_panels="true", texture_limits=f"ds={DS:g},dg={DG:g}")
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["texture_limits"] == {"ds": DS, "dg": DG}
    sample = out["parts"][0]["samples"][0]
    tex = sample["texture"]
    assert tex["vendor"] == "BYK"
    rows = {row["name"]: row for row in tex["rows"]}
    sparkle, grain = rows["sparkle intensity"], rows["graininess"]
    assert sparkle["geometry"] == "45as15" and grain["geometry"] == ""
    d_s = SMP_TEX["sparkle intensity"] - STD_TEX["sparkle intensity"]
    d_g = SMP_TEX["graininess"] - STD_TEX["graininess"]
    assert sparkle["delta"] == pytest.approx(d_s) and sparkle["tolerance"] == "ΔS" and sparkle["limit"] == DS
    assert grain["delta"] == pytest.approx(d_g) and grain["tolerance"] == "ΔG" and grain["limit"] == DG
    assert sparkle["verdict"] == _band(d_s, DS) == "warn" and grain["verdict"] == _band(d_g, DG) == "pass"
    assert tex["verdict"] == "warn" and sample["overall"] == "warn"  # colour passes; texture is the worst


@pytest.mark.parametrize(
    ("params", "loc"),
    [
        ({"texture_limits": "ds=abc"}, ["body", "texture_limits", "ds"]),
        ({"texture_limits": "dq=1"}, ["body", "texture_limits"]),
        ({"keep_outliers": "true"}, ["body", "keep_outliers"]),
        ({"average_panels": "maybe"}, ["query", "average_panels"]),
    ],
)
def test_bad_options_name_the_field(
    job: tuple[httpx.Client, dict[str, str], list[int]], params: dict[str, str], loc: list[str]
) -> None:
    r = _summary(job, **params)
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"] == loc
