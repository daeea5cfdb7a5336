"""Pure-ASGI middleware: a cap on request bodies (uploads included), 413 beyond ``max_body_bytes``;
security headers on every response."""

from __future__ import annotations

import json
from collections.abc import Mapping

from starlette.types import ASGIApp, Message, Receive, Scope, Send


async def send_json(send: Send, status: int, detail: object, close: bool = False) -> None:
    """Answer a request from ASGI middleware: ``{"detail": detail}`` as JSON with *status*.

    With *close* the response says ``Connection: close`` (the server then drops the connection).
    """
    body = json.dumps({"detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if close:
        headers.append((b"connection", b"close"))
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


class _TooLarge(Exception):
    pass


class BodySizeLimit:
    """Refuse a request whose declared or streamed body exceeds *max_bytes*, or the cap *per_path* gives
    its exact path (e.g. a larger one for library uploads). A per-path cap given as (bytes, field) is that
    of an upload route whose body is essentially one file field: its 413 names the field as a 422 does
    (``detail[0].loc`` = ["body", field])."""

    def __init__(
        self, app: ASGIApp, max_bytes: int, per_path: Mapping[str, int | tuple[int, str]] | None = None
    ) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.per_path = {k: v if isinstance(v, tuple) else (v, "") for k, v in (per_path or {}).items()}

    async def _refuse(self, send: Send, limit: int, field: str = "") -> None:
        message = f"request body over the {limit}-byte limit"
        if not field:
            await send_json(send, 413, message)
            return
        accepted = f"a body of at most {limit} bytes"
        detail = {"loc": ["body", field], "msg": f"{field}: {message}", "type": "too_large"}
        await send_json(send, 413, [{**detail, "ctx": {"accepted": accepted}}])

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit, field = self.per_path.get(scope.get("path", ""), (self.max_bytes, ""))
        for name, value in scope.get("headers", []):
            if name == b"content-length":
                try:
                    declared = int(value)
                except ValueError:
                    declared = limit + 1
                if declared > limit:
                    await self._refuse(send, limit, field)
                    return
        seen = 0
        started = False

        async def limited_receive() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > limit:
                    raise _TooLarge
            return message

        async def tracking_send(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except _TooLarge:
            if not started:
                await self._refuse(send, limit, field)


#: Added to every response (a route's own value wins): no MIME sniffing of uploads echoed back or of
#: JSON read as HTML, no framing, no referrer leaking ids in URLs.
SECURITY_HEADERS: tuple[tuple[bytes, bytes], ...] = (
    (b"x-content-type-options", b"nosniff"),
    (b"x-frame-options", b"DENY"),
    (b"referrer-policy", b"no-referrer"),
)
#: Every response of the service is either a secret (tokens), data behind a token, or liveness that
#: must not be served stale: none may be stored by a browser or a proxy (OWASP REST cheat sheet).
NO_STORE: tuple[bytes, bytes] = (b"cache-control", b"no-store")


class SecurityHeaders:
    """Add :data:`SECURITY_HEADERS` and ``Cache-Control: no-store`` to each HTTP response that lacks
    them, error responses of the inner middleware (413) included; register it outermost."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                present = {name.lower() for name, _ in headers}
                headers += [(k, v) for k, v in (*SECURITY_HEADERS, NO_STORE) if k not in present]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, with_headers)
