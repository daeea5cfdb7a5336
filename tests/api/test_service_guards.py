"""``station serve`` as a real process, over HTTP: an image that Pillow refuses to decode is a 422 on
a connection that stays open; idempotency keys are scoped per user; simulators are capped per station,
detachable, and end with the service.

The simulator processes are found as the service's children in ``/proc``.
"""

from __future__ import annotations

import json
import os
import signal
import socket
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest

from tests.api._images import bomb_png
from tests.serve_process import ServeProcess, ServeStartError
from tests.waiting import WaitTimeout, wait_until

V1 = "/api/v1"
MAX_SIMULATORS = 2


@dataclass
class Served:
    svc: ServeProcess
    tokens: dict[str, str]

    def auth(self, name: str) -> dict[str, str]:
        return {"Authorization": f"Bearer {self.tokens[name]}"}


def _start(tmp: Path, *args: str, env: dict[str, str] | None = None) -> ServeProcess:
    svc = ServeProcess(tmp / "data", ("--no-demo-library", *args), env=env, start_timeout_s=90)
    try:
        svc.start()
    except ServeStartError as exc:
        pytest.fail(str(exc))
    return svc


def _users(svc: ServeProcess, *names_roles: tuple[str, str]) -> dict[str, str]:
    admin = {"Authorization": f"Bearer {svc.token}"}
    tokens = {"admin": svc.token}
    for name, role in names_roles:
        r = httpx.post(f"{svc.base}{V1}/users", json={"name": name, "role": role}, headers=admin, timeout=30)
        assert r.status_code == 201, r.text
        tokens[name] = r.json()["token"]
    return tokens


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Served]:
    svc = _start(tmp_path_factory.mktemp("guards"), "--simulators", "ma6")
    try:
        yield Served(svc, _users(svc, ("tech-a", "technician"), ("tech-b", "technician"), ("sty", "stylist")))
    finally:
        svc.stop()


def _exchange(sock: socket.socket, request: bytes, limit_s: float = 30) -> tuple[int, dict[str, str], bytes]:
    """Send one HTTP/1.1 request on *sock* and read its response (status, headers, body)."""
    sock.sendall(request)
    sock.settimeout(limit_s)
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError(f"closed before a response: {data[:200]!r}")
        data += chunk
    head, body = data.split(b"\r\n\r\n", 1)
    lines = head.decode("latin-1").split("\r\n")
    headers = {k.strip().lower(): v.strip() for k, v in (line.split(":", 1) for line in lines[1:])}
    length = int(headers.get("content-length", "0"))
    while len(body) < length:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("closed in the middle of a response body")
        body += chunk
    return int(lines[0].split()[1]), headers, body


@pytest.mark.parametrize(
    "path",
    [
        f"{V1}/styling/eyedrop?face_x=1&face_y=1&flop_x=6&flop_y=6",
        f"{V1}/styling/sketch-fit",
    ],
)
def test_an_image_pillow_cannot_decode_is_422_and_the_connection_stays(served: Served, path: str) -> None:
    png = bomb_png()
    assert len(png) < 50_000
    token = served.tokens["sty"]
    with socket.create_connection(("127.0.0.1", served.svc.port), timeout=30) as sock:
        status, headers, body = _exchange(
            sock,
            f"POST {path} HTTP/1.1\r\nHost: t\r\nAuthorization: Bearer {token}\r\n"
            f"Content-Type: image/png\r\nContent-Length: {len(png)}\r\n\r\n".encode()
            + png,
        )
        assert status == 422, body[:500]
        detail = json.loads(body)["detail"][0]
        assert detail["loc"][-1] == "image" and "Decompressed" in detail["msg"], detail
        assert headers.get("connection", "").lower() != "close"
        status, _headers, body = _exchange(sock, b"GET /health HTTP/1.1\r\nHost: t\r\n\r\n")
        assert status == 200, body[:200]
    assert served.svc.proc is not None and served.svc.proc.poll() is None
    assert not any("Traceback" in line for line in served.svc.log), served.svc.tail()


