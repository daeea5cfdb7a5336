"""Library CSV import / export.

Format (one header row, then one paint per row)::

    code,type,gloss_gu,L15,a15,b15,L45,a45,b45,L110,a110,b110[,L<angle>,a<angle>,b<angle> ...][,synthetic][,recipe]

``type`` is ``solid``, ``metallic`` or ``pearl``; angles are aspecular degrees (illumination at 45°,
D65 / CIE 1964 10°); more angle triples may follow, named the same way (``L-15,a-15,b-15``, ``L25,…``).
Validation is strict: each fault raises :class:`LibraryFormatError` naming the 1-based row (header =
row 1), the column and the accepted range. A code is printable text (no control characters, so no
CR/LF or NUL) and, unless ``allow_formulas``, does not start with ``= + - @`` (CSV injection,
:mod:`station.csv_cells`); a field is at most 131072 characters (the csv module's limit). The export
writes such a code with a leading single quote. Accepted ranges: the domain's Lab bound, 0 ≤ L* ≤ 200 (a metallic face may exceed 100),
−150 ≤ a*, b* ≤ 150 (:data:`station.model.domain.LAB_RANGES`),
0 ≤ gloss ≤ 100 GU (the model's range), codes unique, non-empty, at most 64 characters.

Two optional trailing columns keep every field of a library through a round trip: ``synthetic``
(``true`` | ``false`` per row; the library is synthetic when every row says ``true``) and ``recipe``
(``colorant=fraction`` pairs separated by ``;``, mass fractions 0–1, the colorants of the library's
colorant database). The export writes ``synthetic`` for a synthetic library and ``recipe`` when the
library carries recipes.

Stated precision of the export: 4 decimals for Lab and gloss (round trip import(export(x)) equals x
rounded to 1e-4, and export(import(export(x))) is byte-identical).
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from station.csv_cells import escape_cell, is_formula
from station.formulate.errors import LibraryFormatError
from station.formulate.library import PAINT_TYPES, STANDARD_ANGLES, Library
from station.model.domain import GLOSS_MAX_GU, GLOSS_MIN_GU
from station.model.domain import LAB_RANGES as DOMAIN_LAB_RANGES

PRECISION_DECIMALS = 4
#: Accepted Lab and gloss of a library row: the domain's bounds (station.model.domain).
LAB_RANGES = DOMAIN_LAB_RANGES
GLOSS_RANGE = (GLOSS_MIN_GU, GLOSS_MAX_GU)
MAX_CODE_LENGTH = 64
MAX_ROWS = 2_000_000
_ANGLE_COL = re.compile(r"^([Lab])(-?\d+(?:\.\d+)?)$")
#: Optional trailing columns, in this order.
EXTRA_COLUMNS = ("synthetic", "recipe")
RECIPE_DECIMALS = 6
_BOOL = {"true": True, "1": True, "false": False, "0": False}


def _angle_name(a: float) -> str:
    return str(int(a)) if float(a).is_integer() else repr(float(a))


def header_for(angles_deg: tuple[float, ...], extras: tuple[str, ...] = ()) -> list[str]:
    """Return the CSV header for *angles_deg*: the 3 standard angles first, then the others in order,
    then the optional *extras* (a subsequence of :data:`EXTRA_COLUMNS`)."""
    ordered = list(STANDARD_ANGLES) + [a for a in angles_deg if a not in STANDARD_ANGLES]
    cols = ["code", "type", "gloss_gu"]
    for a in ordered:
        n = _angle_name(a)
        cols += [f"L{n}", f"a{n}", f"b{n}"]
    return cols + [c for c in EXTRA_COLUMNS if c in extras]


def _split_extras(header: list[str]) -> tuple[list[str], tuple[str, ...]]:
    """Header without its optional trailing columns, and those columns (in :data:`EXTRA_COLUMNS` order)."""
    extras: list[str] = []
    cols = list(header)
    for name in reversed(EXTRA_COLUMNS):
        if cols and cols[-1] == name:
            extras.insert(0, cols.pop())
    for c in cols:
        if c in EXTRA_COLUMNS:
            raise LibraryFormatError(
                1, c, f"optional columns last, in the order {','.join(EXTRA_COLUMNS)}", c
            )
    return cols, tuple(extras)


def _parse_recipe(text: str, row: int) -> dict[str, float]:
    """``name=fraction;…`` → {name: fraction}; empty text is no recipe."""
    out: dict[str, float] = {}
    for part in text.split(";"):
        part = part.strip()
        if not part:
            continue
        name, sep, value = part.partition("=")
        name = name.strip()
        if not sep or not name:
            raise LibraryFormatError(row, "recipe", "colorant=fraction pairs separated by ';'", part)
        if name in out:
            raise LibraryFormatError(row, "recipe", "each colorant once", name)
        out[name] = _number(value, row, "recipe", 0.0, 1.0)
    return out


def format_recipe(names: tuple[str, ...], fractions: np.ndarray) -> str:
    """The ``recipe`` cell of one paint: its non-zero mass fractions as ``name=fraction`` pairs."""
    fmt = f"{{:.{RECIPE_DECIMALS}f}}"
    rounded = np.round(np.asarray(fractions, dtype=np.float64), RECIPE_DECIMALS)
    return ";".join(f"{n}={fmt.format(v)}" for n, v in zip(names, rounded, strict=True) if v > 0)


def _parse_header(header: list[str]) -> tuple[float, ...]:
    if header[:3] != ["code", "type", "gloss_gu"]:
        raise LibraryFormatError(1, None, "header starting code,type,gloss_gu", ",".join(header[:3]))
    rest = header[3:]
    if len(rest) % 3 or not rest:
        raise LibraryFormatError(
            1, None, "Lab columns in complete L<angle>,a<angle>,b<angle> triples", len(rest)
        )
    angles: list[float] = []
    for k in range(0, len(rest), 3):
        triple = rest[k : k + 3]
        ms = [m for m in (_ANGLE_COL.match(c.strip()) for c in triple) if m is not None]
        if len(ms) != len(triple) or [m.group(1) for m in ms] != ["L", "a", "b"]:
            raise LibraryFormatError(
                1, triple[0], "a triple named L<angle>,a<angle>,b<angle>", ",".join(triple)
            )
        names = {m.group(2) for m in ms}
        if len(names) != 1:
            raise LibraryFormatError(
                1, triple[0], "the same angle in L, a and b of one triple", ",".join(triple)
            )
        ang = float(names.pop())
        if not -90.0 < ang < 180.0:
            raise LibraryFormatError(1, triple[0], "aspecular angle in (-90, 180) degrees", ang)
        if ang in angles:
            raise LibraryFormatError(1, triple[0], "each angle once", ang)
        angles.append(ang)
    if tuple(angles[:3]) != STANDARD_ANGLES:
        raise LibraryFormatError(1, None, "the first triples at 15, 45, 110 degrees", angles[:3])
    return tuple(angles)


def _number(text: str, row: int, col: str, lo: float, hi: float) -> float:
    try:
        v = float(text)
    except ValueError as exc:
        raise LibraryFormatError(row, col, f"a number in [{lo:g}, {hi:g}]", text) from exc
    if not math.isfinite(v) or not lo <= v <= hi:
        raise LibraryFormatError(row, col, f"a number in [{lo:g}, {hi:g}]", text)
    return v


def _records(stream: io.TextIOBase) -> Iterator[list[str]]:
    """The CSV records of *stream*; a malformed one is a :class:`LibraryFormatError` naming its row."""
    reader = csv.reader(stream)
    row = 1
    while True:
        try:
            record = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise LibraryFormatError(
                row, None, "CSV fields (a line break only inside a quoted field)", detail=str(exc)
            ) from exc
        row += 1
        yield record


def _open(source: str | Path | io.TextIOBase, name: str | None) -> tuple[io.TextIOBase, str | None]:
    """A text stream over *source* (a path is read as UTF-8, a BOM dropped) and the library's name."""
    if not isinstance(source, (str, Path)):
        return source, name
    path = Path(source)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError as exc:
        raise LibraryFormatError(None, None, "an existing CSV file", str(path)) from exc
    except UnicodeDecodeError as exc:
        raise LibraryFormatError(None, None, "UTF-8 text", str(path)) from exc
    return io.StringIO(text), name or path.stem


