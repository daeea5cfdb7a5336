"""Strict JSON request bodies: no NaN, ±Infinity, overflowing numbers, lone surrogates or NUL anywhere.

Python's ``json`` module (which FastAPI parses bodies with) accepts ``NaN``, ``Infinity`` and
``-Infinity``, turns ``1e309`` into ``inf`` and lets a lone UTF-16 surrogate (``"\\ud800"``, or the raw
bytes ``ED A0 80``) through as a string that cannot be encoded again. None of them is valid input to
any route: RFC 8259 has no non-finite numbers, and a surrogate or NUL in stored text breaks the
database (PostgreSQL refuses NUL) or the response. This pure-ASGI middleware parses every JSON body
once more with those values caught, and answers 422 in the request-validation shape with ``loc``
naming the offending member (``["body", "design", "face", 0]``); the bad value itself is never
written back. Bodies that are not JSON pass unchanged. A query parameter holding NUL (``%00``) is
refused the same way (``["query", NAME]``). A route of class :class:`ParsedJsonRoute` reads the document
parsed here instead of parsing the body a second time.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Coroutine, Iterator
from typing import Any
from urllib.parse import parse_qsl

from fastapi.routing import APIRoute
from starlette.requests import Request
from starlette.responses import Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from station.api.middleware import send_json

__all__ = ["PARSED_BODY", "ParsedJsonRoute", "StrictJsonBody", "find_hostile", "safe_text"]

MAX_LOC_TEXT = 64
#: Scope key under which :class:`StrictJsonBody` leaves ``(body, document)`` for :class:`ParsedJsonRoute`.
PARSED_BODY = "station.json_body"
_JSON_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})


def safe_text(value: object, limit: int = MAX_LOC_TEXT) -> str:
    """*value* as printable text: surrogates and control characters escaped, at most *limit* characters."""
    text = value if isinstance(value, str) else str(value)
    if len(text) > limit:
        text = text[:limit] + "…"
    if text.isprintable():
        return text
    return ascii(text)[1:-1]


def _string_fault(text: str) -> str | None:
    if "\x00" in text:
        return "text without NUL characters"
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return "valid Unicode text (no lone UTF-16 surrogates)"
    return None


def _walk(node: Any, path: tuple[int | str, ...]) -> Iterator[tuple[tuple[int | str, ...], str, str]]:
    """The faults in *node* (as Python's ``json`` parses it: ``NaN``, ``±Infinity`` and overflowing
    numbers come out as non-finite floats), in document order."""
    if isinstance(node, float) and not math.isfinite(node):
        yield (
            path,
            "a finite number (NaN, Infinity and overflowing numbers are not JSON numbers)",
            "finite_number",
        )
    elif isinstance(node, str):
        fault = _string_fault(node)
        if fault:
            yield path, fault, "string_unicode"
    elif isinstance(node, dict):
        for key, value in node.items():
            fault = _string_fault(key)
            if fault:
                yield (*path, safe_text(key)), f"a member name of {fault}", "string_unicode"
            yield from _walk(value, (*path, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            kind = value.__class__
            if kind is int or (kind is float and math.isfinite(value)):
                continue  # the common case (spectra, Lab): nothing to look into
            yield from _walk(value, (*path, i))


def _checked(body: bytes) -> tuple[Any, tuple[tuple[int | str, ...], str, str] | None]:
    """``(document, fault)`` of JSON *body*: the parsed document (``None`` when there is a fault or it does
    not parse) and :func:`find_hostile`'s fault."""
    try:
        doc = json.loads(body)
    except json.JSONDecodeError:
        return None, None
    except UnicodeDecodeError:
        return None, ((), "UTF-8 JSON text", "json_invalid")
    except (ValueError, RecursionError):
        return None, (
            (),
            "JSON within the parser's limits (integers of at most 4300 digits, bounded nesting)",
            "json_invalid",
        )
    for loc, msg, kind in _walk(doc, ()):
        return None, (tuple(safe_text(p) if isinstance(p, str) else p for p in loc), msg, kind)
    return doc, None


def find_hostile(body: bytes) -> tuple[tuple[int | str, ...], str, str] | None:
    """``(loc, msg, type)`` of the first value in JSON *body* that no route accepts, else ``None``.

    Unparseable bodies are left to FastAPI (its 422 ``json_invalid``), except those Python's parser
    fails on with something else than a syntax error (an integer of more than 4300 digits, nesting
    deeper than the interpreter's recursion limit), which are reported here at ``body``.
    """
    return _checked(body)[1]


class _ParsedRequest(Request):
    """A request whose JSON body :class:`StrictJsonBody` already parsed: :meth:`json` hands that on."""

    async def json(self) -> Any:
        held = self.scope.get(PARSED_BODY)
        if held is not None and held[0] == await self.body():
            return held[1]
        return await super().json()


class ParsedJsonRoute(APIRoute):
    """A route that reads the JSON document :class:`StrictJsonBody` parsed instead of parsing it again.

    The document is the one Python's ``json`` gives for a body without the values the guard refuses,
    so what the route validates is unchanged; a body the guard did not hold is parsed as usual.
    """

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def parsed_handler(request: Request) -> Response:
            return await handler(_ParsedRequest(request.scope, request.receive))

        return parsed_handler


def _is_json(scope: Scope) -> bool:
    for name, value in scope.get("headers", []):
        if name == b"content-type":
            media = value.split(b";", 1)[0].strip().lower()
            return media == b"application/json" or media.endswith(b"+json")
    return True  # FastAPI parses a body without a content type as JSON


def _query_fault(raw: bytes) -> tuple[tuple[int | str, ...], str, str] | None:
    """A query parameter holding NUL (``%00``): PostgreSQL cannot compare or store it."""
    if b"%00" not in raw and b"\x00" not in raw:
        return None
    for name, value in parse_qsl(raw.decode("latin-1"), keep_blank_values=True):
        if "\x00" in value or "\x00" in name:
            return ("query", safe_text(name)), "text without NUL characters", "string_unicode"
    return None


async def _refuse(send: Send, fault: tuple[tuple[int | str, ...], str, str]) -> None:
    loc, msg, kind = fault
    await send_json(send, 422, [{"loc": list(loc), "msg": msg, "type": kind}])


class StrictJsonBody:
    """Refuse (422) a JSON request body holding a value no route accepts; see the module docstring."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        query = _query_fault(scope.get("query_string", b""))
        if query is not None:
            await _refuse(send, query)
            return
        if scope.get("method") not in _JSON_METHODS or not _is_json(scope):
            await self.app(scope, receive, send)
            return
        chunks: list[bytes] = []
        more = True
        while more:
            message = await receive()
            if message["type"] != "http.request":  # the client went away
                return
            chunks.append(message.get("body", b""))
            more = message.get("more_body", False)
        body = b"".join(chunks)
        doc, fault = _checked(body) if body.strip() else (None, None)
        if fault is not None:
            loc, msg, kind = fault
            await _refuse(send, (("body", *loc), msg, kind))
            return
        if doc is not None:
            scope[PARSED_BODY] = (body, doc)
        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)
