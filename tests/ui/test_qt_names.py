"""No viewer widget overwrites a member of its Qt base class.

A widget attribute named like a Qt member (``self.render = QLabel()``, ``self.model = model`` on a
QListWidget) hides the Qt method from Python callers and from anything that looks it up by name, and a
Python method named like a non-virtual Qt method (``update``) is bypassed whenever Qt calls its own. Every
QObject subclass of the viewer (``ui/widgets/*``, ``ui/app.py``) is checked three ways against the names
of its first Qt base class:

* the names its own classes define (methods, properties, signals, class attributes), overrides of Qt's
  virtual functions excepted;
* the attributes its methods assign (``self.X = ...`` anywhere in the class source);
* the instance attributes of the constructed main window, every screen built, and every widget in it.

Planted classes prove each check fails on a shadowing name and lets a virtual override through.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import textwrap
from types import ModuleType

import pytest
from PySide6.QtCore import QObject, Signal, SignalInstance
from PySide6.QtGui import QPaintEvent
from PySide6.QtWidgets import QLabel, QWidget

import ui.app
import ui.widgets

pytestmark = [pytest.mark.qt]

#: Qt's virtual functions the viewer overrides on purpose (besides every ``...Event`` handler, which Qt
#: declares virtual): Qt calls the Python override.
VIRTUALS = frozenset({"event", "eventFilter", "run", "paintGL", "resizeGL", "initializeGL", "sizeHint"})

#: Non-virtual Qt methods a class extends, calling the Qt method itself, with the reason it may.
EXTENDED = {
    (
        "GcPausingThread",
        "start",
    ): "pauses the cyclic collector, then calls QThread.start; Qt never calls start()",
}

#: Names PySide6 itself puts on every subclass.
BINDING_NAMES = frozenset({"staticMetaObject"})


def _is_qt(cls: type) -> bool:
    return cls.__module__.split(".")[0] in ("PySide6", "shiboken6", "Shiboken")


def qt_base(cls: type) -> type:
    """The first Qt class in *cls*'s method resolution order."""
    return next(k for k in cls.__mro__ if _is_qt(k))


def _own_classes(cls: type) -> list[type]:
    """The classes of *cls*'s MRO written in Python (before its Qt base), ``typing.Generic`` left out."""
    out = []
    for k in cls.__mro__:
        if _is_qt(k):
            break
        if k.__module__ != "typing":
            out.append(k)
    return out


def _qt_names(cls: type) -> set[str]:
    return {n for n in dir(qt_base(cls)) if not n.startswith("__")} - BINDING_NAMES


def _allowed(cls: type, name: str) -> bool:
    member = inspect.getattr_static(cls, name)
    overrides_virtual = callable(member) and (name.endswith("Event") or name in VIRTUALS)
    extends = any(k.__name__ == c and name == n for k in _own_classes(cls) for c, n in EXTENDED)
    return overrides_virtual or extends


def class_shadows(cls: type) -> list[str]:
    """Names defined by *cls*'s own classes that are members of its Qt base (virtual overrides allowed)."""
    qt = _qt_names(cls)
    own = {n for k in _own_classes(cls) for n in vars(k)}
    return sorted(n for n in own & qt if not _allowed(cls, n))


def assigned_shadows(cls: type) -> list[str]:
    """Names assigned as ``self.X`` in the source of *cls*'s own classes that are members of its Qt base."""
    assigned: set[str] = set()
    for k in _own_classes(cls):
        tree = ast.parse(textwrap.dedent(inspect.getsource(k)))
        for node in ast.walk(tree):
            targets = node.targets if isinstance(node, ast.Assign) else []
            if isinstance(node, (ast.AnnAssign, ast.AugAssign)):
                targets = [node.target]
            for t in targets:
                for leaf in ast.walk(t):
                    if isinstance(leaf, ast.Attribute) and isinstance(leaf.value, ast.Name):
                        if leaf.value.id == "self":
                            assigned.add(leaf.attr)
    return sorted(assigned & _qt_names(cls))


