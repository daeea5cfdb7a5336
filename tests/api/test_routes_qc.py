"""``/api/v1/qc``: gloss readings stored and paired with colour, checks against a standard, bad input named."""

from __future__ import annotations

import datetime as dt
import json
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
    smp_id = _colour(api, panel, SMP, minutes=1)
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
    # a standard at two of the sample's three angles is judged at those two only
    two = body | {
        "standard": {"geometries_deg": ANGLES[:2], "lab": STD[:2]},
        "sample": {"measurement_id": smp_id},
    }
    out2 = c.post(f"{V1}/qc/check", json=two, headers=api.auth("technician")).json()
    assert [g["aspecular_deg"] for g in out2["per_geometry"]] == [15.0, 45.0] and out2["verdict"] == "warn"
    assert out2["sample_measurement_id"] == smp_id


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
        (good | {"sample": {"geometries_deg": [15.0], "lab": [SMP[0]]}}, 422, "sample.geometries"),
        (good | {"sample": {"measurement_id": 999_999}}, 404, "sample.measurement_id"),
        (
            good | {"tolerance": {"geometries": [{"geometry": "45as15", "de": 1}], "bogus": 1}},
            422,
            "tolerance.bogus",
        ),
        (good | {"tolerance": {"geometries": [{"geometry": "45as25", "de": 1}]}}, 422, "standard.geometries"),
        (good | {"tolerance": {"geometries": []}, "formula": "cie76"}, 422, "tolerance"),
        (good | {"formula": "audi2000"}, 422, "audi2000"),
    ]
    for body, code, words in cases:
        r = c.post(f"{V1}/qc/check", json=body, headers=qa)
        assert r.status_code == code, (words, r.text)
        assert words in r.text, (words, r.text)


def _populated(api: Api):
    from tests.qc.conftest import populate

    with api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
        job = populate(session)
        session.commit()
    return job


