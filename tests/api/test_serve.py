"""``station serve`` as a real process over real HTTP (uvicorn on a free loopback port).

First start: migrations applied, the bootstrap admin token printed, a simulated MA6 attached,
calibrated and measured through the API, the measurement queryable. "Printed once" is checked
in-process (the serve handler with uvicorn stubbed) to keep the suite fast.
"""

from __future__ import annotations

import re
import stat
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi import FastAPI

from station.api.settings import BOOTSTRAP_TOKEN_FILE
from tests.serve_process import ServeStartError, serving

REPO = Path(__file__).resolve().parents[2]


@contextmanager
def _serve(data_dir: Path, *extra: str) -> Iterator[tuple[str, str]]:
    """A real ``station serve`` (no demo library) of this checkout: (base URL, admin token)."""
    try:
        with serving(data_dir, "--no-demo-library", *extra, cwd=REPO, start_timeout_s=60) as svc:
            yield svc.base, svc.token
    except ServeStartError as exc:
        pytest.fail(str(exc))


def test_serve_first_start_real_http(tmp_path: Path) -> None:
    with _serve(tmp_path, "--simulators", "ma6") as (base, token):
        assert token, "bootstrap admin token not printed on first start"
        auth = {"Authorization": f"Bearer {token}"}
        with httpx.Client(base_url=base, timeout=30) as http:
            assert http.get("/health").json()["database"] == "ok"
            assert http.get("/api/v1/instruments").status_code == 401
            instruments = http.get("/api/v1/instruments", headers=auth).json()
            assert [i["model"] for i in instruments] == ["MA6"] and instruments[0]["simulated"]
            inst = instruments[0]["id"]
            cal = http.post(f"/api/v1/instruments/{inst}/calibrate", json={"reference": "W-17"}, headers=auth)
            assert cal.status_code == 200 and cal.json()["passed"] is True
            panel = http.post("/api/v1/panels", json={"job": "J-9", "part": "fender"}, headers=auth).json()
            r = http.post(f"/api/v1/instruments/{inst}/measure", json={"panel_id": panel["id"]}, headers=auth)
            assert r.status_code == 201, r.text
            m = r.json()["measurement"]
            assert r.json()["status"] == "stored"
            assert m["geometries_deg"] == [-15.0, 15.0, 25.0, 45.0, 75.0, 110.0]
            assert m["calibration_id"] is not None and len(m["spectra"][0]) == 31
            L = [lab[0] for lab in m["lab"]]
            assert all(0 < v < 200 for v in L)
            listed = http.get("/api/v1/measurements", params={"job": "J-9"}, headers=auth).json()
            assert listed["count"] == 1 and listed["data"][0]["id"] == m["id"]
            assert (
                http.post("/api/v1/instruments/ma6-nothing/measure", json={}, headers=auth).status_code == 404
            )
    assert (tmp_path / "station.sqlite3").exists()


def test_bootstrap_token_is_handed_out_on_first_start_only(tmp_path: Path, monkeypatch, capsys) -> None:
    """The serve handler in-process, with uvicorn.run stubbed: first start hands out a token, the second does not.

    Output captured (not a terminal): the token goes to ``bootstrap-token`` (0600) and only its path is
    printed; on a terminal it is printed.
    """
    import uvicorn

    from station.cli import main

    started: list[tuple[FastAPI, dict[str, Any]]] = []
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: started.append((app, kw)))
    argv = ["serve", "--data-dir", str(tmp_path), "--simulators", "", "--no-demo-library", "--port", "8123"]
    assert main(argv) == 0
    first = capsys.readouterr().out
    token_file = tmp_path / BOOTSTRAP_TOKEN_FILE
    assert "cst_" not in first and str(token_file) in first, first
    assert stat.S_IMODE(token_file.stat().st_mode) == 0o600
    token = token_file.read_text().strip()
    assert re.fullmatch(r"cst_[\w-]+", token), token
    assert main(argv) == 0
    assert "cst_" not in capsys.readouterr().out
    assert [kw["host"] for _app, kw in started] == ["127.0.0.1", "127.0.0.1"]
    from fastapi.testclient import TestClient

    with TestClient(started[-1][0]) as client:  # the app serve built, on the same data folder
        me = client.get("/api/v1/me", headers={"Authorization": f"Bearer {token}"})
        assert me.json()["role"] == "admin"


def test_bootstrap_token_is_printed_on_a_terminal(tmp_path: Path, monkeypatch, capsys) -> None:
    import uvicorn

    from station.cli import main

    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: None)
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    assert main(["serve", "--data-dir", str(tmp_path), "--simulators", "", "--no-demo-library"]) == 0
    assert re.search(r"cst_[\w-]+", capsys.readouterr().out)
    assert not (tmp_path / BOOTSTRAP_TOKEN_FILE).exists()


def test_serve_refuses_bad_input(tmp_path: Path, capsys) -> None:
    from station.cli import main

    assert main(["serve", "--data-dir", str(tmp_path), "--port", "0"]) == 2
    assert "--port" in capsys.readouterr().err
    assert main(["serve", "--data-dir", str(tmp_path), "--simulators", "ma6,xyz"]) == 2
    assert "--simulators" in capsys.readouterr().err
