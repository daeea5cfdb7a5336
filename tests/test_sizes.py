"""Rooms of the right size: no function over 80 lines and no file over 600 lines, beyond a shrinking list.

Every ``.py`` file of ``station/``, ``db/``, ``ui/``, ``simulators/`` and ``bench/`` (frozen migrations
excepted) is parsed with :mod:`ast`. A function (or method, named ``Class.method``) longer than
:data:`MAX_FUNCTION_LINES` lines, decorators and docstring included, or a file longer than
:data:`MAX_FILE_LINES` lines, fails the test unless :data:`ALLOWED` names it with the reason it is still
that long. The list only shrinks: an entry that is no longer over its limit fails too, so a split is
followed by deleting its entry. Split by responsibility (CONTRIBUTING, "Conventions"); a widget's
constructor into small builder methods.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ROOTS = ("station", "db", "ui", "simulators", "bench")
FROZEN = ("db/migrations",)
MAX_FUNCTION_LINES = 80
MAX_FILE_LINES = 600


#: ``path`` (a file over 600 lines) or ``path:qualname`` (a function over 80 lines) → why it still is.
ALLOWED: dict[str, str] = {}


def _functions(tree: ast.Module) -> Iterator[tuple[str, int]]:
    """``(qualname, lines)`` of every function and method of *tree*, nested ones included."""

    def walk(node: ast.AST, prefix: str) -> Iterator[tuple[str, int]]:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                first = min([child.lineno, *(d.lineno for d in child.decorator_list)])
                assert child.end_lineno is not None
                yield prefix + child.name, child.end_lineno - first + 1
                yield from walk(child, f"{prefix}{child.name}.")
            elif isinstance(child, ast.ClassDef):
                yield from walk(child, f"{prefix}{child.name}.")
            else:
                yield from walk(child, prefix)

    return walk(tree, "")


def oversized(root: Path, roots: tuple[str, ...] = ROOTS) -> dict[str, int]:
    """Every file over :data:`MAX_FILE_LINES` lines (``path``) and function over
    :data:`MAX_FUNCTION_LINES` lines (``path:qualname``) under *roots* of *root*, with its length."""
    found: dict[str, int] = {}
    for top in roots:
        for path in sorted((root / top).rglob("*.py")):
            rel = path.relative_to(root).as_posix()
            if rel.startswith(FROZEN):
                continue
            text = path.read_text(encoding="utf-8")
            lines = len(text.splitlines())
            if lines > MAX_FILE_LINES:
                found[rel] = lines
            for name, length in _functions(ast.parse(text, filename=rel)):
                if length > MAX_FUNCTION_LINES:
                    found[f"{rel}:{name}"] = length
    return found


@pytest.fixture(scope="module")
def found() -> dict[str, int]:
    """The repository's oversized files and functions (parsed once for the module's tests)."""
    return oversized(REPO)


def test_no_function_or_file_is_over_its_limit_beyond_the_list(found: dict[str, int]) -> None:
    new = {k: v for k, v in found.items() if k not in ALLOWED}
    assert not new, "over the limit (split it by responsibility): " + ", ".join(
        f"{k} ({v} lines)" for k, v in sorted(new.items())
    )


def test_the_list_only_shrinks(found: dict[str, int]) -> None:
    stale = sorted(k for k in ALLOWED if k not in found)
    assert not stale, "no longer over the limit, delete from ALLOWED: " + ", ".join(stale)
    assert all(reason.strip() for reason in ALLOWED.values())


def test_a_planted_long_function_and_file_are_found(tmp_path: Path) -> None:
    pkg = tmp_path / "station"
    pkg.mkdir()

    def body(n: int, indent: str) -> str:
        return "\n".join(f"{indent}x{i} = {i}" for i in range(n))

    (pkg / "short.py").write_text(f"def fits():\n{body(MAX_FUNCTION_LINES - 1, '    ')}\n")  # 80 lines
    (pkg / "long.py").write_text(
        f"class C:\n    @staticmethod\n    def m():\n{body(MAX_FUNCTION_LINES, '        ')}\n"
    )
    (pkg / "big.py").write_text("\n".join(f"V{i} = {i}" for i in range(MAX_FILE_LINES + 1)) + "\n")
    migrations = tmp_path / "db" / "migrations"
    migrations.mkdir(parents=True)
    (migrations / "old.py").write_text("\n".join(f"V{i} = {i}" for i in range(MAX_FILE_LINES + 5)) + "\n")
    assert oversized(tmp_path, ("station", "db")) == {
        "station/big.py": MAX_FILE_LINES + 1,
        "station/long.py:C.m": MAX_FUNCTION_LINES + 2,  # the decorator counts
    }
