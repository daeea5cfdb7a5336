"""Connection limits of ``station serve``: a deadline on request headers, caps per client and in all,
and a bound on requests handled at once that idle connections do not count against.

uvicorn's ``limit_concurrency`` counts open connections, so connections that never send a request
(64 idle sockets, no token needed) made every request a 503 for as long as they were held; and its
``timeout_keep_alive`` only starts after a first response. Here:

- :class:`GuardedH11Protocol` (uvicorn's h11 protocol with a :class:`ConnectionGuard`) gives each
  connection ``header_timeout_s`` seconds, from its opening (and, on a kept-alive connection, from the
  first byte of each later request) to deliver a complete request line and headers; a connection that
  has sent part of one then gets a ``408`` and is closed, one that has sent nothing is closed (a
  slow-header client cannot hold it; between requests the keep-alive timeout applies).
- At most ``max_per_client`` connections per client address and ``max_connections`` in all: a new
  connection beyond either first closes the oldest *idle* connection (no request being handled) of
  that client (or of any client, for the total); when every one is busy the new connection is
  answered ``503`` and closed. Idle connections of one client therefore never keep another client,
  or a new connection of the same client, out.
- :class:`RequestConcurrencyLimit` answers ``503`` (``Connection: close``) to a request arriving while
  ``limit`` requests are being handled; it counts requests, not connections.

The body deadline is :class:`station.api.timeouts.BodyReadTimeout`'s; the idle time between requests is
uvicorn's ``timeout_keep_alive``.
"""

from __future__ import annotations

import asyncio
from collections import OrderedDict
from typing import Any

import h11
from starlette.types import ASGIApp, Receive, Scope, Send
from uvicorn.protocols.http.h11_impl import H11Protocol

from station.api.middleware import send_json

__all__ = ["ConnectionGuard", "GuardedH11Protocol", "RequestConcurrencyLimit", "guarded_protocol"]

_CLOSE_408 = (
    b"HTTP/1.1 408 Request Timeout\r\ncontent-type: application/json\r\nconnection: close\r\n"
    b"content-length: %d\r\n\r\n%s"
)
_CLOSE_503 = (
    b"HTTP/1.1 503 Service Unavailable\r\ncontent-type: application/json\r\nconnection: close\r\n"
    b"content-length: %d\r\n\r\n%s"
)


def _raw_response(template: bytes, detail: str) -> bytes:
    body = b'{"detail": "%s"}' % detail.encode("ascii")
    return template % (len(body), body)


