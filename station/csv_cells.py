"""Spreadsheet-safe CSV text cells (CSV / formula injection, OWASP "CSV Injection").

A spreadsheet opening a CSV runs a cell that starts with ``=``, ``+``, ``-`` or ``@`` as a formula, and
some also after a leading tab or carriage return. Exports therefore prefix such *text* cells with a
single quote (the OWASP rule), which the spreadsheet shows and does not evaluate; numeric columns are
written as numbers and never escaped (``-1.5`` is a number, not a formula). Imports refuse such text
cells unless the caller allows them.
"""

from __future__ import annotations

__all__ = ["FORMULA_LEADS", "escape_cell", "is_formula"]

#: First characters that make a spreadsheet evaluate (or, tab and CR, reinterpret) a cell.
FORMULA_LEADS = ("=", "+", "-", "@", "\t", "\r")


def is_formula(text: str) -> bool:
    """Whether the text cell *text* would be taken as a formula by a spreadsheet."""
    return text.startswith(FORMULA_LEADS)


def escape_cell(text: str) -> str:
    """*text* with a single quote in front when it :func:`is_formula`, else unchanged."""
    return "'" + text if is_formula(text) else text
