"""The PEP 562 loader shared by ``station.model`` and ``station.analysis`` (``station.lazy``)."""

from __future__ import annotations

import importlib
import sys
import textwrap
from pathlib import Path

import pytest

from station.lazy import lazy_getattr
from tests.processes import run


def _package(root: Path) -> None:
    """A package ``lazypkg`` whose name ``VALUE`` lives in ``lazypkg.heavy``, which records its import."""
    pkg = root / "lazypkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        textwrap.dedent(
            """
            from station.lazy import lazy_getattr

            __getattr__ = lazy_getattr(__name__, {"lazypkg.heavy": ("VALUE",)})
            """
        )
    )
    (pkg / "heavy.py").write_text(
        "import sys\nsys.heavy_imports = getattr(sys, 'heavy_imports', 0) + 1\nVALUE = 42\n"
    )


def test_a_name_is_loaded_on_first_use_and_only_then(tmp_path: Path) -> None:
    _package(tmp_path)
    script = textwrap.dedent(
        """
        import sys
        import lazypkg
        before = "lazypkg.heavy" in sys.modules
        first, second = lazypkg.VALUE, lazypkg.VALUE
        print(before, first, second, sys.heavy_imports)
        """
    )
    env_path = f"{tmp_path}:{Path(__file__).resolve().parents[1]}"
    done = run([sys.executable, "-c", script], timeout=60, env={"PYTHONPATH": env_path, "PATH": ""})
    assert done.returncode == 0, done.stderr
    out = done.stdout.split()
    assert out == ["False", "42", "42", "1"]


def test_an_unknown_name_raises_attribute_error_naming_the_package() -> None:
    import json

    getter = lazy_getattr("some.package", {"json": ("dumps",)})
    assert getter("dumps") is json.dumps
    with pytest.raises(AttributeError, match=r"module 'some.package' has no attribute 'missing'"):
        getter("missing")


def test_the_map_is_copied_so_a_later_change_to_it_does_not_leak_in() -> None:
    names = {"json": ["dumps"]}
    getter = lazy_getattr("pkg", names)
    names["json"].append("loads")
    import json

    assert getter("dumps") is json.dumps
    with pytest.raises(AttributeError):
        getter("loads")


@pytest.mark.parametrize("package", ["station.model", "station.analysis", "station.api"])
def test_every_lazy_name_of_the_packages_is_the_object_its_module_defines(package: str) -> None:
    pkg = importlib.import_module(package)
    lazy = pkg._LAZY
    assert lazy, package
    for module, names in lazy.items():
        for name in names:
            assert getattr(pkg, name) is getattr(importlib.import_module(module), name), (name, module)
            assert name in pkg.__all__, name
    with pytest.raises(AttributeError, match=package):
        pkg.no_such_name  # noqa: B018


def test_a_name_listed_under_two_modules_is_refused() -> None:
    with pytest.raises(ValueError, match="'dumps' listed under json and pickle"):
        lazy_getattr("pkg", {"json": ("dumps",), "pickle": ("dumps",)})
