"""The text drawn on a PDF's pages, read without a PDF library (the reports are matplotlib's PDFs)."""

from __future__ import annotations

import re
import zlib


def pdf_text(pdf: bytes) -> str:
    """The text drawn on the PDF's pages: the strings of every ``Tj``/``TJ`` of its (deflated) content
    streams, a ``TJ`` array's parts joined (a kerned word is split there)."""
    out: list[str] = []
    # The stream's bytes run to "endstream"; the end-of-line before it is left to the decompressor, which
    # stops at the end of its data: taking "\r?\n" off there cut a deflated stream whose last byte is
    # 0x0D (one in 256) and lost its page's text.
    for m in re.finditer(rb"(?<!end)stream\r?\n(.*?)endstream", pdf, re.S):
        try:
            body = zlib.decompressobj().decompress(m.group(1))
        except zlib.error:
            body = m.group(1)
        for arr in re.finditer(rb"\[(.*?)\]\s*TJ|\((.*?)\)\s*Tj", body, re.S):
            parts = re.findall(rb"\(((?:\\.|[^\\)])*)\)", arr.group(1) or b"(" + arr.group(2) + b")")
            out.append(b"".join(parts).decode("latin-1"))
    return "\n".join(out)
