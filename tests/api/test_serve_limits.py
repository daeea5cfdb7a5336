"""``station serve`` as a real process: address from the environment, private files, server limits.

One service on an SQLite data folder that started world-readable (0755/0644) with ``CACAD_HOST``,
``CACAD_PORT`` (overridden by ``--port``), a 1 s body deadline, a 1 s header deadline, a 1 s keep-alive
timeout, a limit of 3 requests at once, 2 connections per client, 80 in all and a 4 KiB header cap, all
from the environment (a second service has a 120 s header deadline, for the tests that hold idle
connections). Raw sockets play the slow and idle clients; other client addresses are other loopback
addresses (127.0.0.2, …) bound as the source.
"""

from __future__ import annotations

import os
import signal
import socket
import stat
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import pytest

from station.api.settings import BOOTSTRAP_TOKEN_FILE
from tests.serve_process import ServeProcess, ServeStartError, free_port, serve_env, upgrade_data_dir
from tests.waiting import WaitTimeout, pause, wait_until

#: Two ``station serve`` children and timed waits: a long file, run early (tests/conftest.py).
pytestmark = pytest.mark.slow

BODY_TIMEOUT_S = 1.0
KEEP_ALIVE_S = 1
LIMIT = 3
MAX_HEADER_BYTES = 4096
HEADER_TIMEOUT_S = 1.0
PER_CLIENT = 2
MAX_CONNECTIONS = 80
ROOMY_HEADER_TIMEOUT_S = 120.0


class Service:
    """The running service: its base URL, data folder, admin token and the port the env asked for."""

    def __init__(self, base: str, data_dir: Path, token: str, env_port: int, port: int) -> None:
        self.base, self.data_dir, self.token, self.env_port, self.port = base, data_dir, token, env_port, port


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Service]:
    yield from _serve(tmp_path_factory, HEADER_TIMEOUT_S)


@pytest.fixture(scope="module")
def roomy(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Service]:
    """The same limits with a header deadline far beyond the test (idle connections stay while it runs)."""
    yield from _serve(tmp_path_factory, ROOMY_HEADER_TIMEOUT_S)


def _serve(tmp_path_factory: pytest.TempPathFactory, header_timeout_s: float) -> Iterator[Service]:
    data_dir = tmp_path_factory.mktemp("serve") / "data"
    env = serve_env()
    upgrade_data_dir(data_dir, env)
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
        CACAD_HEADER_TIMEOUT_S=str(header_timeout_s),
        CACAD_MAX_CONNECTIONS_PER_CLIENT=str(PER_CLIENT),
        CACAD_MAX_CONNECTIONS=str(MAX_CONNECTIONS),
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


def _connect(service: Service, source: str = "127.0.0.1") -> socket.socket:
    """A TCP connection to the service from the loopback address *source*."""
    return socket.create_connection(("127.0.0.1", service.port), timeout=10, source_address=(source, 0))


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


def test_port_flag_overrides_the_environment_and_only_new_files_are_made_private(service: Service) -> None:
    assert httpx.get(service.base + "/health", timeout=10).status_code == 200
    with pytest.raises(httpx.ConnectError):
        httpx.get(f"http://127.0.0.1:{service.env_port}/health", timeout=2)
    # what existed before the start keeps its mode (the product never chmods a path it did not create)
    assert stat.S_IMODE(service.data_dir.stat().st_mode) == 0o755
    assert stat.S_IMODE((service.data_dir / "station.sqlite3").stat().st_mode) == 0o644
    # what the service creates is private from its first byte
    assert stat.S_IMODE((service.data_dir / BOOTSTRAP_TOKEN_FILE).stat().st_mode) == 0o600


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


def _slow_body(service: Service, source: str) -> socket.socket:
    """A request in flight: headers and part of a body, the rest never sent (408 after the body deadline)."""
    sock = _connect(service, source)
    sock.sendall(
        b"POST /api/v1/panels HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\n"
        + f"Authorization: Bearer {service.token}\r\nContent-Length: 200\r\n\r\n".encode()
        + b'{"job": "J'
    )
    return sock


def _is_closed(sock: socket.socket, within_s: float) -> tuple[bool, bytes]:
    """Whether the server closed *sock* within *within_s* seconds, and what it sent before."""
    data, _after = _read_all(sock, limit_s=within_s)
    try:
        sock.settimeout(0.05)
        closed = sock.recv(1) == b""
    except TimeoutError:
        closed = False
    except OSError:
        closed = True
    return closed, data


def _wait_until(condition: Callable[[], bool], timeout_s: float) -> bool:
    """Whether *condition* came true within *timeout_s* seconds (polled every 0.05 s)."""
    try:
        wait_until(condition, timeout_s)
    except WaitTimeout:
        return False
    return True


def _taken_in(service: Service) -> None:
    """Return once the service has taken in every connection opened (and every byte sent) before this
    call: the kernel hands connections over in the order they came, so a request on a new connection is
    answered only after the service has accepted all of the earlier ones and read what they sent."""
    r = httpx.get(service.base + "/health", timeout=10)
    assert r.status_code == 200, r.text