def test_standards_summary_and_reports(api: Api) -> None:
    c, qa, tech = api.client, api.auth("qa"), api.auth("technician")
    job = _populated(api)
    assert c.get(f"{V1}/qc/jobs/J-100/standards/fender", headers=qa).status_code == 404
    put = c.put(f"{V1}/qc/jobs/J-100/standards/fender", json={"measurement_id": job.standard_id}, headers=qa)
    assert put.status_code == 200, put.text
    assert put.json()["measurement_id"] == job.standard_id and put.json()["design_id"] is None
    # a second standard for the same part needs replace; a technician may not set standards at all
    again = c.put(
        f"{V1}/qc/jobs/J-100/standards/fender", json={"measurement_id": job.sample_ids[0]}, headers=qa
    )
    assert again.status_code == 422 and again.json()["detail"][0]["loc"][-1] == "replace"
    assert (
        c.put(f"{V1}/qc/jobs/J-100/standards/bumper", json={"design_id": 1}, headers=tech).status_code == 403
    )
    bumper = c.put(
        f"{V1}/qc/jobs/J-100/standards/bumper", json={"measurement_id": job.correction_id}, headers=qa
    )
    assert bumper.status_code == 200
    got = c.get(f"{V1}/qc/jobs/J-100/standards/fender", headers=tech).json()
    assert got["measurement_id"] == job.standard_id and got["created_by_id"] is not None
    jobs = c.get(f"{V1}/qc/jobs", headers=tech).json()
    assert [(j["job"], j["parts"]) for j in jobs] == [("J-100", ["bumper", "fender"]), ("J-200", ["door"])]

    linked = c.post(
        f"{V1}/qc/gloss", json=_gloss(None, 0, 92.0, measurement_id=job.sample_ids[2]), headers=tech
    ).json()
    s = c.get(f"{V1}/qc/jobs/J-100/summary", params={"formula": "cie76"}, headers=qa)
    assert s.status_code == 200, s.text
    parts = {p["part"]: p for p in s.json()["parts"]}
    fender = parts["fender"]
    # ΔE*ab of each sample = |offset| at every geometry (the offsets are the same at all three); limit 1
    from tests.qc.conftest import FENDER_OFFSETS

    expected = [math.sqrt(sum(v * v for v in off)) for off in FENDER_OFFSETS]
    got_de = [smp["qc"]["max_de"] for smp in fender["samples"]]
    assert got_de == pytest.approx(expected, abs=1e-9)
    assert [smp["qc"]["verdict"] for smp in fender["samples"]] == [
        "fail" if d > 1.0 else "pass" for d in expected
    ]
    assert (
        fender["counts"] == {"pass": 6, "warn": 0, "fail": 1}
        and fender["standard"]["measurement_id"] == job.standard_id
    )
    worst = fender["samples"][5]["qc"]
    assert "ΔE 2.5 beyond 1" in worst["reason"] and all(g["verdict"] == "fail" for g in worst["per_geometry"])
    # bumper: the correction (50.3, 0, 0) is the standard, the second sample is (50, 0.6, 0): √(0.09 + 0.36)
    assert [smp["qc"]["max_de"] for smp in parts["bumper"]["samples"]] == pytest.approx([math.sqrt(0.45)])
    assert s.json()["counts"] == {"pass": 7, "warn": 0, "fail": 1}
    assert [smp["gloss"]["id"] if smp["gloss"] else None for smp in fender["samples"]] == [
        None,
        None,
        linked["id"],
        None,
        None,
        None,
        None,
    ]

    if c.app.state.settings.effective_database_url.startswith("sqlite"):  # type: ignore[attr-defined]
        # rendered once (the backend does not change the report; it only costs time)
        pdf = c.get(f"{V1}/qc/jobs/J-100/report.pdf", params={"formula": "cie76"}, headers=qa)
        assert pdf.status_code == 200 and pdf.headers["content-type"] == "application/pdf"
        assert pdf.content.startswith(b"%PDF") and len(pdf.content) > 10_000
    csv_text = c.get(f"{V1}/qc/jobs/J-100/report.csv", params={"formula": "cie76"}, headers=qa)
    assert csv_text.status_code == 200 and csv_text.headers["content-type"].startswith("text/csv")
    import csv
    import io

    rows = list(csv.DictReader(io.StringIO(csv_text.text)))
    assert len(rows) == (7 + 1) * 3  # one row per judged sample and geometry
    far = [r for r in rows if r["part"] == "fender" and r["measurement_id"] == str(job.sample_ids[5])]
    assert [float(r["dE"]) for r in far] == pytest.approx([2.5] * 3)

    bad = [
        (c.get(f"{V1}/qc/jobs/J-404/summary", headers=qa), 422, "job"),
        (c.get(f"{V1}/qc/jobs/J-100/summary", params={"formula": "cmc2"}, headers=qa), 422, "formula"),
        (c.get(f"{V1}/qc/jobs/J-100/standards/wing", headers=qa), 422, "part"),
        (c.put(f"{V1}/qc/jobs/J-100/standards/door", json={}, headers=qa), 422, "standard"),
        (
            c.put(f"{V1}/qc/jobs/J-100/standards/door", json={"measurement_id": 999_999}, headers=qa),
            422,
            "measurement_id",
        ),
        (
            c.put(
                f"{V1}/qc/jobs/J-100/standards/door", json={"measurement_id": job.superseded_id}, headers=qa
            ),
            422,
            "superseded",
        ),
    ]
    for r, code, words in bad:
        assert r.status_code == code, (words, r.text)
        assert words in r.text, (words, r.text)


def _spectral(api: Api, panel: int, curves: list[list[float]], minutes: float) -> int:
    body = make_reading(31, int(minutes), panel_id=panel).model_dump(mode="json")
    body |= {
        "client_id": str(uuid.uuid4()),
        "geometries_deg": ANGLES,
        "lab": STD,
        "wavelengths_nm": [400.0 + 10 * k for k in range(31)],
        "spectra": curves,
    }
    r = api.client.post(f"{V1}/measurements", json=body, headers=api.auth("technician"))
    assert r.status_code == 201, r.text
    return r.json()["id"]


