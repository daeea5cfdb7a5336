"""Formulation routes (chemist): ColorSnap top-k, formulation, XML / CxF3 export, library CSV import/export.

ColorSnap is checked against a brute-force NumPy scan of the rows as stored, the formulation's predicted
ΔE per angle against the colorant model's own prediction of the returned recipe, the exports by reading
them back with the formulation package's readers.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
from sqlalchemy import insert

from db.models import LibraryPaint
from station.api.services.library import library_rows
from station.formulate.color_xml import read_color_xml
from station.formulate.colorants import default_database, predict_lab
from station.formulate.cxf import read_cxf_specs
from station.formulate.demo import generate_library
from station.formulate.library_csv import read_library_csv
from station.model.design_io import design_from_dict
from station.model.difference import delta_e
from tests.api.conftest import Api

V1 = "/api/v1"
ANGLES = (15.0, 45.0, 110.0)
DESIGN = {
    "name": "Blue metallic",
    "face": [62.0, -4.0, -38.0],
    "flop": [24.0, 1.0, -20.0],
    "travel_deg": 70.0,
    "gloss_gu": 88.0,
}
CSV = (
    "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\n"
    "R-1,solid,90,40,50,30,40,50,30,40,50,30\n"
    "M-1,metallic,85,90,-2,-30,60,-1,-25,30,0,-15\n"
)


@pytest.fixture
def lib_api(sqlite_api: Api) -> tuple[Api, list[dict]]:
    """The service with a small SYNTHETIC library (with recipes) in its database."""
    rows = library_rows(generate_library(n_solid=60, n_metallic=40, n_pearl=20, seed=3))
    with sqlite_api.client.app.state.sessions() as session:  # type: ignore[attr-defined]
        session.execute(insert(LibraryPaint), rows)
        session.commit()
    return sqlite_api, rows


def _stored_lab(rows: list[dict]) -> np.ndarray:
    return np.array([[r["lab"][[float(a) for a in r["angles_deg"]].index(a)] for a in ANGLES] for r in rows])


def _counts(api: Api) -> tuple[int, int]:
    get = lambda p: api.client.get(f"{V1}/{p}", headers=api.auth("admin")).json()["count"]  # noqa: E731
    return get("library"), get("audit")


@pytest.mark.parametrize("metric", ["cie76", "cie2000", "din6175"])
def test_snap_is_the_brute_force_top_k(lib_api: tuple[Api, list[dict]], metric: str) -> None:
    api, rows = lib_api
    target = design_from_dict(DESIGN).lab_at(np.array(ANGLES))
    r = api.client.post(
        f"{V1}/formulation/snap",
        json={"design": DESIGN, "k": 4, "metric": metric},
        headers=api.auth("chemist"),
    )
    assert r.status_code == 200, r.text
    got = r.json()
    lab = _stored_lab(rows)  # the design is the reference
    per_angle = delta_e(np.broadcast_to(target, lab.shape), lab, method=metric, aspecular_deg=ANGLES)
    sums = per_angle.sum(axis=1)
    order = np.argsort(sums, kind="stable")[:4]
    assert [m["code"] for m in got["matches"]] == [rows[i]["code"] for i in order]
    np.testing.assert_allclose([m["sum_de"] for m in got["matches"]], sums[order], rtol=1e-9)
    np.testing.assert_allclose([m["de_per_angle"] for m in got["matches"]], per_angle[order], rtol=1e-9)
    assert got["matches"][0]["recipe"] == rows[int(order[0])]["extra"]["recipe"]
    assert got["library_paints"] == len(rows) and got["synthetic"] is True
    # the same target as Lab triples gives the same answer
    by_lab = api.client.post(
        f"{V1}/formulation/snap",
        json={"lab": target.tolist(), "k": 4, "metric": metric},
        headers=api.auth("admin"),
    ).json()
    assert [m["code"] for m in by_lab["matches"]] == [m["code"] for m in got["matches"]]


def test_snap_index_is_built_once_per_library(lib_api: tuple[Api, list[dict]]) -> None:
    api, _ = lib_api
    for k in (1, 2, 3):
        assert (
            api.client.post(
                f"{V1}/formulation/snap", json={"design": DESIGN, "k": k}, headers=api.auth("chemist")
            ).status_code
            == 200
        )
    cache = api.client.app.state.library_cache  # type: ignore[attr-defined]
    assert cache.builds == 1
    assert (
        api.client.post(f"{V1}/library/import", content=CSV, headers=api.auth("chemist")).status_code == 201
    )
    assert (
        api.client.post(
            f"{V1}/formulation/snap", json={"lab": [[40, 50, 30]] * 3, "k": 1}, headers=api.auth("chemist")
        ).json()["matches"][0]["code"]
        == "R-1"
    )
    assert cache.builds == 2  # rebuilt once for the changed library


def test_snap_refusals(sqlite_api: Api) -> None:
    c, chem = sqlite_api.client, sqlite_api.auth("chemist")
    assert c.post(f"{V1}/formulation/snap", json={"design": DESIGN}, headers=chem).status_code == 409  # empty
    r = c.post(f"{V1}/formulation/snap", json={"design": DESIGN, "lab": [[50, 0, 0]] * 3}, headers=chem)
    assert r.status_code == 422 and "exactly one" in r.json()["detail"][0]["msg"]
    r = c.post(f"{V1}/formulation/snap", json={"lab": [[50, 0, 0]] * 2}, headers=chem)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][:2] == ["body", "lab"]
    r = c.post(f"{V1}/formulation/snap", json={"design": DESIGN, "metric": "cie94"}, headers=chem)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][:2] == ["body", "metric"]
    assert c.post(f"{V1}/formulation/snap", json={"design_id": 99}, headers=chem).status_code == 404


def test_formulate_predicted_de_is_the_colorant_models(lib_api: tuple[Api, list[dict]]) -> None:
    api, _ = lib_api
    target = design_from_dict(DESIGN).lab_at(np.array(ANGLES))
    r = api.client.post(
        f"{V1}/formulation/formulate", json={"design": DESIGN, "tolerance": 1.0}, headers=api.auth("chemist")
    )
    assert r.status_code == 200, r.text
    got = r.json()
    names = default_database().names
    c = np.array([got["recipe"].get(n, 0.0) for n in names])
    predicted = predict_lab(c, ANGLES)
    np.testing.assert_allclose(got["predicted_lab"], predicted, atol=1e-3)  # fractions < 1e-6 are omitted
    np.testing.assert_allclose(got["de_per_angle"], delta_e(predicted, target, method="cie2000"), atol=1e-3)
    assert got["mean_de"] == pytest.approx(np.mean(got["de_per_angle"]))
    assert got["formulable"] is (got["mean_de"] <= 1.0)
    assert got["synthetic_colorants"] is True and got["matches"]
    r = api.client.post(
        f"{V1}/formulation/formulate", json={"design": DESIGN, "tolerance": 0.0}, headers=api.auth("chemist")
    )
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][:2] == ["body", "tolerance"]


@pytest.mark.parametrize("kind", ["solid", "pearl"])
def test_formulate_starts_only_from_the_chosen_types_nearest_matches(
    lib_api: tuple[Api, list[dict]], kind: str
) -> None:
    api, rows = lib_api
    body = {"design": DESIGN, "types": [kind], "k": 3, "library": rows[0]["extra"]["library"]}
    r = api.client.post(f"{V1}/formulation/formulate", json=body, headers=api.auth("chemist"))
    assert r.status_code == 200, r.text
    got = r.json()
    # brute force: summed CIEDE2000 over 15/45/110 against every stored paint of that type
    target = design_from_dict(DESIGN).lab_at(np.array(ANGLES))
    of_kind = [r for r in rows if r["category"] == kind]
    sums = np.array([delta_e(lab, target, method="cie2000").sum() for lab in _stored_lab(of_kind)])
    expected = [of_kind[i]["code"] for i in np.argsort(sums)[:3]]
    assert [m["code"] for m in got["matches"]] == expected
    assert {m["type"] for m in got["matches"]} == {kind}
    np.testing.assert_allclose([m["sum_de"] for m in got["matches"]], np.sort(sums)[:3], atol=1e-9)


def test_formulate_refuses_an_unknown_type_or_library_naming_the_field(
    lib_api: tuple[Api, list[dict]],
) -> None:
    api, _ = lib_api
    before = _counts(api)
    for body, field in (
        ({"design": DESIGN, "types": ["chrome"]}, "types"),
        ({"design": DESIGN, "types": []}, "types"),
        ({"design": DESIGN, "library": "no-such-library"}, "library"),
    ):
        r = api.client.post(f"{V1}/formulation/formulate", json=body, headers=api.auth("chemist"))
        assert r.status_code == 422, r.text
        assert field in r.text
    assert _counts(api) == before


def test_formulate_a_stored_design_version(lib_api: tuple[Api, list[dict]]) -> None:
    api, _ = lib_api
    d = api.client.post(
        f"{V1}/designs", json={"name": "Blue", "design": DESIGN}, headers=api.auth("stylist")
    ).json()
    r = api.client.post(
        f"{V1}/formulation/formulate", json={"design_id": d["id"], "version": 1}, headers=api.auth("chemist")
    )
    assert r.status_code == 200, r.text
    np.testing.assert_allclose(
        r.json()["design_lab"], design_from_dict(DESIGN).lab_at(np.array(ANGLES)), atol=1e-9
    )
    assert (
        api.client.post(
            f"{V1}/formulation/formulate",
            json={"design_id": d["id"], "version": 2},
            headers=api.auth("chemist"),
        ).status_code
        == 404
    )


@pytest.mark.parametrize("fmt", ["xml", "cxf"])
def test_export_reads_back_with_the_match(lib_api: tuple[Api, list[dict]], fmt: str) -> None:
    api, _ = lib_api
    r = api.client.post(
        f"{V1}/formulation/export",
        json={"design": DESIGN, "format": fmt, "five_angles": True},
        headers=api.auth("chemist"),
    )
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("application/xml")
    assert f'filename="Blue_metallic.{fmt}"' in r.headers["content-disposition"]
    specs = read_color_xml(r.content) if fmt == "xml" else read_cxf_specs(r.content)
    assert [s.role for s in specs] == ["design", "match"]
    design = design_from_dict(DESIGN)
    for s in specs[0].sets:
        np.testing.assert_allclose(s.lab, design.lab_at(np.asarray(s.angles_deg)), atol=1e-4)
    assert {tuple(s.angles_deg) for s in specs[0].sets} >= {(15.0, 45.0, 110.0), (25.0, 45.0, 75.0)}
    snap = api.client.post(
        f"{V1}/formulation/snap", json={"design": DESIGN, "k": 1}, headers=api.auth("chemist")
    ).json()
    assert specs[1].code == r.headers["x-match-code"] == snap["matches"][0]["code"]
    alone = api.client.post(
        f"{V1}/formulation/export", json={"design": DESIGN, "match": False}, headers=api.auth("chemist")
    )
    assert [s.role for s in read_color_xml(alone.content)] == ["design"]


def test_library_import_and_export_round_trip(sqlite_api: Api) -> None:
    c, chem = sqlite_api.client, sqlite_api.auth("chemist")
    r = c.post(
        f"{V1}/library/import",
        params={"name": "lab paints"},
        content=CSV,
        headers=chem | {"Content-Type": "text/csv"},
    )
    assert r.status_code == 201, r.text
    assert r.json() == {
        "library": "lab paints",
        "paints": 2,
        "angles_deg": [15.0, 45.0, 110.0],
        "types": {"solid": 1, "metallic": 1, "pearl": 0},
    }
    paint = c.get(f"{V1}/library/M-1", headers=sqlite_api.auth("stylist")).json()
    assert paint["lab"][0] == [90.0, -2.0, -30.0] and paint["extra"]["library"] == "lab paints"
    exported = c.get(f"{V1}/library/export.csv", headers=sqlite_api.auth("qa"))
    assert exported.status_code == 200 and exported.headers["content-type"].startswith("text/csv")
    back = read_library_csv(io.StringIO(exported.text))
    original = read_library_csv(io.StringIO(CSV))
    assert list(back.codes) == list(original.codes)
    np.testing.assert_allclose(back.lab, original.lab, atol=1e-4)
    solids = c.get(f"{V1}/library/export.csv", params={"category": "solid"}, headers=chem)
    assert list(read_library_csv(io.StringIO(solids.text)).codes) == ["R-1"]
    events = c.get(f"{V1}/audit", params={"entity": "library"}, headers=sqlite_api.auth("admin")).json()
    assert events["data"][0]["action"] == "library.import" and events["data"][0]["detail"]["paints"] == 2


def test_failed_imports_store_nothing(sqlite_api: Api) -> None:
    c, chem = sqlite_api.client, sqlite_api.auth("chemist")
    assert c.post(f"{V1}/library/import", content=CSV, headers=chem).status_code == 201
    before = _counts(sqlite_api)
    again = CSV.replace("M-1", "M-2")  # R-1 is already stored: nothing of this file is added
    assert c.post(f"{V1}/library/import", content=again, headers=chem).status_code == 409
    bad = CSV.replace("40,50,30,40", "400,50,30,40", 1)  # L15 out of range on row 2
    r = c.post(f"{V1}/library/import", content=bad.replace("R-1", "R-9"), headers=chem)
    assert r.status_code == 422
    loc = r.json()["detail"][0]["loc"]
    assert loc[0] == "body" and "row 2" in loc[1] and "L15" in loc[1]
    assert c.post(f"{V1}/library/import", content=b"\xff\xfe", headers=chem).status_code == 422
    assert c.post(f"{V1}/library/import", params={"name": ""}, content=CSV, headers=chem).status_code == 422
    # over the 1 MiB cap of other routes but under the upload's own: read, refused as CSV, nothing stored
    # (the upload cap itself: tests/api/test_library_service.py)
    assert c.post(f"{V1}/library/import", content="x" * 1_100_000, headers=chem).status_code == 422
    assert _counts(sqlite_api) == before


def test_browse_filters_like_the_thesis_browser(lib_api: tuple[Api, list[dict]]) -> None:
    from station.model.indices import library_indices

    api, rows = lib_api
    lab = _stored_lab(rows)
    flop = [library_indices(*lab[i]).flop_index for i in range(len(rows))]
    expected = [
        r["code"]
        for r, f in zip(rows, flop, strict=True)
        if r["category"] in ("metallic", "pearl") and f is not None and 3.0 <= f <= 12.0
    ]
    params: dict[str, float | list[str]] = {
        "types": ["metallic", "pearl"],
        "flop_min": 3.0,
        "flop_max": 12.0,
        "limit": 1000,
    }
    r = api.client.get(f"{V1}/library/browse", params=params, headers=api.auth("stylist"))
    assert r.status_code == 200, r.text
    got = r.json()
    assert [p["code"] for p in got["paints"]] == expected and got["matched"] == len(expected) > 0
    for p in got["paints"]:
        assert p["indices"]["flop"] == pytest.approx(
            flop[[x["code"] for x in rows].index(p["code"])], rel=1e-9
        )
    reds = api.client.get(
        f"{V1}/library/browse", params={"set": "solids", "group": "red"}, headers=api.auth("qa")
    ).json()
    assert all(p["group"] == ["solids", "chromatic", "red"] for p in reds["paints"])
    assert reds["matched"] == got["hierarchy"]["solids"]["chromatic"].get("red", 0)
    bad = api.client.get(
        f"{V1}/library/browse", params={"chroma_min": 5, "chroma_max": 1}, headers=api.auth("qa")
    )
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"][:2] == ["body", "chroma"]
    bad = api.client.get(f"{V1}/library/browse", params={"group": "purple"}, headers=api.auth("qa"))
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"][:2] == ["query", "group"]


def test_closed_loop_is_stored_with_its_history(lib_api: tuple[Api, list[dict]]) -> None:
    api, rows = lib_api
    # a design inside the colorant gamut: a library paint's own colour (its recipe reproduces it)
    lab = _stored_lab(rows)[5]
    face, flop = [round(float(x), 4) for x in lab[0]], [round(float(x), 4) for x in lab[2]]
    body = {
        "name": "in gamut",
        "face": face,
        "flop": flop,
        "travel_deg": None if face == flop else 60.0,
        "gloss_gu": 80.0,
    }
    d = api.client.post(
        f"{V1}/designs", json={"name": "in gamut", "design": body}, headers=api.auth("stylist")
    )
    assert d.status_code == 201, d.text
    before = _counts(api)
    r = api.client.post(
        f"{V1}/formulation/closed-loop",
        json={"design_id": d.json()["id"], "corrections": 3},
        headers=api.auth("chemist"),
    )
    assert r.status_code == 201, r.text
    job = r.json()
    assert job["steps"] and job["steps"][0]["kind"] == "initial" and "SYNTHETIC" in job["measurement"]
    assert job["corrections"] == len(job["steps"]) - 1 <= 3
    # each step's ΔE is the measured Lab against the design (CIEDE2000), recomputed here
    design_lab = np.asarray(job["design_lab"])
    for step in job["steps"]:
        de = delta_e(design_lab, np.asarray(step["measured_lab"]), method="cie2000")
        np.testing.assert_allclose(step["de_per_angle"], de, atol=1e-6)
        assert step["mean_de"] == pytest.approx(float(np.mean(de)), abs=1e-6)
        # the recipe weighed out as 1 kg: fraction × 1000 g, binder the rest
        assert step["batch"]["total_g"] == 1000.0
        assert step["batch"]["binder_g"] == pytest.approx(1000.0 * (1 - sum(step["recipe"].values())))
    for before, after in zip(
        job["steps"], job["steps"][1:], strict=False
    ):  # tinting additions per correction
        add = after["additions"]
        if not add["remake"]:  # adding to the mixed batch reaches the corrected proportions
            total = add["new_total_g"]
            for name, frac in after["recipe"].items():
                mixed = 1000.0 * before["recipe"].get(name, 0.0) + add["additions_g"].get(name, 0.0)
                assert mixed == pytest.approx(frac * total, abs=1e-6)
    assert (job["status"] == "converged") is (job["steps"][-1]["mean_de"] <= 1.0)
    stored = api.client.get(f"{V1}/recipes/{job['recipe_id']}", headers=api.auth("qa")).json()
    assert stored["recipe"] == job["final_recipe"] and stored["state"] in ("done", "failed")
    events = api.client.get(f"{V1}/audit", params={"entity": "recipe"}, headers=api.auth("admin")).json()[
        "data"
    ]
    assert events[0]["action"] == "recipe.closed_loop" and events[0]["detail"]["status"] == job["status"]
    assert _counts(api)[1] == before[1] + 1
    refused = api.client.post(
        f"{V1}/formulation/closed-loop",
        json={"design_id": d.json()["id"], "corrections": 9},
        headers=api.auth("chemist"),
    )
    assert refused.status_code == 422 and refused.json()["detail"][0]["loc"][:2] == ["body", "corrections"]


def test_formulate_says_when_the_colorant_limit_refuses_the_design(lib_api: tuple[Api, list[dict]]) -> None:
    """The viewer's demo red needs more than 5 colorants (a brute force over every 5-subset of the pearl
    line reaches 1.47, bench:formulate-independent): the service's miss says so with the N-colorant
    gamut's verdict (station.formulate.gamut.recipe_gamut), a recipe of at most 5 colorants."""
    api, _ = lib_api
    red = {"name": "red", "face": [62.0, 48.0, 30.0], "flop": [24.0, 38.0, 18.0], "travel_deg": 70.0}
    body = {"design": {**red, "gloss_gu": 88.0}}
    r = api.client.post(f"{V1}/formulation/formulate", json=body, headers=api.auth("chemist"))
    assert r.status_code == 200, r.text
    got = r.json()
    gamut = got["gamut"]
    assert not got["formulable"] and not gamut["inside"] and gamut["line_inside"]
    assert gamut["max_colorants"] == 5 and gamut["needed_colorants"] > 5
    assert gamut["mean_de"] > 1.0 >= gamut["line_mean_de"]
    assert gamut["message"].startswith("outside the 5-colorant gamut of line ")
    assert f"max colorants {gamut['needed_colorants']}" in gamut["message"]
    assert got["message"].endswith(gamut["message"])
    assert len([n for n in gamut["recipe"] if n != "matting_silica"]) <= 5


