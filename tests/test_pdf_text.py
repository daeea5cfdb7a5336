"""The tests' PDF text reader (tests/pdf_text.py) against streams built here with zlib."""

from __future__ import annotations

import zlib

from tests.pdf_text import pdf_text


def _pdf(stream: bytes, eol: bytes = b"\n") -> bytes:
    head = b"%PDF-1.4\n1 0 obj << /Length " + str(len(stream)).encode() + b" /Filter /FlateDecode >>\n"
    return head + b"stream" + eol + stream + eol + b"endstream\nendobj\n"


def _ending_in_cr(text: bytes) -> bytes:
    """*text* padded with a PDF comment until its deflated form ends in 0x0D (Adler-32's last byte)."""
    for pad in range(32, 127):
        for k in range(1, 300):
            body = text + b" %" + bytes([pad]) * k
            if zlib.compress(body)[-1] == 0x0D:
                return body
    raise AssertionError("no padding gives a deflated stream ending in 0x0D")


def test_a_deflated_stream_ending_in_a_carriage_return_keeps_its_text() -> None:
    body = _ending_in_cr(b"BT (before the first fail) Tj ET")
    assert zlib.compress(body)[-1] == 0x0D
    for eol in (b"\n", b"\r\n"):
        assert pdf_text(_pdf(zlib.compress(body), eol)) == "before the first fail"


def test_kerned_arrays_are_joined_and_plain_streams_are_read() -> None:
    body = b"BT [(be) -20 (fore)] TJ ET\nBT (the fail) Tj ET"
    assert pdf_text(_pdf(zlib.compress(body))).splitlines() == ["before", "the fail"]
    assert pdf_text(_pdf(body)).splitlines() == ["before", "the fail"]