def test_requests_over_the_limit_are_503(service: Service) -> None:
    """Three requests in flight (from three clients): the fourth is 503; once they end, 200 again."""
    held = [_slow_body(service, f"127.0.0.{n}") for n in (4, 5, 6)]
    try:
        # polled: a fourth request is served until the service has read the three; from then until their
        # body deadline (408) it must be refused. The deadline only bounds how long a failure takes.
        statuses: list[int] = []

        def refused() -> bool:
            statuses.append(httpx.get(service.base + "/health", timeout=10).status_code)
            return statuses[-1] == 503

        assert _wait_until(refused, 5 * BODY_TIMEOUT_S), statuses
        assert set(statuses) <= {200, 503}, statuses
    finally:
        for sock in held:
            sock.close()
    assert _wait_until(lambda: httpx.get(service.base + "/health", timeout=10).status_code == 200, 10)


def test_idle_connections_without_a_token_do_not_make_requests_503(roomy: Service) -> None:
    """64 connections that never send a request, from 64 other clients, from one other client and from
    this one, leave the roomy answering: idle connections count against no request limit and yield
    to new ones."""
    held = [_connect(roomy, f"127.0.1.{n}") for n in range(1, 65)]
    held += [_connect(roomy, "127.0.0.2") for _ in range(64)]
    held += [_connect(roomy) for _ in range(64)]
    try:
        _taken_in(roomy)  # every one of them accepted: a cap that closed them would have done so
        assert not any(_is_closed(sock, 0.01)[0] for sock in held[:64])  # one each: all still open
        for _ in range(5):
            assert httpx.get(roomy.base + "/health", timeout=10).status_code == 200
        r = httpx.get(
            roomy.base + "/api/v1/panels", headers={"Authorization": f"Bearer {roomy.token}"}, timeout=10
        )
        assert r.status_code == 200, r.text
    finally:
        for sock in held:
            sock.close()


def test_a_connection_without_a_whole_request_is_closed_at_the_header_deadline(service: Service) -> None:
    """Nothing sent: closed silently; headers trickled one byte at a time (before the first request
    and after a response): 408 and closed, both within the header deadline."""
    quiet = _connect(service)
    first = _connect(service)
    later = _connect(service)
    later.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\n\r\n")
    reply = _read_response(later, 5)
    assert reply.startswith(b"HTTP/1.1 200"), reply[:200]
    for sock in (first, later):
        sock.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\n")
    start = time.monotonic()
    answers: dict[int, bytes] = {}
    try:
        while len(answers) < 2 and time.monotonic() - start < 10 * HEADER_TIMEOUT_S:
            for i, sock in enumerate((first, later)):
                if i in answers:
                    continue
                try:
                    sock.sendall(b"X")  # a slow client: one header byte every 0.1 s
                    sock.settimeout(0.05)
                    data = sock.recv(65536)
                    answers[i] = data + _read_all(sock, 2)[0]
                except TimeoutError:
                    continue
                except OSError:
                    answers[i] = b""
            pause(0.05, "a slow client between two header bytes")
        elapsed = time.monotonic() - start
        assert set(answers) == {0, 1}, f"still open after {elapsed:.1f} s"
        assert elapsed <= HEADER_TIMEOUT_S + 3, elapsed
        assert all(a.startswith(b"HTTP/1.1 408") or a == b"" for a in answers.values()), answers
        assert any(a.startswith(b"HTTP/1.1 408") for a in answers.values()), answers
        closed, data = _is_closed(quiet, 3)
        assert closed and data == b"", data
    finally:
        for sock in (quiet, first, later):
            sock.close()


def test_a_client_over_its_connection_cap_yields_its_oldest_idle_one(roomy: Service) -> None:
    """A client at its cap: a new connection closes its oldest idle one (and is served); when every
    one of its connections is busy, the new one is refused with 503. Other clients are served."""
    idle = [_connect(roomy, "127.0.0.7") for _ in range(PER_CLIENT)]
    newest = _connect(roomy, "127.0.0.7")
    try:
        closed, data = _is_closed(idle[0], 2)
        assert closed and data == b""
        assert not _is_closed(idle[1], 0.2)[0]
        newest.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n")
        assert _read_all(newest, 5)[0].startswith(b"HTTP/1.1 200")
    finally:
        for sock in (*idle, newest):
            sock.close()
    busy = [_slow_body(roomy, "127.0.0.8") for _ in range(PER_CLIENT)]
    try:
        _taken_in(roomy)  # both requests read: both connections busy
        with _connect(roomy, "127.0.0.8") as refused:
            data, _ = _read_all(refused, 5)
        assert data.startswith(b"HTTP/1.1 503") and b"per client" in data, data[:300]
        assert httpx.get(roomy.base + "/health", timeout=10).status_code == 200
    finally:
        for sock in busy:
            sock.close()


