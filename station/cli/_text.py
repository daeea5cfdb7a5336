"""Terminal text of a command's result: aligned tables, rounded numbers, units read off the key names.

The ``--json`` output is the handler's dict itself; this module is the person's view of the same dict.
Units and rounding follow the project's key-naming convention (docs/design.md): a key's last word
names its unit — ``travel_deg`` is printed ``60.00°``, ``gloss_gu`` ``85.0 GU``, ``batch_g`` in
grams — and Lab and ΔE values (keys such as ``face``, ``lab``, ``mean_de``) are rounded to 2
decimals. A ``recipe`` (mass fractions) is one colorant a line, in % and, when the result carries
the weighed-out batch, in g. Standard library only: the CLI's start-up imports this module.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

UNITS: dict[str, str] = {
    "deg": "°",
    "gu": " GU",
    "hu": " HU",
    "nm": " nm",
    "c": " °C",
    "ms": " ms",
    "s": " s",
    "g": " g",
    "mm": " mm",
    "pct": " %",
    "percent": " %",
}
"""Unit printed after a number, by the last word of its key (``travel_deg`` → ``°``)."""

DECIMALS: dict[str, int] = {"deg": 2, "gu": 1, "hu": 2, "nm": 0, "c": 1, "ms": 1, "s": 2, "g": 2, "mm": 2}
"""Decimals of a number with a unit, by the last word of its key."""

TWO_DECIMAL_WORDS = frozenset(
    {"lab", "face", "flop", "de", "delta", "rms", "mean", "max", "min", "residual", "mi", "epsilon"}
    | {"dl", "da", "db", "dc", "dh", "l", "a", "b", "sum", "tolerance", "limit", "seam", "changes"}
)
"""Words of a key whose numbers are Lab or ΔE values: printed with 2 decimals."""

ROW_LABEL_KEYS = ("geometries", "angles_deg", "angles")
"""Sibling keys whose list names the rows of a per-geometry table (``lab`` next to ``geometries``)."""

WIDE_COLUMNS = 12
"""A list of rows wider than this (spectra) is summarised by its shape, the values left to --json."""

TABLE_CELL_ITEMS = 6
"""A list of more items than this does not go in a table cell: its row is printed as a block."""

LONG_TEXT = 40
"""A list holding a text longer than this is printed one item a line (advice, warnings)."""

INDENT = "  "


def _words(key: str) -> list[str]:
    return key.lower().replace("-", "_").replace(".", "_").split("_")


def format_number(key: str, value: float | int) -> str:
    """*value* rounded and with its unit, both read off *key* (module docstring)."""
    unit_word = _unit_word(key)
    unit = UNITS.get(unit_word, "")
    if isinstance(value, int) and not isinstance(value, bool):
        return f"{value}{unit}"
    if not math.isfinite(value):
        return f"{value}{unit}"
    decimals = DECIMALS.get(unit_word, 2) if unit_word else 2
    if not unit_word and not TWO_DECIMAL_WORDS.intersection(_words(key)):
        return _general(value)
    if 0 < abs(value) < 0.5 * 10.0**-decimals and unit_word:
        return f"{_general(value)}{unit}"  # a resolution or a tolerance, not a rounding of zero
    text = f"{value:.{decimals}f}"
    if text.startswith("-") and float(text) == 0:
        text = text[1:]
    return f"{text}{unit}"


def _unit_word(key: str) -> str:
    """The unit word ending *key* (``travel_deg`` → ``deg``); a one-word key names no unit (``c``)."""
    words = _words(key)
    return words[-1] if len(words) > 1 and words[-1] in UNITS else ""


def _general(value: float) -> str:
    """A number without a known unit: 4 significant digits, at most 4 decimals."""
    if value == 0 or (value.is_integer() and abs(value) < 1e15):
        return f"{value:.0f}"
    if abs(value) >= 1:
        return f"{value:.4g}" if abs(value) < 1e6 else f"{value:.3e}"
    if abs(value) >= 1e-4:
        return f"{value:.4f}".rstrip("0")
    return f"{value:.2e}"


def format_scalar(key: str, value: Any) -> str:
    """One value for a person: numbers by :func:`format_number`, yes/no, ``—`` for none."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)):
        return format_number(key, value)
    if isinstance(value, Mapping):
        return ", ".join(f"{k} {format_scalar(str(k), v)}" for k, v in value.items()) or "—"
    if isinstance(value, Sequence) and not isinstance(value, str):
        sep = "; " if any(_is_list(v) for v in value) else ", "
        return sep.join(format_scalar(key, v) for v in value) or "—"
    return str(value)


def _is_list(value: Any) -> bool:
    return isinstance(value, Sequence) and not isinstance(value, str)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def format_table(rows: Sequence[Sequence[str]], header: Sequence[str] | None = None, indent: str = "") -> str:
    """Aligned columns of text: the first column left-aligned, the others right-aligned."""
    table = [list(header)] if header is not None else []
    table += [list(r) for r in rows]
    if not table:
        return ""
    width = max(len(r) for r in table)
    table = [r + [""] * (width - len(r)) for r in table]
    sizes = [max(len(r[i]) for r in table) for i in range(width)]
    lines = []
    for row in table:
        cells = [row[0].ljust(sizes[0])] + [c.rjust(s) for c, s in zip(row[1:], sizes[1:], strict=True)]
        lines.append((indent + "  ".join(cells)).rstrip())
    return "\n".join(lines)


