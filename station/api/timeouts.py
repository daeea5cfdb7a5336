"""A pure-ASGI deadline on request bodies: a client that has not sent its whole body in time gets 408.

uvicorn bounds the idle time between requests (``timeout_keep_alive``) but not the time a client takes
to send a body it has announced, so one slow client could hold a connection (and a worker task) for as
long as it likes. The deadline runs from the moment the request reaches the app until the last body
chunk arrives; requests without a body never start it. On expiry the app sees a disconnect and the
client a ``408`` with ``Connection: close`` (whatever the app answered instead is dropped).
"""

from __future__ import annotations

import asyncio

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from station.api.middleware import send_json


class BodyReadTimeout:
    """Answer 408 and close when a request body is not complete within *timeout_s* seconds."""

    def __init__(self, app: ASGIApp, timeout_s: float) -> None:
        if not timeout_s > 0:
            raise ValueError(f"timeout_s must be > 0 seconds, got {timeout_s!r}")
        self.app = app
        self.timeout_s = timeout_s

    async def _refuse(self, send: Send) -> None:
        await send_json(send, 408, f"request body not received within {self.timeout_s:g} s", close=True)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        deadline = asyncio.get_running_loop().time() + self.timeout_s
        body_done = False
        timed_out = False
        started = False

        async def timed_receive() -> Message:
            nonlocal body_done, timed_out
            if timed_out:
                return {"type": "http.disconnect"}
            if body_done:
                return await receive()
            try:
                async with asyncio.timeout_at(deadline):
                    message = await receive()
            except TimeoutError:
                timed_out = True
                return {"type": "http.disconnect"}
            if message["type"] != "http.request" or not message.get("more_body", False):
                body_done = True
            return message

        async def guarded_send(message: Message) -> None:
            nonlocal started
            if timed_out and not started:
                return  # replaced by the 408 below
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, timed_receive, guarded_send)
        except Exception:
            if not timed_out:
                raise
        if timed_out and not started:
            await self._refuse(send)
