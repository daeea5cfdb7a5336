"""``/api/v1/booth``: a constructed metameric pair (equal under D65, not under A) over real HTTP and in-process."""

from __future__ import annotations

import uuid
from pathlib import Path

import colour
import numpy as np
import pytest

from station.model.booth import metameric_pair
from station.model.colorimetry import OBSERVER_10
from station.model.spectra import WAVELENGTHS, reflectance_from_lab
from tests.api.conftest import Api
from tests.ingest._readings import make_reading

V1 = "/api/v1"
ANGLES = [15.0, 45.0, 110.0]
GEOMETRIES = ["45as15", "45as45", "45as110"]
#: A blue metallic per geometry, Lab D65 / 10°.
BLUE = [[62.0, 6.0, -34.0], [38.0, 4.0, -28.0], [22.0, 3.0, -20.0]]


def _pair() -> tuple[np.ndarray, np.ndarray]:
    std, smp = metameric_pair(reflectance_from_lab(BLUE), strength=0.4)
    return std.round(6), smp.round(6)  # what the store keeps (6 decimals)


def _lab(refl: np.ndarray, illuminant: str, observer: str = OBSERVER_10) -> np.ndarray:
    """colour-science's Lab (ASTM E308) relative to the illuminant's own integrated white."""
    cmfs = colour.MSDS_CMFS[observer]
    ill = colour.SDS_ILLUMINANTS[{"F11": "FL11", "TL84": "FL11"}.get(illuminant, illuminant)]
    rows = []
    for r in refl:
        sd = colour.SpectralDistribution(dict(zip(WAVELENGTHS, r, strict=True)))
        xyz = colour.sd_to_XYZ(sd, cmfs, ill, method="ASTM E308") / 100
        white = colour.sd_to_XYZ(colour.sd_ones(sd.shape), cmfs, ill, method="ASTM E308") / 100
        rows.append(colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white)))
    return np.asarray(rows)


def _measurement_body(panel: int, spectra: np.ndarray | None, k: int) -> dict:
    body = make_reading(47, k, panel_id=panel).model_dump(mode="json")
    body |= {
        "client_id": str(uuid.uuid4()),
        "geometries_deg": ANGLES,
        "lab": BLUE,
        "wavelengths_nm": None if spectra is None else WAVELENGTHS.tolist(),
        "spectra": None if spectra is None else spectra.tolist(),
    }
    return body


def _check_pair(doc: dict, std: np.ndarray, smp: np.ndarray, names: list[str]) -> None:
    assert set(doc) == {"illuminants", "reference"} and doc["reference"] == "D65"
    by_name = {i["name"]: i for i in doc["illuminants"]}
    assert list(by_name) == names
    for g in by_name["D65"]["per_geometry"]:
        assert g["dE00"] < 1e-3 and g["metamerism_index"] == 0.0
    for name in names[1:]:
        expected = colour.delta_E(_lab(std, name), _lab(smp, name), method="CIE 2000")
        rows = by_name[name]["per_geometry"]
        assert [g["geometry"] for g in rows] == GEOMETRIES
        assert [g["dE00"] for g in rows] == pytest.approx(expected, abs=1e-3)
        assert [g["metamerism_index"] for g in rows] == pytest.approx(expected, abs=1e-3)
        assert np.array([g["standard_lab"] for g in rows]) == pytest.approx(_lab(std, name), abs=1e-6)
        assert np.array([g["sample_lab"] for g in rows]) == pytest.approx(_lab(smp, name), abs=1e-6)
        assert by_name[name]["mean_de"] == pytest.approx(float(np.mean([g["dE00"] for g in rows])))
    assert min(g["dE00"] for g in by_name["A"]["per_geometry"]) > 0.5


