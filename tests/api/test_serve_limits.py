"""``station serve`` as a real process: address from the environment, private files, server limits.

One service on an SQLite data folder that started world-readable (0755/0644) with ``CACAD_HOST``,
``CACAD_PORT`` (overridden by ``--port``), a 1 s body deadline, a 1 s keep-alive timeout and a
concurrency limit of 3 and a 4 KiB header cap, all from the environment. Raw sockets play the slow and idle clients.
"""

from __future__ import annotations

import os
import signal
import socket
import stat
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from station.api.serve_process import ServeProcess, ServeStartError, free_port
from station.api.settings import BOOTSTRAP_TOKEN_FILE

REPO = Path(__file__).resolve().parents[2]
BODY_TIMEOUT_S = 1.0
KEEP_ALIVE_S = 1
LIMIT = 3
MAX_HEADER_BYTES = 4096


class Service:
    """The running service: its base URL, data folder, admin token and the port the env asked for."""

    def __init__(self, base: str, data_dir: Path, token: str, env_port: int, port: int) -> None:
        self.base, self.data_dir, self.token, self.env_port, self.port = base, data_dir, token, env_port, port


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Service]:
    data_dir = tmp_path_factory.mktemp("serve") / "data"
    env = dict(os.environ, PYTHONPATH=str(REPO), PYTHONUNBUFFERED="1")
    env.pop("CACAD_DATABASE_URL", None)
    created = subprocess.run(
        [sys.executable, "-m", "station.cli", "db", "upgrade", "--data-dir", str(data_dir)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert created.returncode == 0, created.stderr
    os.chmod(data_dir, 0o755)  # as an earlier version left it
    os.chmod(data_dir / "station.sqlite3", 0o644)
    env_port = free_port()
    env.update(
        CACAD_HOST="127.0.0.1",
        CACAD_PORT=str(env_port),
        CACAD_BODY_TIMEOUT_S=str(BODY_TIMEOUT_S),
        CACAD_KEEP_ALIVE_TIMEOUT_S=str(KEEP_ALIVE_S),
        CACAD_LIMIT_CONCURRENCY=str(LIMIT),
        CACAD_MAX_HEADER_BYTES=str(MAX_HEADER_BYTES),
    )
    svc = ServeProcess(data_dir, ("--simulators", "", "--no-demo-library"), env=env, start_timeout_s=60)
    try:
        svc.start()
    except ServeStartError as exc:
        pytest.fail(str(exc))
    try:
        token_file = data_dir / BOOTSTRAP_TOKEN_FILE
        assert any(str(token_file) in line for line in svc.log) and not any(
            "cst_" in line for line in svc.log
        )
        yield Service(svc.base, data_dir, token_file.read_text().strip(), env_port, svc.port)
    finally:
        svc.stop(signal.SIGTERM)


def _connect(service: Service) -> socket.socket:
    return socket.create_connection(("127.0.0.1", service.port), timeout=10)


def _read_all(sock: socket.socket, limit_s: float) -> tuple[bytes, float]:
    """Everything until the server closes (or *limit_s* passes), and when the close came."""
    start = time.monotonic()
    data = b""
    sock.settimeout(limit_s)
    try:
        while chunk := sock.recv(65536):
            data += chunk
    except TimeoutError:
        pass
    return data, time.monotonic() - start


def test_port_flag_overrides_the_environment_and_files_are_private(service: Service) -> None:
    assert httpx.get(service.base + "/health", timeout=10).status_code == 200
    with pytest.raises(httpx.ConnectError):
        httpx.get(f"http://127.0.0.1:{service.env_port}/health", timeout=2)
    assert stat.S_IMODE(service.data_dir.stat().st_mode) == 0o700
    for name in ("station.sqlite3", "station.sqlite3-wal", BOOTSTRAP_TOKEN_FILE):
        path = service.data_dir / name
        if path.exists():
            assert stat.S_IMODE(path.stat().st_mode) == 0o600, name
    assert (service.data_dir / "station.sqlite3").exists()


def test_a_slow_body_gets_408_and_the_connection_closed(service: Service) -> None:
    with _connect(service) as sock:
        sock.sendall(
            b"POST /api/v1/panels HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\n"
            + f"Authorization: Bearer {service.token}\r\nContent-Length: 200\r\n\r\n".encode()
            + b'{"job": "J'
        )
        data, closed_after = _read_all(sock, limit_s=10 * BODY_TIMEOUT_S)
    assert data.startswith(b"HTTP/1.1 408"), data[:200]
    assert BODY_TIMEOUT_S * 0.8 <= closed_after <= BODY_TIMEOUT_S + 3, closed_after
    r = httpx.post(  # the service is unharmed: a whole body is served
        service.base + "/api/v1/panels",
        json={"job": "J-1", "part": "door"},
        headers={"Authorization": f"Bearer {service.token}"},
        timeout=10,
    )
    assert r.status_code == 201, r.text


def test_an_idle_keep_alive_connection_is_closed(service: Service) -> None:
    with _connect(service) as sock:
        sock.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\n\r\n")
        data, closed_after = _read_all(sock, limit_s=10 * KEEP_ALIVE_S)
    assert data.startswith(b"HTTP/1.1 200"), data[:200]
    assert closed_after <= KEEP_ALIVE_S + 3, closed_after


def test_concurrency_over_the_limit_is_503(service: Service) -> None:
    held = [_connect(service) for _ in range(LIMIT - 1)]
    try:
        time.sleep(0.3)
        r = httpx.get(service.base + "/health", timeout=10)
        assert r.status_code == 503, r.text
    finally:
        for sock in held:
            sock.close()
    time.sleep(0.3)
    assert httpx.get(service.base + "/health", timeout=10).status_code == 200


def test_headers_still_arriving_beyond_the_cap_are_refused(service: Service) -> None:
    """h11 buffers at most the cap of a request whose headers have not ended yet, then answers 400."""
    with _connect(service) as sock:
        sock.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\nX-Pad: " + b"a" * (2 * MAX_HEADER_BYTES))
        data, _closed_after = _read_all(sock, limit_s=5)
    assert data.startswith(b"HTTP/1.1 400"), data[:200]
    with _connect(service) as sock:  # under the cap the same request, once complete, is served
        sock.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\nX-Pad: " + b"a" * (MAX_HEADER_BYTES // 2))
        time.sleep(0.2)
        sock.sendall(b"\r\nConnection: close\r\n\r\n")
        data, _closed_after = _read_all(sock, limit_s=5)
    assert data.startswith(b"HTTP/1.1 200"), data[:200]


def test_environment_address_and_limits_reach_uvicorn(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """In-process with uvicorn.run stubbed: CACAD_HOST/CACAD_PORT are used, flags override them."""
    import uvicorn

    from station.api.timeouts import BodyReadTimeout
    from station.cli import main

    calls: list[tuple[object, dict[str, object]]] = []
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: calls.append((app, kw)))
    monkeypatch.setenv("CACAD_HOST", "127.0.0.2")
    monkeypatch.setenv("CACAD_PORT", "8765")
    monkeypatch.setenv("CACAD_LIMIT_CONCURRENCY", "7")
    argv = ["serve", "--data-dir", str(tmp_path), "--simulators", "", "--no-demo-library"]
    assert main(argv) == 0
    assert main([*argv, "--host", "127.0.0.3", "--port", "8766"]) == 0
    assert [(kw["host"], kw["port"]) for _app, kw in calls] == [("127.0.0.2", 8765), ("127.0.0.3", 8766)]
    app, kw = calls[0]
    assert isinstance(app, BodyReadTimeout) and app.timeout_s == 10.0
    assert (kw["limit_concurrency"], kw["timeout_keep_alive"], kw["h11_max_incomplete_event_size"]) == (
        7,
        5,
        16384,
    )
    monkeypatch.setenv("CACAD_PORT", "http")
    assert main(argv) == 2