def test_idempotency_keys_are_scoped_per_user(served: Served) -> None:
    base = served.svc.base
    with httpx.Client(base_url=base, timeout=60) as http:
        listed = http.get(f"{V1}/instruments", headers=served.auth("tech-a")).json()
        inst = next(i["id"] for i in listed if i["kind"] == "spectro")
        url = f"{V1}/instruments/{inst}/measure"

        def measure(user: str, key: str) -> httpx.Response:
            return http.post(url, json={}, headers={**served.auth(user), "Idempotency-Key": key})

        for key in ("scan-1", "5b0c2f0e-8a51-4a43-9d64-5f7d0c0f1a2b"):
            a = measure("tech-a", key)
            b = measure("tech-b", key)
            assert (a.status_code, a.json()["status"]) == (201, "stored"), a.text
            assert (b.status_code, b.json()["status"]) == (201, "stored"), b.text
            ma, mb = a.json()["measurement"], b.json()["measurement"]
            assert ma["id"] != mb["id"] and a.json()["client_id"] != b.json()["client_id"]
            assert (ma["operator"], mb["operator"]) == ("tech-a", "tech-b")
            for user, first in (("tech-a", a), ("tech-b", b)):  # each user's retry gets its own reading
                again = measure(user, key)
                assert (again.status_code, again.json()["status"]) == (200, "duplicate"), again.text
                assert again.json()["measurement"] == first.json()["measurement"]


def _simulator_pids(parent: int) -> set[int]:
    """Live simulator processes (``python -m simulators.KIND``) whose parent is *parent*."""
    found: set[int] = set()
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if (
            fields[0] != "Z"
            and int(fields[1]) == parent
            and any(a.startswith(b"simulators.") for a in cmdline)
        ):
            found.add(int(entry.name))
    return found


def _until(condition: Callable[[], bool], timeout_s: float) -> bool:
    """Whether *condition* came true within *timeout_s* seconds (polled every 0.05 s)."""
    try:
        wait_until(condition, timeout_s, interval=0.05)
    except WaitTimeout:
        return False
    return True


def test_simulators_are_capped_detachable_and_end_with_the_service(tmp_path: Path) -> None:
    env = dict(os.environ, CACAD_MAX_SIMULATORS=str(MAX_SIMULATORS), PYTHONUNBUFFERED="1")
    svc = _start(tmp_path, "--simulators", "ma6", env=env)
    try:
        tokens = _users(svc, ("tech", "technician"), ("qa", "qa"))
        tech = {"Authorization": f"Bearer {tokens['tech']}"}
        with httpx.Client(base_url=svc.base, timeout=60) as http:
            second = http.post(f"{V1}/instruments/connect", json={"address": "sim:gloss"}, headers=tech)
            assert second.status_code == 201, second.text
            assert len(_simulator_pids(svc.pid)) == MAX_SIMULATORS
            over = http.post(f"{V1}/instruments/connect", json={"address": "sim:ma3"}, headers=tech)
            assert over.status_code == 409, over.text
            assert "max_simulators" in over.text and f"at most {MAX_SIMULATORS}" in over.text
            assert len(_simulator_pids(svc.pid)) == MAX_SIMULATORS  # nothing was spawned for it

            gloss = second.json()["id"]
            qa = {"Authorization": f"Bearer {tokens['qa']}"}
            assert http.delete(f"{V1}/instruments/{gloss}", headers=qa).status_code == 403
            before = _simulator_pids(svc.pid)
            gone = http.delete(f"{V1}/instruments/{gloss}", headers=tech)
            assert gone.status_code == 204, gone.text
            assert _until(lambda: len(_simulator_pids(svc.pid)) == MAX_SIMULATORS - 1, 10)
            assert _simulator_pids(svc.pid) < before
            listed = http.get(f"{V1}/instruments", headers=tech).json()
            assert gloss not in {i["id"] for i in listed}
            assert http.delete(f"{V1}/instruments/{gloss}", headers=tech).status_code == 404
            third = http.post(f"{V1}/instruments/connect", json={"address": "sim:ma3"}, headers=tech)
            assert third.status_code == 201, third.text
            audit = http.get(f"{V1}/audit", params={"entity": "instrument"}, headers=svc_admin(svc))
            assert audit.status_code == 200, audit.text
            assert any(
                e["action"] == "instrument.detach" and e["entity_id"] == gloss for e in audit.json()["data"]
            ), audit.text
        running = _simulator_pids(svc.pid)
        assert len(running) == MAX_SIMULATORS
        assert svc.stop(signal.SIGTERM) is not None
        assert _until(lambda: not any(Path(f"/proc/{pid}").exists() for pid in running), 10), running
    finally:
        svc.stop()


def svc_admin(svc: ServeProcess) -> dict[str, str]:
    return {"Authorization": f"Bearer {svc.token}"}