def _code(cell: str, rowno: int, allow_formulas: bool, seen: dict[str, int]) -> str:
    """The row's paint code, checked (printable, bounded length, no formula, unique); recorded in *seen*."""
    code = cell.strip()
    if not code or len(code) > MAX_CODE_LENGTH or not code.isprintable():
        raise LibraryFormatError(
            rowno,
            "code",
            f"a non-empty code of at most {MAX_CODE_LENGTH} printable characters (no control characters)",
            code[: MAX_CODE_LENGTH + 1],
        )
    if not allow_formulas and is_formula(code):
        raise LibraryFormatError(
            rowno, "code", "a code not starting with = + - @ (a spreadsheet formula; allow_formulas)", code
        )
    if code in seen:
        raise LibraryFormatError(rowno, "code", f"a unique code (first seen on row {seen[code]})", code)
    seen[code] = rowno
    return code


def read_library_csv(
    source: str | Path | io.TextIOBase, name: str | None = None, *, allow_formulas: bool = False
) -> Library:
    """Read a library CSV (see module docstring) from a path or text stream.

    Raises :class:`LibraryFormatError` naming row and column for every fault; never clamps. A code
    starting with ``= + - @`` (a spreadsheet formula) is refused unless *allow_formulas*.
    """
    stream, name = _open(source, name)
    reader = _records(stream)
    try:
        header = next(reader)
    except StopIteration as exc:
        raise LibraryFormatError(1, None, "a header row", "empty file") from exc
    header = [h.strip() for h in header]
    lab_header, extras = _split_extras(header)
    angles = _parse_header(lab_header)
    n_lab = len(lab_header)
    ncol = len(header)
    codes: list[str] = []
    types: list[str] = []
    gloss: list[float] = []
    labs: list[list[float]] = []
    flags: list[bool] = []
    recipes: list[dict[str, float]] = []
    seen: dict[str, int] = {}
    for rowno, row in enumerate(reader, start=2):
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != ncol:
            raise LibraryFormatError(rowno, None, f"{ncol} fields", len(row))
        if rowno > MAX_ROWS:
            raise LibraryFormatError(rowno, None, f"at most {MAX_ROWS} rows", rowno)
        code = _code(row[0], rowno, allow_formulas, seen)
        kind = row[1].strip().lower()
        if kind not in PAINT_TYPES:
            raise LibraryFormatError(rowno, "type", " | ".join(PAINT_TYPES), row[1])
        g = _number(row[2], rowno, "gloss_gu", *GLOSS_RANGE)
        values = []
        for col, text in zip(lab_header[3:], row[3:n_lab], strict=True):
            values.append(_number(text, rowno, col, *LAB_RANGES[col[0]]))
        cells = dict(zip(extras, row[n_lab:], strict=True))
        if "synthetic" in cells:
            flag = _BOOL.get(cells["synthetic"].strip().lower())
            if flag is None:
                raise LibraryFormatError(rowno, "synthetic", "true | false", cells["synthetic"])
            flags.append(flag)
        if "recipe" in cells:
            recipes.append(_parse_recipe(cells["recipe"], rowno))
        codes.append(code)
        types.append(kind)
        gloss.append(g)
        labs.append(values)
    if not codes:
        raise LibraryFormatError(2, None, "at least one paint row", "none")
    lab = np.asarray(labs, dtype=np.float64).reshape(len(codes), len(angles), 3)
    fractions, colorant_names = recipe_matrix(recipes)
    return Library(
        name=name or "library",
        codes=np.asarray(codes),
        types=np.asarray(types),
        gloss_gu=np.asarray(gloss),
        angles_deg=angles,
        lab=lab,
        synthetic=bool(flags) and all(flags),
        recipes=fractions,
        colorant_names=colorant_names,
        source="csv",
    )