def _fits_a_cell(value: Any) -> bool:
    """A value short enough for a table cell: a scalar, up to 6 scalars, up to 3 Lab triples."""
    if not _is_list(value):
        return not isinstance(value, Mapping)
    if all(not _is_list(v) and not isinstance(v, Mapping) for v in value):
        return len(value) <= TABLE_CELL_ITEMS
    return len(value) <= 3 and all(_is_list(v) and len(v) <= 3 and _fits_a_cell(v) for v in value)


def _flatten(row: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """*row* with each nested dict of cell-sized values spread over ``key.sub`` columns."""
    out: dict[str, Any] = {}
    for k, v in row.items():
        name = f"{prefix}{k}"
        if isinstance(v, Mapping) and v and len(v) <= 8 and all(_fits_a_cell(x) for x in v.values()):
            out.update(_flatten(v, f"{name}."))
        else:
            out[name] = v
    return out


def _dict_rows(key: str, rows: Sequence[Mapping[str, Any]], indent: str) -> str:
    """Rows of dicts as one aligned table, or, when a row holds more than a cell can, one block a row."""
    flat = [_flatten(r) for r in rows]
    if not all(_fits_a_cell(v) for r in flat for v in r.values()):
        blocks = []
        for i, row in enumerate(rows, 1):
            blocks += [f"{indent}{key} {i} of {len(rows)}:", human_text(row, indent + INDENT, key)]
        return "\n".join(blocks)
    columns: list[str] = []
    for r in flat:
        columns += [c for c in r if c not in columns]
    # a nested dict spread over columns leaves no column of its own for the rows where it is absent
    columns = [c for c in columns if not any(o.startswith(f"{c}.") for o in columns)]
    cells = [[format_scalar(c, r.get(c)) for c in columns] for r in flat]
    return format_table(cells, [c.replace("_", " ") for c in columns], indent)


def _shape(value: Any) -> list[int]:
    shape: list[int] = []
    while _is_list(value):
        shape.append(len(value))
        if not value:
            break
        value = value[0]
    return shape


def _matrix(key: str, rows: Sequence[Sequence[Any]], labels: Sequence[Any] | None, indent: str) -> str:
    header: list[str] | None = None
    if "lab" in _words(key) and all(len(r) == 3 for r in rows):
        header = ["", "L*", "a*", "b*"] if labels else ["L*", "a*", "b*"]
    cells = [[format_scalar(key, v) for v in r] for r in rows]
    if labels:
        cells = [[str(lab), *c] for lab, c in zip(labels, cells, strict=True)]
    return format_table(cells, header, indent)


def _recipe(recipe: Mapping[str, float], grams: Mapping[str, float] | None, indent: str) -> str:
    """One colorant a line: mass fraction in % and, with the batch, mass in g."""
    rows = []
    for name, fraction in recipe.items():
        row = [name, f"{100 * fraction:.2f} %"]
        if grams is not None and name in grams:
            row.append(f"{grams[name]:.2f} g")
        rows.append(row)
    return format_table(rows, indent=indent)


def _batch_grams(data: Mapping[str, Any]) -> Mapping[str, float] | None:
    batch = data.get("batch")
    if isinstance(batch, Mapping) and isinstance(batch.get("colorants_g"), Mapping):
        return batch["colorants_g"]
    grams = data.get("batch_g")
    return grams if isinstance(grams, Mapping) else None


def human_text(data: Mapping[str, Any], indent: str = "", parent: str = "") -> str:
    """The lines a person reads for a result *data* (JSON types only, as :func:`to_jsonable` gives).

    *parent* is the key *data* sits under: a key of its own without a unit takes the parent's
    (``batch_g: {binder: 819.2}`` is in grams)."""
    lines: list[str] = []
    inner = indent + INDENT
    for name, val in data.items():
        key = name if _unit_word(name) or not _unit_word(parent) else parent
        label = f"{indent}{name}:"
        if key == "recipe" and isinstance(val, Mapping) and all(_is_number(v) for v in val.values()):
            grams = _batch_grams(data)
            unit = "%, g per batch" if grams is not None else "%"
            lines += [f"{label} ({unit})" if val else f"{label} none", _recipe(val, grams, inner)]
        elif isinstance(val, Mapping):
            lines += [f"{label} none"] if not val else [label, human_text(val, inner, key)]
        elif _is_list(val) and val and all(isinstance(v, Mapping) for v in val):
            lines += [label, _dict_rows(key, val, inner)]
        elif _is_list(val) and val and all(_is_list(v) for v in val):
            shape = _shape(val)
            if len(shape) > 2 or any(len(r) > WIDE_COLUMNS for r in val):
                lines.append(f"{label} {' × '.join(map(str, shape))} values (see --json)")
                continue
            labels = next(
                (
                    k
                    for k in ROW_LABEL_KEYS
                    if k != key and _is_list(data.get(k)) and len(data[k]) == len(val)
                ),
                None,
            )
            row_labels = [format_scalar(labels, v) for v in data[labels]] if labels else None
            lines += [label, _matrix(key, val, row_labels, inner)]
        elif _is_list(val) and len(val) > WIDE_COLUMNS and all(_is_number(v) for v in val):
            lines.append(
                f"{label} {len(val)} values, {format_scalar(key, val[0])} … {format_scalar(key, val[-1])}"
            )
        elif _is_list(val) and any(isinstance(v, str) and len(v) > LONG_TEXT for v in val):
            lines += [label, *(f"{inner}- {v}" for v in val)]
        elif _is_list(val) and not val:
            lines.append(f"{label} none")
        else:
            lines.append(f"{label} {format_scalar(key, val)}")
    return "\n".join(line for line in lines if line)