def instance_shadows(obj: QObject) -> list[str]:
    """Instance attributes of *obj* that are members of its Qt base (PySide6 keeps a Qt signal it has
    bound for the object in the instance dictionary: that is the signal itself, not a shadow)."""
    qt = qt_base(type(obj))
    return sorted(
        n
        for n, value in vars(obj).items()
        if n in _qt_names(type(obj))
        and not (isinstance(value, SignalInstance) and isinstance(inspect.getattr_static(qt, n), Signal))
    )


def _viewer_modules() -> list[ModuleType]:
    names = [f"ui.widgets.{m.name}" for m in pkgutil.iter_modules(ui.widgets.__path__)]
    return [importlib.import_module(n) for n in names] + [ui.app]


def viewer_classes() -> list[type]:
    """Every QObject subclass defined in ``ui/widgets`` and ``ui/app.py``."""
    found = []
    for module in _viewer_modules():
        for obj in vars(module).values():
            if inspect.isclass(obj) and issubclass(obj, QObject) and obj.__module__ == module.__name__:
                found.append(obj)
    return found


# ---------------------------------------------------------------- planted classes


class _PlantedMethod(QWidget):
    def update(self) -> None:  # type: ignore[override]  # the planted fault: QWidget.update replaced
        pass

    def paintEvent(self, event: QPaintEvent) -> None:  # a virtual handler: allowed
        super().paintEvent(event)


class _PlantedAttribute(QWidget):
    def __init__(self) -> None:
        super().__init__()
        self.preview = QLabel(self)  # fine
        self.render = QLabel(self)  # type: ignore[method-assign,assignment]  # the planted fault


# ---------------------------------------------------------------- tests


def test_the_checks_fail_on_planted_shadowing(qtbot) -> None:
    assert class_shadows(_PlantedMethod) == ["update"]
    assert assigned_shadows(_PlantedAttribute) == ["render"]
    planted = _PlantedAttribute()
    qtbot.addWidget(planted)
    assert instance_shadows(planted) == ["render"]
    assert class_shadows(_PlantedAttribute) == [] and assigned_shadows(_PlantedMethod) == []


def test_every_viewer_qobject_class_is_checked() -> None:
    names = {c.__name__ for c in viewer_classes()}
    # one from each kind of module: a screen, a view, a plot, a worker thread, the window
    assert {"InstrumentsScreen", "GLRenderView", "CurvePlot", "TaskThread", "MainWindow"} <= names
    assert len(names) >= 25


@pytest.mark.parametrize("cls", viewer_classes(), ids=lambda c: f"{c.__module__}.{c.__name__}")
def test_no_class_shadows_its_qt_base(cls: type) -> None:
    assert class_shadows(cls) == [], f"{cls.__name__} redefines {qt_base(cls).__name__} members"
    assert assigned_shadows(cls) == [], f"{cls.__name__} assigns over {qt_base(cls).__name__} members"


def test_no_constructed_widget_shadows_its_qt_base(qtbot, tmp_path) -> None:
    from ui.app import MainWindow
    from ui.models.measure_db import LocalSink
    from ui.widgets.screens import LazyScreen

    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    win = MainWindow(sink=sink, ask_on_close=False)
    qtbot.addWidget(win)
    try:
        for page in win.screens.values():
            if isinstance(page, LazyScreen):
                page.content()  # every screen built, as its first showing would
        objects = [win, *win.findChildren(QObject)]
        ours = [o for o in objects if type(o).__module__.startswith("ui.")]
        assert len({type(o).__name__ for o in ours}) >= 15  # the screens, their plots and views
        shadows = {type(o).__name__: s for o in ours if (s := instance_shadows(o))}
        assert shadows == {}
    finally:
        win.close()
        qtbot.wait(1)