def test_connections_over_the_total_cap_close_the_oldest_idle_ones(roomy: Service) -> None:
    """At the total cap a new connection (of any client) closes the oldest idle one; requests are served."""
    held = [_connect(roomy, f"127.0.2.{n}") for n in range(1, MAX_CONNECTIONS + 1)]
    extra = [_connect(roomy, f"127.0.3.{n}") for n in range(1, 6)]
    try:
        # polled: each extra connection the service accepts closes one held one
        assert _wait_until(lambda: sum(_is_closed(sock, 0.01)[0] for sock in held) >= len(extra), 10)
        closed = [sock for sock in held if _is_closed(sock, 0.01)[0]]
        assert len(closed) >= len(extra), len(closed)
        assert closed[0] is held[0]
        assert not any(_is_closed(sock, 0.01)[0] for sock in extra)
        assert httpx.get(roomy.base + "/health", timeout=10).status_code == 200
    finally:
        for sock in (*held, *extra):
            sock.close()


def _read_response(sock: socket.socket, limit_s: float) -> bytes:
    """One whole response (headers and its Content-Length of body) from a kept-alive connection."""
    deadline = time.monotonic() + limit_s
    data = b""
    sock.settimeout(limit_s)
    while b"\r\n\r\n" not in data and time.monotonic() < deadline:
        data += sock.recv(65536) or b""
    head, _, body = data.partition(b"\r\n\r\n")
    length = next(
        (
            int(line.split(b":", 1)[1])
            for line in head.split(b"\r\n")
            if line.lower().startswith(b"content-length:")
        ),
        0,
    )
    while len(body) < length and time.monotonic() < deadline:
        body += sock.recv(65536) or b""
    assert len(body) == length, data
    return head + b"\r\n\r\n" + body


def test_headers_still_arriving_beyond_the_cap_are_refused(service: Service) -> None:
    """h11 buffers at most the cap of a request whose headers have not ended yet, then answers 400."""
    with _connect(service) as sock:
        sock.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\nX-Pad: " + b"a" * (2 * MAX_HEADER_BYTES))
        data, _closed_after = _read_all(sock, limit_s=5)
    assert data.startswith(b"HTTP/1.1 400"), data[:200]
    with _connect(service) as sock:  # under the cap the same request, once complete, is served
        sock.sendall(b"GET /health HTTP/1.1\r\nHost: t\r\nX-Pad: " + b"a" * (MAX_HEADER_BYTES // 2))
        pause(0.2, "headers sent in two parts, the service reading the first on its own")
        sock.sendall(b"\r\nConnection: close\r\n\r\n")
        data, _closed_after = _read_all(sock, limit_s=5)
    assert data.startswith(b"HTTP/1.1 200"), data[:200]


def test_environment_address_and_limits_reach_uvicorn(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """In-process with uvicorn.run stubbed: CACAD_HOST/CACAD_PORT are used, flags override them."""
    import uvicorn

    from station.api.connections import GuardedH11Protocol, RequestConcurrencyLimit
    from station.api.timeouts import BodyReadTimeout
    from station.cli import main

    calls: list[tuple[object, dict[str, object]]] = []
    monkeypatch.setattr(uvicorn, "run", lambda app, **kw: calls.append((app, kw)))
    monkeypatch.setenv("CACAD_HOST", "127.0.0.2")
    monkeypatch.setenv("CACAD_PORT", "8765")
    monkeypatch.setenv("CACAD_LIMIT_CONCURRENCY", "7")
    monkeypatch.setenv("CACAD_MAX_CONNECTIONS_PER_CLIENT", "5")
    argv = ["serve", "--data-dir", str(tmp_path), "--simulators", "", "--no-demo-library"]
    assert main(argv) == 0
    assert main([*argv, "--host", "127.0.0.3", "--port", "8766"]) == 0
    assert [(kw["host"], kw["port"]) for _app, kw in calls] == [("127.0.0.2", 8765), ("127.0.0.3", 8766)]
    app, kw = calls[0]
    assert isinstance(app, RequestConcurrencyLimit) and app.limit == 7
    assert isinstance(app.app, BodyReadTimeout) and app.app.timeout_s == 10.0
    assert (kw["timeout_keep_alive"], kw["h11_max_incomplete_event_size"]) == (5, 16384)
    assert "limit_concurrency" not in kw  # uvicorn's counts idle connections
    protocol = kw["http"]
    assert isinstance(protocol, type) and issubclass(protocol, GuardedH11Protocol)
    guard = protocol.guard
    assert (guard.header_timeout_s, guard.max_connections, guard.max_per_client) == (10.0, 256, 5)
    monkeypatch.setenv("CACAD_PORT", "http")
    assert main(argv) == 2
    monkeypatch.setenv("CACAD_PORT", "8765")
    monkeypatch.setenv("CACAD_MAX_CONNECTIONS", "4")  # below the per-client cap
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert (
        len(err) == 1 and "max_connections_per_client" in err[0] and "at most max_connections (4)" in err[0]
    )