def test_booth_over_real_http(tmp_path: Path) -> None:
    """``station serve`` as a process: stored standard and trial of a metameric pair, read in the booth."""
    import httpx

    from tests.api.test_serve import _serve

    std, smp = _pair()
    with _serve(tmp_path) as (base, token):
        auth = {"Authorization": f"Bearer {token}"}
        with httpx.Client(base_url=base + V1, timeout=60) as http:
            panel = http.post("/panels", json={"job": "J-BOOTH", "part": "fender"}, headers=auth).json()["id"]
            ids = []
            for k, spectra in enumerate((std, smp, None)):
                r = http.post("/measurements", json=_measurement_body(panel, spectra, k), headers=auth)
                assert r.status_code == 201, r.text
                ids.append(r.json()["id"])
            body = {"standard_measurement_id": ids[0], "sample_measurement_id": ids[1]}
            r = http.post("/booth", json=body | {"illuminants": ["D65", "A", "F11"]}, headers=auth)
            assert r.status_code == 200, r.text
            _check_pair(r.json(), std, smp, ["D65", "A", "F11"])
            # bad illuminant: 422 naming the field
            r = http.post("/booth", json=body | {"illuminants": ["D65", "D93"]}, headers=auth)
            assert r.status_code == 422 and "illuminants[1]" in r.text and "D93" in r.text, r.text
            # a measurement without spectra: 422 naming the measurement
            r = http.post("/booth", json=body | {"sample_measurement_id": ids[2]}, headers=auth)
            assert r.status_code == 422 and f"measurement {ids[2]}" in r.text and "spectra" in r.text, r.text
            r = http.post("/booth", json=body | {"sample_measurement_id": 999_999}, headers=auth)
            assert r.status_code == 404 and "sample_measurement_id" in r.text
            assert http.post("/booth", json=body).status_code == 401


def test_booth_spectra_in_body_user_lamp_and_refusals(api: Api) -> None:
    c, qa = api.client, api.auth("qa")
    std, smp = _pair()

    def spectra(x: np.ndarray) -> dict:
        return {"geometries": GEOMETRIES, "spectra": x.tolist(), "wavelengths_nm": WAVELENGTHS.tolist()}

    body = {"standard": spectra(std), "sample": spectra(smp), "illuminants": ["D65", "A", "TL84"]}
    r = c.post(f"{V1}/booth", json=body, headers=qa)
    assert r.status_code == 200, r.text
    _check_pair(r.json(), std, smp, ["D65", "A", "TL84"])
    # the 2° observer and a lamp of the lab's own
    wl = list(range(380, 781, 10))
    lamp = {
        "name": "bench lamp",
        "wavelengths_nm": [float(w) for w in wl],
        "values": [50.0 + w / 10 for w in wl],
    }
    r = c.post(
        f"{V1}/booth",
        json=body | {"illuminants": ["D65", "bench lamp"], "user_illuminants": [lamp], "observer": "2"},
        headers=qa,
    )
    assert r.status_code == 200, r.text
    sd = colour.SpectralDistribution(
        dict(zip(wl, lamp["values"], strict=True)), interpolator=colour.LinearInterpolator
    )
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    white = colour.sd_to_XYZ(colour.sd_ones(colour.SpectralShape(400, 700, 10)), cmfs, sd, method="ASTM E308")
    xyz = colour.sd_to_XYZ(
        colour.SpectralDistribution(dict(zip(WAVELENGTHS, std[0], strict=True))), cmfs, sd, method="ASTM E308"
    )
    expected = colour.XYZ_to_Lab(xyz / white[1], colour.XYZ_to_xy(white))
    got = r.json()["illuminants"][1]
    assert got["name"] == "bench lamp"
    assert got["per_geometry"][0]["standard_lab"] == pytest.approx(expected, abs=1e-6)
    bad_lamp = lamp | {"wavelengths_nm": [float(w) for w in range(450, 851, 10)]}
    cases: list[tuple[dict[str, object], int, str]] = [
        ({"illuminants": ["D65", "D93"]}, 422, "illuminants[1]"),
        ({"illuminants": []}, 422, "illuminants"),
        ({"illuminants": ["A", "a"]}, 422, "distinct"),
        ({"observer": "4"}, 422, "observer"),
        ({"standard_measurement_id": 1}, 422, "exactly one"),
        ({"sample": None}, 422, "exactly one"),
        (
            {"user_illuminants": [bad_lamp], "illuminants": ["bench lamp"]},
            422,
            "user_illuminants[0].wavelengths_nm",
        ),
        ({"standard": {"geometries": GEOMETRIES, "spectra": [[0.5] * 31] * 2}}, 422, "standard.spectra"),
    ]
    for extra, code, words in cases:
        resp = c.post(f"{V1}/booth", json=body | extra, headers=qa)
        assert resp.status_code == code and words in resp.text, (extra, resp.text)


def test_booth_catalogue(api: Api) -> None:
    r = api.client.get(f"{V1}/booth/illuminants", headers=api.auth("technician"))
    assert r.status_code == 200
    doc = r.json()
    assert doc["illuminants"] == ["D65", "D50", "A", "F2", "F11", "TL84", "LED-B3", "LED-B4"]
    assert doc["observers"]["2"] == "CIE 1931 2 Degree Standard Observer" and doc["reference"] == "D65"
    assert doc["shapes"] == ["panels", "seam", "car"]