def test_formulate_takes_the_chemists_options(lib_api: tuple[Api, list[dict]]) -> None:
    """The advice of a miss can be acted on over HTTP: the demo red with ``max_colorants`` raised to the
    count the gamut named gets a recipe of at most that many colorants from the named line, amounts on the
    chosen scale (a 1000 g batch's grams are whole multiples of ``scale_resolution_g``); out-of-range options
    are 422s naming the field, and nothing is stored."""
    api, _ = lib_api
    red = {"name": "red", "face": [62.0, 48.0, 30.0], "flop": [24.0, 38.0, 18.0], "travel_deg": 70.0}
    url, auth = f"{V1}/formulation/formulate", api.auth("chemist")
    first = api.client.post(url, json={"design": {**red, "gloss_gu": 88.0}}, headers=auth).json()
    needed = first["gamut"]["needed_colorants"]
    line = first["gamut"]["line"]
    body = {
        "design": {**red, "gloss_gu": 88.0},
        "max_colorants": needed,
        "line": line,
        "scale_resolution_g": 0.5,
    }
    r = api.client.post(url, json=body, headers=auth)
    assert r.status_code == 200, r.text
    got = r.json()
    colorants = [n for n, v in got["recipe"].items() if v > 0 and n not in ("binder", "matting_silica")]
    assert len(colorants) <= needed
    assert got["mean_de"] < first["mean_de"]
    for grams in got["batch"]["colorants_g"].values():
        assert grams / 0.5 == pytest.approx(round(grams / 0.5), abs=1e-6)
    before = _counts(api)
    for field, value in (
        ("max_colorants", 0),
        ("max_colorants", 11),
        ("scale_resolution_g", 0.0),
        ("line", "gold"),
    ):
        bad = api.client.post(url, json={"design": red, field: value}, headers=auth)
        assert bad.status_code == 422, (field, bad.text)
        assert field in str(bad.json()["detail"]), (field, bad.text)
    assert _counts(api) == before