def test_metamerism_and_repeats(api: Api) -> None:
    import colour
    import numpy as np

    c, qa = api.client, api.auth("qa")
    panel = _panel(api)
    wl = np.arange(400, 701, 10)
    flat = [[0.5] * 31, [0.3] * 31, [0.1] * 31]
    ramp = [
        list(0.2 + 0.6 * (wl - 400) / 300),
        list(0.1 + 0.4 * (wl - 400) / 300),
        list(0.05 + 0.1 * (wl - 400) / 300),
    ]
    std_id, smp_id = _spectral(api, panel, flat, 0), _spectral(api, panel, ramp, 1)
    same = c.post(
        f"{V1}/qc/metamerism",
        json={"standard_measurement_id": std_id, "sample_measurement_id": std_id},
        headers=qa,
    )
    assert same.status_code == 200, same.text
    assert all(g["MI_A"] == 0 and g["MI_F11"] == 0 and g["dE_D65"] == 0 for g in same.json()["per_geometry"])
    r = c.post(
        f"{V1}/qc/metamerism",
        json={"standard_measurement_id": std_id, "sample_measurement_id": smp_id, "formula": "cie76"},
        headers=qa,
    ).json()
    # independent: colour-science Lab under D65 and A (1964 10°), sample corrected additively under D65
    shape = colour.SpectralShape(400, 700, 10)
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"].copy().align(shape)

    def lab(curve: list[float], ill: str) -> np.ndarray:
        sd_ill = colour.SDS_ILLUMINANTS[ill].copy().align(shape)
        xyz = colour.sd_to_XYZ(colour.SpectralDistribution(dict(zip(wl, curve, strict=True))), cmfs, sd_ill)
        white = colour.sd_to_XYZ(colour.sd_ones(shape), cmfs, sd_ill)
        return colour.XYZ_to_Lab(xyz / 100, colour.XYZ_to_xy(white / 100))

    for i, g in enumerate(r["per_geometry"]):
        d65 = lab(ramp[i], "D65") - lab(flat[i], "D65")
        a = lab(ramp[i], "A") - lab(flat[i], "A")
        assert g["dE_D65"] == pytest.approx(float(np.linalg.norm(d65)), abs=0.05)
        assert g["MI_A"] == pytest.approx(float(np.linalg.norm(a - d65)), abs=0.05)
    no_spectra = _colour(api, panel, STD, minutes=5)
    r2 = c.post(
        f"{V1}/qc/metamerism",
        json={"standard_measurement_id": no_spectra, "sample_measurement_id": smp_id},
        headers=qa,
    )
    assert r2.status_code == 422 and "standard.spectra" in r2.text

    labs = [[[50.0, 1.0, 2.0]] * 3, [[50.6, 1.0, 2.0]] * 3, [[49.7, 1.3, 2.0]] * 3]
    ids = [_colour(api, panel, lab3, minutes=10 + k) for k, lab3 in enumerate(labs)]
    rep = c.post(f"{V1}/qc/repeats", json={"measurement_ids": ids}, headers=qa)
    assert rep.status_code == 200, rep.text
    out = rep.json()
    assert out["n"] == 3 and [row["measurement_id"] for row in out["readings"]] == ids
    import statistics

    for g in out["per_geometry"]:
        assert g["mean"] == pytest.approx([50.1, 1.1, 2.0])
        assert g["sd"] == pytest.approx(
            [statistics.stdev([50.0, 50.6, 49.7]), statistics.stdev([1.0, 1.0, 1.3]), 0.0]
        )
    for body, code, words in [
        ({"measurement_ids": []}, 422, "measurement_ids"),
        ({"measurement_ids": [ids[0], ids[0]]}, 422, "distinct"),
        ({"measurement_ids": [ids[0], 999_999]}, 404, "measurement_ids[1]"),
    ]:
        resp = c.post(f"{V1}/qc/repeats", json=body, headers=qa)
        assert resp.status_code == code and words in resp.text, resp.text


def test_qc_journey_over_real_http(tmp_path) -> None:
    """``station serve`` as a process: gloss meter and MA6 simulators measure a standard and a sample,
    QA sets the standard, checks the sample, reads the job summary and downloads the CSV report (the PDF
    is checked in-process above: rendering it here would double this test's time)."""
    import httpx

    from tests.api.test_serve import _serve

    with _serve(tmp_path, "--simulators", "ma6,gloss") as (base, token):
        auth = {"Authorization": f"Bearer {token}"}
        with httpx.Client(base_url=base + V1, timeout=60) as http:
            ids = {i["kind"]: i["id"] for i in http.get("/instruments", headers=auth).json()}
            taken = []
            for _ in range(2):
                panel = http.post("/panels", json={"job": "J-HTTP", "part": "mirror"}, headers=auth).json()[
                    "id"
                ]
                r = http.post(
                    f"/instruments/{ids['spectro']}/measure",
                    params={"gloss_instrument_id": ids["gloss"]},
                    json={"panel_id": panel},
                    headers=auth,
                )
                assert r.status_code == 201, r.text
                taken.append(r.json())
            std, smp = (t["measurement"]["id"] for t in taken)
            assert (
                http.put(
                    "/qc/jobs/J-HTTP/standards/mirror", json={"measurement_id": std}, headers=auth
                ).status_code
                == 200
            )
            check = http.post(
                "/qc/check",
                json={
                    "standard": {"measurement_id": std},
                    "sample": {"measurement_id": smp},
                    "formula": "cie76",
                },
                headers=auth,
            ).json()
            s_lab, p_lab = (t["measurement"]["lab"] for t in taken)
            assert [g["dE"] for g in check["per_geometry"]] == pytest.approx(
                [_de76(a, b) for a, b in zip(s_lab, p_lab, strict=True)], abs=1e-9
            )
            summary = http.get("/qc/jobs/J-HTTP/summary", params={"formula": "cie76"}, headers=auth).json()
            (part,) = summary["parts"]
            assert [x["measurement_id"] for x in part["samples"]] == [smp]
            assert part["samples"][0]["qc"]["verdict"] == check["verdict"]
            view = http.get("/qc/measurements", params={"job": "J-HTTP"}, headers=auth).json()
            assert {m["gloss"]["id"] for m in view["data"]} == {t["gloss_reading_id"] for t in taken}
            csv_r = http.get("/qc/jobs/J-HTTP/report.csv", headers=auth)
            assert (
                csv_r.status_code == 200 and len(csv_r.text.strip().splitlines()) == 1 + 6
            )  # header + 6 geometries
            bad = http.post("/qc/check", json={"standard": {"measurement_id": std}}, headers=auth)
            assert bad.status_code == 422 and bad.json()["detail"][0]["loc"][-1] == "sample"


