"""Every ``clicked`` connection of the viewer's widgets to a method of the widget names a method that takes
no argument: Qt's ``clicked(bool)`` then drops its ``checked`` flag. A method with a parameter (even one
with a default) would receive ``checked`` in it, as "Load stored measurements" once received it as its
row limit. Lambdas are the author's explicit choice and are not checked here."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

WIDGETS = Path(__file__).resolve().parents[2] / "ui" / "widgets"


def _clicked_slots(tree: ast.Module) -> list[tuple[str, str, int]]:
    """(class, method, line) of every ``<x>.clicked.connect(self.<method>)`` inside a class."""
    out = []
    for cls in (n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)):
        for call in (n for n in ast.walk(cls) if isinstance(n, ast.Call)):
            f = call.func
            if (
                isinstance(f, ast.Attribute)
                and f.attr == "connect"
                and isinstance(f.value, ast.Attribute)
                and f.value.attr == "clicked"
                and len(call.args) == 1
                and isinstance(slot := call.args[0], ast.Attribute)
                and isinstance(slot.value, ast.Name)
                and slot.value.id == "self"
            ):
                out.append((cls.name, slot.attr, call.lineno))
    return out


def _methods(tree: ast.Module, cls_name: str) -> dict[str, ast.FunctionDef]:
    cls = next(n for n in ast.walk(tree) if isinstance(n, ast.ClassDef) and n.name == cls_name)
    return {n.name: n for n in cls.body if isinstance(n, ast.FunctionDef)}


@pytest.mark.parametrize("path", sorted(WIDGETS.glob("*.py")), ids=lambda p: p.name)
def test_clicked_slots_take_no_checked_flag(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for cls_name, method, line in _clicked_slots(tree):
        fn = _methods(tree, cls_name).get(method)
        assert fn is not None, f"{path.name}:{line}: {cls_name}.{method} is not defined in the class"
        a = fn.args
        extra = [x.arg for x in a.posonlyargs + a.args][1:] + ([a.vararg.arg] if a.vararg else [])
        assert not extra, (
            f"{path.name}:{line}: clicked(bool) connected to {cls_name}.{method}({', '.join(extra)}): "
            "the checked flag would land in its first parameter; connect a no-argument method instead"
        )


def test_the_check_sees_the_qa_button():
    """The scan finds the connections it guards (here: the QA screen's three buttons)."""
    tree = ast.parse((WIDGETS / "qa_screen.py").read_text(encoding="utf-8"))
    names = {m for _c, m, _l in _clicked_slots(tree)}
    assert {"run", "_on_load_clicked", "_send"} <= names