def recipe_matrix(recipes: list[dict[str, float]]) -> tuple[np.ndarray | None, tuple[str, ...] | None]:
    """(N, C) mass fractions over the colorants named anywhere in *recipes*, or none when no row has a
    recipe; columns in the colorant database's order when every name is one of its colorants (so a round
    trip of the demo library gives back its matrix), else in first-seen order."""
    from station.formulate.colorants import default_database

    names: list[str] = []
    for r in recipes:
        names += [n for n in r if n not in names]
    if not names:
        return None, None
    known = default_database().names
    if set(names) <= set(known):
        names = list(known)
    matrix = np.array([[r.get(n, 0.0) for n in names] for r in recipes], dtype=np.float64)
    return matrix, tuple(names)


def write_library_csv(library: Library, target: str | Path | io.TextIOBase) -> None:
    """Write *library* as CSV (standard angles first), Lab and gloss to :data:`PRECISION_DECIMALS` decimals.

    A synthetic library is written as such: a ``synthetic`` column (and its codes carry the ``SYN-`` prefix
    the generator gave them); recipes go in a ``recipe`` column. A code a spreadsheet would
    evaluate (``=``, ``+``, ``-``, ``@``, tab, CR first) is written with a leading single quote.
    """
    names, fractions = library.colorant_names, library.recipes
    extras: tuple[str, ...] = ("synthetic",) if library.synthetic else ()
    if fractions is not None and names is not None:
        extras += ("recipe",)
    header = header_for(library.angles_deg, extras)
    lab_cols = header[: len(header) - len(extras)]
    order = [library.angles_deg.index(float(h[1:])) for h in lab_cols[3::3]]
    fmt = f"{{:.{PRECISION_DECIMALS}f}}"
    own = isinstance(target, (str, Path))
    fh = open(target, "w", newline="", encoding="utf-8") if isinstance(target, (str, Path)) else target
    try:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(header)
        lab = library.lab[:, order, :].reshape(len(library), -1)
        for i in range(len(library)):
            tail: list[str] = []
            if library.synthetic:
                tail.append("true")
            if fractions is not None and names is not None:
                tail.append(format_recipe(names, fractions[i]))
            w.writerow(
                [escape_cell(str(library.codes[i])), library.types[i], fmt.format(library.gloss_gu[i])]
                + [fmt.format(v) for v in lab[i]]
                + tail
            )
    finally:
        if own:
            fh.close()
