"""Images built in the tests: a PNG that Pillow refuses to decode."""

from __future__ import annotations

import io
import struct
import zlib

from PIL import Image


def bomb_png() -> bytes:
    """An 8 × 8 PNG (about 48 KB) with a zTXt chunk whose text inflates to 48 MiB (Pillow refuses
    text beyond ``PngImagePlugin.MAX_TEXT_CHUNK`` with a ``ValueError``)."""
    buf = io.BytesIO()
    Image.new("RGB", (8, 8), (200, 10, 10)).save(buf, "PNG")
    png = buf.getvalue()
    body = b"Comment\x00\x00" + zlib.compress(b"a" * (48 * 1_048_576), 9)
    chunk = struct.pack(">I", len(body)) + b"zTXt" + body + struct.pack(">I", zlib.crc32(b"zTXt" + body))
    ihdr_end = 8 + 25  # signature, then IHDR (length, type, 13 bytes, CRC)
    return png[:ihdr_end] + chunk + png[ihdr_end:]