class ConnectionGuard:
    """The limits of one server: *header_timeout_s* (seconds), *max_connections* in all and
    *max_per_client* per client address. Used from the event loop's thread only."""

    def __init__(self, *, header_timeout_s: float, max_connections: int, max_per_client: int) -> None:
        if not header_timeout_s > 0:
            raise ValueError(f"header_timeout_s must be > 0 seconds, got {header_timeout_s!r}")
        if not 1 <= max_per_client <= max_connections:
            raise ValueError(
                f"expected 1 <= max_per_client <= max_connections, got {max_per_client}, {max_connections}"
            )
        self.header_timeout_s = header_timeout_s
        self.max_connections = max_connections
        self.max_per_client = max_per_client
        self._all: OrderedDict[GuardedH11Protocol, None] = OrderedDict()  # oldest first
        self._by_client: dict[str, OrderedDict[GuardedH11Protocol, None]] = {}

    def open_connections(self, client: str | None = None) -> int:
        """Connections held now, of *client* (an address) or in all."""
        if client is None:
            return len(self._all)
        return len(self._by_client.get(client, ()))

    def admit(self, conn: GuardedH11Protocol) -> bool:
        """Count *conn* in, closing the oldest idle connection where a cap is reached; ``False``
        (nothing counted) when a cap is reached and no connection there is idle."""
        peers = self._by_client.get(conn.client_address, OrderedDict())
        if len(peers) >= self.max_per_client and not self._evict_oldest_idle(peers):
            return False
        if len(self._all) >= self.max_connections and not self._evict_oldest_idle(self._all):
            return False
        self._all[conn] = None
        self._by_client.setdefault(conn.client_address, OrderedDict())[conn] = None
        return True

    def release(self, conn: GuardedH11Protocol) -> None:
        """Count *conn* out (idempotent)."""
        self._all.pop(conn, None)
        peers = self._by_client.get(conn.client_address)
        if peers is not None:
            peers.pop(conn, None)
            if not peers:
                del self._by_client[conn.client_address]

    def _evict_oldest_idle(self, conns: OrderedDict[GuardedH11Protocol, None]) -> bool:
        for other in conns:
            if other.is_idle:
                self.release(other)
                other.close_idle()
                return True
        return False


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol under a :class:`ConnectionGuard` (build one with :func:`guarded_protocol`)."""

    guard: ConnectionGuard

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._header_deadline: asyncio.TimerHandle | None = None

    @property
    def client_address(self) -> str:
        """The peer's address (``""`` when the transport does not say)."""
        return self.client[0] if self.client else ""

    @property
    def is_idle(self) -> bool:
        """No request is being handled: waiting for (the rest of) a request line and headers."""
        return self.cycle is None or self.cycle.response_complete

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        if not self.guard.admit(self):
            detail = (
                f"connection limit reached ({self.guard.max_per_client} per client, "
                f"{self.guard.max_connections} in all) and every connection busy"
            )
            self.logger.warning("%s: %s", self.client_address or "client", detail)
            transport.write(_raw_response(_CLOSE_503, detail))
            transport.close()
            return
        self._arm_header_deadline()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm_header_deadline()
        self.guard.release(self)
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        if self._header_deadline is None and self._awaiting_headers():
            self._arm_header_deadline()  # the first bytes of a request after a response: its time starts

    def handle_events(self) -> None:
        super().handle_events()
        if self.conn.their_state is not h11.IDLE:  # the request line and headers are in
            self._disarm_header_deadline()

    def _awaiting_headers(self) -> bool:
        return not self.transport.is_closing() and self.conn.their_state is h11.IDLE

    def close_idle(self) -> None:
        """Close this idle connection to make room for another (as a keep-alive timeout would)."""
        self._disarm_header_deadline()
        if not self.transport.is_closing():
            self.transport.close()

    def _arm_header_deadline(self) -> None:
        self._disarm_header_deadline()
        self._header_deadline = self.loop.call_later(self.guard.header_timeout_s, self._headers_late)

    def _disarm_header_deadline(self) -> None:
        if self._header_deadline is not None:
            self._header_deadline.cancel()
            self._header_deadline = None

    def _headers_late(self) -> None:
        self._header_deadline = None
        if not self._awaiting_headers():
            return
        started, _closed = self.conn.trailing_data
        if started:
            detail = f"request headers not received within {self.guard.header_timeout_s:g} s"
            self.transport.write(_raw_response(_CLOSE_408, detail))
        self.guard.release(self)
        self.transport.close()


def guarded_protocol(guard: ConnectionGuard) -> type[GuardedH11Protocol]:
    """A :class:`GuardedH11Protocol` class bound to *guard*, for ``uvicorn.run(http=…)``."""
    return type("GuardedH11Protocol", (GuardedH11Protocol,), {"guard": guard})


class RequestConcurrencyLimit:
    """Answer ``503`` (and close) to an HTTP request that arrives while *limit* requests are handled."""

    def __init__(self, app: ASGIApp, limit: int) -> None:
        if limit < 1:
            raise ValueError(f"limit must be >= 1, got {limit!r}")
        self.app = app
        self.limit = limit
        self.active = 0

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        if self.active >= self.limit:
            await send_json(send, 503, f"more than {self.limit} requests at once; retry", close=True)
            return
        self.active += 1
        try:
            await self.app(scope, receive, send)
        finally:
            self.active -= 1
