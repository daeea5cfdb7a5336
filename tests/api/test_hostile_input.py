"""Hostile input against the service: each case a request an attacker (or a bad day) sends, answered 422.

Found 1 (instrument address reaching pyserial's ``spy://``), Found 2 (NaN/±Infinity/1e309/lone
surrogates → 500), Found 4 (NUL, year 1/9999 with an offset, bare CR and oversized CSV fields, CRLF in
a library code, bool/str coerced into Lab) and Found 5 (CSV injection). The expectation is always the
HTTP contract (docs/api.md): 422 with ``loc`` naming the field, never 500.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from station.csv_cells import FORMULA_LEADS
from tests.api.conftest import Api, make_api
from tests.ingest._readings import make_reading

V1 = "/api/v1"
HEADER = "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\n"
ROW = ",solid,90,40,50,30,40,50,30,40,50,30\n"
DESIGN = {"face": [50, 1, 1], "flop": [30, 1, 1], "travel_deg": 60}


@pytest.fixture
def tapi(tmp_path: Path) -> Iterator[Api]:
    """The service on a SQLite file in its own data folder (as ``station serve`` lays it out)."""
    yield from make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)


def _digest(path: Path) -> tuple[int, str]:
    data = path.read_bytes()
    return len(data), hashlib.sha256(data).hexdigest()


def _post_raw(api: Api, path: str, body: bytes, role: str = "admin") -> tuple[int, dict[str, object]]:
    r = api.client.post(path, content=body, headers={**api.auth(role), "content-type": "application/json"})
    return r.status_code, r.json()


# -- Found 1: the instrument address ------------------------------------------------------------------
def test_found1_spy_url_cannot_touch_the_database(tapi: Api, tmp_path: Path) -> None:
    db = tmp_path / "station.sqlite3"
    tapi.client.post(f"{V1}/panels", json={"job": "J-1", "part": "door"}, headers=tapi.auth("technician"))
    before = _digest(db)
    assert before[0] > 0
    r = tapi.client.post(
        f"{V1}/instruments/connect",
        json={"address": f"ma6@spy:///dev/null?file={db}"},
        headers=tapi.auth("technician"),
    )
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"] == ["body", "address"]
    assert _digest(db) == before  # not truncated, not written
    panels = tapi.client.get(f"{V1}/panels", headers=tapi.auth("qa")).json()
    assert panels["count"] == 1


@pytest.mark.parametrize(
    "address",
    [
        "ma6@loop://",
        "ma6@hwgrep://.*",
        "ma6@socket://127.0.0.1:5432",
        "ma6@rfc2217://192.0.2.7:2217",
        "ma6@/etc/passwd",
        "ma6@/root/.ssh/id_rsa",
        "gloss@hid:/etc/shadow",
        "ma6@/dev/ttyUSB0/../../etc/passwd",
    ],
)
def test_found1_other_transports_are_422_without_filesystem_facts(tapi: Api, address: str) -> None:
    r = tapi.client.post(
        f"{V1}/instruments/connect", json={"address": address}, headers=tapi.auth("technician")
    )
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"] == ["body", "address"]
    text = r.text.lower()
    for fact in ("exist", "permission", "no such file", "denied", "errno", "directory"):
        assert fact not in text


def test_found1_an_absent_allowed_device_says_nothing_about_files(tapi: Api) -> None:
    r = tapi.client.post(
        f"{V1}/instruments/connect", json={"address": "ma6@/dev/ttyUSB97"}, headers=tapi.auth("technician")
    )
    assert r.status_code == 404
    assert r.json() == {"detail": "no instrument answers at ma6@/dev/ttyUSB97"}


def test_found1_tcp_only_to_configured_hosts(tmp_path: Path) -> None:
    import socket

    with socket.socket() as s:  # a loopback port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    for api in make_api(
        f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path, instrument_hosts=(f"127.0.0.1:{port}",)
    ):
        tech = api.auth("technician")
        allowed = api.client.post(
            f"{V1}/instruments/connect", json={"address": f"ma6@socket://127.0.0.1:{port}"}, headers=tech
        )
        assert allowed.status_code == 404, allowed.text  # admitted, nothing answers
        other = api.client.post(
            f"{V1}/instruments/connect", json={"address": f"ma6@socket://127.0.0.1:{port + 1}"}, headers=tech
        )
        assert other.status_code == 422 and other.json()["detail"][0]["loc"] == ["body", "address"]


def test_instrument_hosts_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    from station.api import Settings

    monkeypatch.setenv("CACAD_INSTRUMENT_HOSTS", "10.0.0.9, lab-bridge:4001")
    assert Settings().instrument_hosts == ("10.0.0.9", "lab-bridge:4001")
    monkeypatch.setenv("CACAD_INSTRUMENT_HOSTS", "bad host!")
    with pytest.raises(ValueError, match="instrument_hosts"):
        Settings()


# -- Found 2: non-finite numbers and surrogates in JSON -----------------------------------------------
NON_FINITE = [b"NaN", b"Infinity", b"-Infinity", b"1e309", b"-1e309"]


@pytest.mark.parametrize("token", NON_FINITE)
def test_found2_non_finite_numbers_are_422_naming_the_field(tapi: Api, token: bytes) -> None:
    body = b'{"name": "d", "design": {"face": [' + token + b', 1, 1], "flop": [30, 1, 1], "travel_deg": 60}}'
    status, out = _post_raw(tapi, f"{V1}/designs", body)
    assert status == 422
    assert out["detail"][0]["loc"] == ["body", "design", "face", 0]  # type: ignore[index]
    reading = make_reading(51, 0).model_dump(mode="json")
    reading["gloss_gu"] = "__X__"
    raw = json.dumps(reading).replace('"__X__"', token.decode()).encode()
    status, out = _post_raw(tapi, f"{V1}/measurements", raw)
    assert status == 422 and out["detail"][0]["loc"] == ["body", "gloss_gu"]  # type: ignore[index]


@pytest.mark.parametrize("raw", [b'"\\ud800"', b'"x\\udfffy"', b'"\xed\xa0\x80"'])
def test_found2_lone_surrogates_are_422(tapi: Api, raw: bytes) -> None:
    status, out = _post_raw(tapi, f"{V1}/panels", b'{"job": ' + raw + b', "part": "door"}')
    assert status == 422 and out["detail"][0]["loc"] == ["body", "job"]  # type: ignore[index]
    status, out = _post_raw(tapi, f"{V1}/panels", b'{"job": "J", "part": "door", ' + raw + b": 1}")
    assert status == 422 and out["detail"][0]["loc"][0] == "body"  # type: ignore[index]


def test_found2_the_validation_body_never_echoes_the_input(tapi: Api) -> None:
    big = "x" * 100_000
    r = tapi.client.post(f"{V1}/panels", json={"job": big, "part": "door"}, headers=tapi.auth("admin"))
    assert r.status_code == 422 and len(r.content) < 2000 and "input" not in r.json()["detail"][0]
    # bytes where a JSON object is expected (text/plain body): no input echoed, no 500
    r = tapi.client.post(
        f"{V1}/panels",
        content=b"\xff\xfe\x00garbage",
        headers={**tapi.auth("admin"), "content-type": "text/plain"},
    )
    assert r.status_code == 422 and "input" not in r.json()["detail"][0]


# -- Found 4 ------------------------------------------------------------------------------------------
def test_found4_nul_in_free_text_is_422(tapi: Api) -> None:
    status, out = _post_raw(tapi, f"{V1}/panels", b'{"job": "J", "part": "door", "notes": "a\\u0000b"}')
    assert status == 422 and out["detail"][0]["loc"] == ["body", "notes"]  # type: ignore[index]
    r = tapi.client.get(f"{V1}/panels", params={"job": "a\x00b"}, headers=tapi.auth("qa"))
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "job"]


@pytest.mark.parametrize("when", ["0001-01-01T00:00:00+05:00", "9999-12-31T23:59:59-05:00"])
def test_found4_out_of_range_dates_are_422(tapi: Api, when: str) -> None:
    reading = make_reading(52, 0).model_dump(mode="json") | {"measured_at": when}
    r = tapi.client.post(f"{V1}/measurements", json=reading, headers=tapi.auth("technician"))
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "measured_at"]


@pytest.mark.parametrize("value", [True, "55.3"])
def test_found4_bool_and_numeric_strings_are_not_lab(tapi: Api, value: object) -> None:
    reading = make_reading(53, 0).model_dump(mode="json")
    reading["lab"][0][0] = value
    r = tapi.client.post(f"{V1}/measurements", json=reading, headers=tapi.auth("technician"))
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "lab", 0, 0]
    design = {"name": "d", "design": {**DESIGN, "face": [value, 1, 1]}}
    r = tapi.client.post(f"{V1}/designs", json=design, headers=tapi.auth("stylist"))
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "design", "face", 0]


def _import(api: Api, text: str, **params: str | bool) -> tuple[int, dict[str, object]]:
    r = api.client.post(
        f"{V1}/library/import",
        content=text.encode("utf-8", "surrogatepass"),
        params=params,
        headers={**api.auth("chemist"), "content-type": "text/csv"},
    )
    return r.status_code, r.json()


@pytest.mark.parametrize(
    ("text", "where"),
    [
        (HEADER + "R-1" + ROW.replace("\n", "\r") + "R-2" + ROW, "row 2"),  # bare CR ends no record
        (HEADER + "R-1,solid," + "9" * 140_000 + ROW[9:], "row 2"),  # field over 131072 characters
        (HEADER + '"' + "x" * 140_000 + '"' + ROW, "row 2"),
        (HEADER + '"R-1\r\nX-Evil: 1"' + ROW, "row 2, column 'code'"),  # CRLF inside a code
        (HEADER + "R-\x001" + ROW, "row 2, column 'code'"),
        (HEADER + "\ud800" + ROW, "body"),  # not UTF-8
    ],
)
def test_found4_hostile_library_csv_is_422_naming_row_and_column(tapi: Api, text: str, where: str) -> None:
    status, out = _import(tapi, text)
    assert status == 422, out
    assert out["detail"][0]["loc"][-1] == where  # type: ignore[index]


def test_found4_crlf_in_a_stored_code_keeps_the_export_response_whole(tapi: Api) -> None:
    """A code that reached the database with CR/LF (before import refused it) cannot split the header."""
    from sqlalchemy import insert

    from db.models import LibraryPaint
    from station.api.services.library import library_rows
    from station.formulate.demo import generate_library

    app = tapi.client.app
    lib = generate_library(n_solid=3, n_metallic=0, n_pearl=0, seed=2)
    rows = library_rows(lib)
    for row in rows:
        row["code"] = f"{row['code']}\r\nX-Evil: 1"
    with app.state.sessions() as session:  # type: ignore[attr-defined]
        session.execute(insert(LibraryPaint), rows)
        session.commit()
    r = tapi.client.post(
        f"{V1}/formulation/export",
        json={"design": DESIGN, "format": "xml", "match": True},
        headers=tapi.auth("chemist"),
    )
    assert r.status_code == 200, r.text
    assert "x-evil" not in r.headers and "%0D%0AX-Evil" in r.headers["x-match-code"]


# -- Found 5: CSV injection ---------------------------------------------------------------------------
@pytest.mark.parametrize("lead", FORMULA_LEADS)
def test_found5_library_import_refuses_formula_codes_unless_asked(tapi: Api, lead: str) -> None:
    # a tab or CR lead cannot smuggle a formula in: the code is stripped, then checked
    code = f"{lead}HYPERLINK(1)" if lead not in "\t\r" else f"{lead}=HYPERLINK(1)"
    text = HEADER + f'"{code}"' + ROW
    status, out = _import(tapi, text, name="formulas")
    assert status == 422 and "column 'code'" in out["detail"][0]["loc"][-1]  # type: ignore[index]


def test_found5_library_export_escapes_formula_codes(tapi: Api) -> None:
    codes = ["=1+2", "+SUM(A1)", "-2+3", "@cmd", "R-1"]
    text = HEADER + "".join(f"{c}{ROW}" for c in codes)
    status, out = _import(tapi, text, name="formulas", allow_formulas=True)
    assert status == 201, out
    r = tapi.client.get(f"{V1}/library/export.csv", headers=tapi.auth("qa"))
    got = {row["code"] for row in csv.DictReader(io.StringIO(r.text))}
    assert got == {"'=1+2", "'+SUM(A1)", "'-2+3", "'@cmd", "R-1"}  # OWASP: one leading single quote


def test_found5_measurement_export_escapes_text_cells_not_numbers(tapi: Api) -> None:
    reading = make_reading(54, 0).model_dump(mode="json")
    reading["operator"] = '=HYPERLINK("http://x")'
    reading["panel"] = {"job": "@SUM(1)", "part": "door"}
    reading["panel_id"] = None
    reading["lab"][0] = [40.0, -1.5, -12.25]
    r = tapi.client.post(f"{V1}/measurements", json=reading, headers=tapi.auth("technician"))
    assert r.status_code == 201, r.text
    r = tapi.client.get(f"{V1}/measurements/export.csv", headers=tapi.auth("qa"))
    rows = list(csv.DictReader(io.StringIO(r.text)))
    assert rows and all(row["operator"] == '\'=HYPERLINK("http://x")' for row in rows)
    assert all(row["job"] == "'@SUM(1)" for row in rows)
    first = min(rows, key=lambda row: float(row["aspecular_deg"]))
    assert (first["a"], first["b"]) == ("-1.5", "-12.25")  # numbers are not formulas
    for row in rows:
        for key, cell in row.items():
            if key not in ("L", "a", "b", "aspecular_deg", "gloss_gu", "gloss_geometry_deg"):
                assert not cell.startswith(FORMULA_LEADS), (key, cell)


# -- over real HTTP: every refusal keeps the keep-alive connection ------------------------------------
def test_bad_requests_on_one_connection_against_station_serve(tmp_path: Path) -> None:
    import httpx

    from tests.api.test_serve import _serve

    db = tmp_path / "station.sqlite3"
    reading = make_reading(55, 0).model_dump(mode="json")
    reading["lab"][1][2] = "__X__"
    bad_json = [
        ("/instruments/connect", json.dumps({"address": f"ma6@spy:///dev/null?file={db}"}).encode()),
        ("/designs", b'{"name":"d","design":{"face":[NaN,1,1],"flop":[30,1,1],"travel_deg":60}}'),
        ("/designs", b'{"name":"d","design":{"face":[1e309,1,1],"flop":[30,1,1],"travel_deg":60}}'),
        ("/panels", b'{"job":"\xed\xa0\x80","part":"door"}'),
        ("/panels", b'{"job":"J","part":"door","notes":"a\\u0000b"}'),
        ("/measurements", json.dumps(reading).replace('"__X__"', "true").encode()),
        ("/measurements", json.dumps(reading).replace('"__X__"', '"-Infinity"').encode()),
    ]
    bad_csv = [
        (HEADER + "R-1" + ROW.replace("\n", "\r") + "R-2" + ROW).encode(),
        (HEADER + "R-1,solid," + "9" * 140_000 + ROW[9:]).encode(),
        (HEADER + '"R-1\r\nX-Evil: 1"' + ROW).encode(),
        (HEADER + "=HYPERLINK(1)" + ROW).encode(),
    ]
    with _serve(tmp_path) as (base, token), httpx.Client(base_url=base + V1, timeout=30) as client:
        auth = {"Authorization": f"Bearer {token}"}
        before = _digest(db)
        ports = set()
        for path, body in bad_json:
            r = client.post(path, content=body, headers={**auth, "content-type": "application/json"})
            assert r.status_code == 422, (path, r.status_code, r.text[:200])
            assert r.json()["detail"][0]["loc"][0] == "body"
            ports.add(r.extensions["network_stream"].get_extra_info("socket").getsockname()[1])
        for body in bad_csv:
            r = client.post("/library/import", content=body, headers={**auth, "content-type": "text/csv"})
            assert r.status_code == 422, (r.status_code, r.text[:200])
            ports.add(r.extensions["network_stream"].get_extra_info("socket").getsockname()[1])
        assert len(ports) == 1  # one connection carried every refusal
        assert client.get("/me", headers=auth).status_code == 200
        assert _digest(db)[0] >= before[0] > 0  # the database is still there (it may have grown)