def test_a_15_degree_block_is_shown_with_its_texture_and_never_judged(api: Api) -> None:
    """A measurement of the 15° block keeps its illumination and vendor texture; QC refuses it."""
    c, tech, qa = api.client, api.auth("technician"), api.auth("qa")
    panel = _panel(api, "J-15")
    body = make_reading(22, 1, panel_id=panel).model_dump(mode="json") | {
        "client_id": str(uuid.uuid4()),
        "illumination_deg": 15,
        "geometries_deg": ANGLES,
        "lab": SMP,
        "spectra": None,
        "wavelengths_nm": None,
        "texture": [
            {"vendor": "BYK-Gardner", "name": "sparkle_area", "geometry": "15AS15", "value": 12.5},
            {"vendor": "BYK-Gardner", "name": "graininess", "geometry": "", "value": 4.0},
        ],
    }
    r = c.post(f"{V1}/measurements", json=body, headers=tech)
    assert r.status_code == 201, r.text
    got = c.get(f"{V1}/measurements/{r.json()['id']}", headers=qa).json()
    assert got["illumination_deg"] == 15.0 and got["geometries_deg"] == ANGLES
    assert got["texture"] == [  # the geometry in the domain's spelling, values as sent
        {"vendor": "BYK-Gardner", "name": "sparkle_area", "geometry": "15as15", "value": 12.5},
        {"vendor": "BYK-Gardner", "name": "graininess", "geometry": "", "value": 4.0},
    ]
    lit45 = _colour(api, panel, STD)
    shown = c.get(f"{V1}/measurements/{lit45}", headers=qa).json()
    assert (shown["illumination_deg"], shown["texture"]) == (45.0, None)
    by_block = {
        ill: [m["id"] for m in c.get(f"{V1}/measurements", params={"panel_id": panel, "illumination_deg": ill},
                                     headers=qa).json()["data"]]
        for ill in (15, 45)
    }  # fmt: skip
    assert by_block == {15: [got["id"]], 45: [lit45]}
    csv_text = c.get(f"{V1}/measurements/export.csv", params={"panel_id": panel}, headers=qa).text
    header, *lines = csv_text.splitlines()
    col = header.split(",").index("illumination_deg")
    assert sorted({line.split(",")[col] for line in lines}) == ["15.0", "45.0"] and len(lines) == 6
    check = {"standard": {"measurement_id": lit45}, "sample": {"measurement_id": r.json()["id"]}}
    refused = c.post(f"{V1}/qc/check", json=check, headers=qa)
    assert refused.status_code == 422 and "illumination_deg" in refused.text and "45°" in refused.text
    # a texture value at a geometry of another block, or twice, is refused naming texture
    for texture in (
        [{"vendor": "V", "name": "sparkle", "geometry": "45as15", "value": 1.0}],
        [{"vendor": "V", "name": "g", "value": 1.0}, {"vendor": "V", "name": "g", "value": 2.0}],
        [{"vendor": "V", "name": "g", "geometry": "15as15", "value": float("nan")}],
    ):
        bad = body | {"client_id": str(uuid.uuid4()), "texture": texture}
        raw = json.dumps(bad)  # NaN written as the bare token a hostile client sends
        r = c.post(f"{V1}/measurements", content=raw, headers=tech | {"content-type": "application/json"})
        assert r.status_code == 422 and "texture" in r.text, r.text
