"""Refusing XML: every XML file the formulation bridge reads goes through :func:`parse_xml`.

Parsing is defusedxml's ElementTree with DTDs, entity declarations and external references all
forbidden (so "billion laughs", quadratic blow-up, XXE and external DTD fetches are refused before
expansion), a byte limit checked before the parser sees the data, and element-count and depth limits
checked after. Refusals raise :class:`HostileXMLError`; plain malformation raises
:class:`XMLFormatError`; both name the file and the limit.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET  # types and ParseError only; parsing is defusedxml
from pathlib import Path

import defusedxml.ElementTree as DET
from defusedxml import DefusedXmlException

from station.formulate.errors import HostileXMLError, XMLFormatError

MAX_ELEMENTS = 2_000_000
MAX_DEPTH = 32


def read_limited(source: str | Path | bytes, max_bytes: int, field: str = "file") -> bytes:
    """Return the bytes of *source* (a path or bytes), refusing more than *max_bytes*."""
    if isinstance(source, (bytes, bytearray)):
        data = bytes(source)
    else:
        path = Path(source)
        try:
            size = path.stat().st_size
            if size > max_bytes:
                raise HostileXMLError(field, f"at most {max_bytes} bytes", size, str(path))
            with path.open("rb") as fh:
                data = fh.read(max_bytes + 1)
        except FileNotFoundError as exc:
            raise XMLFormatError(field, "an existing file", str(path)) from exc
    if len(data) > max_bytes:
        raise HostileXMLError(field, f"at most {max_bytes} bytes", len(data))
    return data


def _depth(elem: ET.Element, limit: int) -> int:
    stack = [(elem, 1)]
    deepest = 1
    while stack:
        node, d = stack.pop()
        deepest = max(deepest, d)
        if deepest > limit:
            return deepest
        stack.extend((child, d + 1) for child in node)
    return deepest


def parse_xml(source: str | Path | bytes, max_bytes: int, field: str = "file") -> ET.Element:
    """Parse XML safely and return the root element (see module docstring for what is refused)."""
    data = read_limited(source, max_bytes, field)
    head = data[:4096].lower()
    if b"<!doctype" in head or b"<!entity" in data.lower():
        raise HostileXMLError(field, "XML without a DTD or entity declarations", "<!DOCTYPE/<!ENTITY")
    try:
        root = DET.fromstring(data, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    except DefusedXmlException as exc:
        raise HostileXMLError(
            field, "XML without DTDs, entities or external references", type(exc).__name__
        ) from exc
    except ET.ParseError as exc:
        raise XMLFormatError(field, "well-formed XML", str(exc)) from exc
    count = sum(1 for _ in root.iter())
    if count > MAX_ELEMENTS:
        raise HostileXMLError(field, f"at most {MAX_ELEMENTS} elements", count)
    depth = _depth(root, MAX_DEPTH)
    if depth > MAX_DEPTH:
        raise HostileXMLError(field, f"nesting depth at most {MAX_DEPTH}", depth)
    return root
