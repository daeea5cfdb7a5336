"""The hostile values of issue 13, shared by the fuzz test and the schemathesis run.

Raw JSON tokens (Python's ``json`` would not write most of them), the CSV uploads and the image
uploads. Each is something a client can send on the wire; the service must answer each with < 500.
"""

from __future__ import annotations

#: JSON values as raw bytes: non-finite numbers, lone surrogates (escaped and as raw UTF-8 bytes), NUL,
#: bool/str where numbers go, out-of-range instants with an offset, an oversized and a CRLF-laden text,
#: a spreadsheet formula.
JSON_TOKENS: tuple[bytes, ...] = (
    b"NaN",
    b"Infinity",
    b"-Infinity",
    b"1e309",
    b"-1e309",
    b'"\\ud800"',
    b'"x\\udfff"',
    b'"\xed\xa0\x80"',
    b'"a\\u0000b"',
    b"true",
    b"false",
    b'"12.5"',
    b'"0001-01-01T00:00:00+05:00"',
    b'"9999-12-31T23:59:59-05:00"',
    b'"' + b"x" * 140_000 + b'"',
    b'"R-1\\r\\nX-Evil: 1"',
    b'"=HYPERLINK(1)"',
    b"-1.5",
    b"1" * 5000,
    b"[" * 2000 + b"]" * 2000,
)

#: Python values of the same kinds, for strategies that build objects (schemathesis).
PY_VALUES: tuple[object, ...] = (
    float("nan"),
    float("inf"),
    float("-inf"),
    "\ud800",
    "a\x00b",
    True,
    "12.5",
    "0001-01-01T00:00:00+05:00",
    "9999-12-31T23:59:59-05:00",
    "R-1\r\nX-Evil: 1",
    "=HYPERLINK(1)",
)

_HEADER = "code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110\n"
_ROW = ",solid,90,40,50,30,40,50,30,40,50,30\n"

#: Library CSV uploads: bare CR, oversized fields, CRLF/NUL in a code, formulas, bad UTF-8, a lone quote.
CSV_BODIES: tuple[bytes, ...] = (
    (_HEADER + "R-1" + _ROW.replace("\n", "\r") + "R-2" + _ROW).encode(),
    (_HEADER + "R-1,solid," + "9" * 140_000 + _ROW[9:]).encode(),
    (_HEADER + '"' + "x" * 140_000 + '"' + _ROW).encode(),
    (_HEADER + '"R-1\r\nX-Evil: 1"' + _ROW).encode(),
    (_HEADER + "R-\x001" + _ROW).encode(),
    (_HEADER + "=HYPERLINK(1)" + _ROW).encode(),
    (_HEADER + "@SUM(1)" + _ROW).encode(),
    (_HEADER + "R-1,solid,NaN,inf,50,30,40,50,30,40,50,-Infinity\n").encode(),
    (_HEADER + '"R-1' + _ROW).encode(),
    _HEADER.encode() + b"\xed\xa0\x80" + _ROW.encode(),
    b"\xff\xfe\x00\x00",
    b"\r",
    b"",
)

#: Image uploads: not an image, a truncated PNG, a PNG header with garbage.
IMAGE_BODIES: tuple[bytes, ...] = (
    b"",
    b"\x89PNG\r\n\x1a\n",
    b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x7f\xff\xff\xff\x7f\xff\xff\xff\x08\x02\x00\x00\x00",
    b"\xff\xd8\xff\xe0" + b"\x00" * 64,
    b"GIF89a",
)
