"""A strict ``multipart/form-data`` reader for upload routes (RFC 7578), on the standard library's MIME
parser: the body is already bounded by ``station.api.middleware.BodySizeLimit``, so it is parsed whole.

:func:`form_parts` returns each named part's bytes; a body that is not multipart/form-data, a part without a
name, a repeated or unexpected name is an :class:`~station.errors.InputError` naming the field (a 422).
"""

from __future__ import annotations

import email.parser
import email.policy
from collections.abc import Collection

from station.errors import InputError


def form_parts(content_type: str | None, body: bytes, names: Collection[str]) -> dict[str, bytes]:
    """{name: bytes} of the parts of a multipart/form-data *body* sent with header *content_type*; only
    *names* are accepted (InputError naming ``body`` or the part otherwise)."""
    if not content_type or not content_type.lower().startswith("multipart/form-data"):
        raise InputError("body", "multipart/form-data", content_type)
    head = f"Content-Type: {content_type}\r\nMIME-Version: 1.0\r\n\r\n".encode("latin-1", "replace")
    msg = email.parser.BytesParser(policy=email.policy.HTTP).parsebytes(head + body)
    if not msg.is_multipart() or msg.defects:
        raise InputError("body", "multipart/form-data with a boundary", None, "malformed body")
    parts: dict[str, bytes] = {}
    for part in msg.iter_parts():
        name = part.get_param("name", header="content-disposition")
        if not isinstance(name, str) or not name:
            raise InputError("body", "form-data parts with a name", None)
        if name not in names:
            raise InputError(name, "one of the parts " + ", ".join(sorted(names)), None, "unexpected part")
        if name in parts:
            raise InputError(name, "one part of this name", None, "repeated")
        payload = part.get_payload(decode=True)
        parts[name] = payload if isinstance(payload, bytes) else b""
    return parts
