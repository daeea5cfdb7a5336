"""Names of a package loaded on first use (PEP 562), so that importing the package stays cheap.

A package whose public names pull in heavy libraries (colour-science, SciPy) keeps its cheap names
imported eagerly and hands the others to :func:`lazy_getattr`::

    __getattr__ = lazy_getattr(__name__, {"station.model.fit": ("FitResult", "fit_fftg")})

The module is imported the first time one of its names is asked for; Python caches it, so later
look-ups cost a dictionary read.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterable, Mapping
from types import MappingProxyType, ModuleType
from typing import Any


def lazy_getattr(package: str, modules: Mapping[str, Iterable[str]]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for *package* that loads each name of *modules* from its module.

    *modules* maps a dotted module to the public names it defines. A name not listed raises
    :class:`AttributeError` naming *package*, as a module without ``__getattr__`` does; a name listed
    under two modules raises :class:`ValueError` at once.
    """
    names: dict[str, str] = {}
    for module, listed in modules.items():
        for name in listed:
            if name in names:
                raise ValueError(f"{package}: {name!r} listed under {names[name]} and {module}")
            names[name] = module
    table = MappingProxyType(names)

    def __getattr__(name: str) -> Any:
        """Load *name* from its module the first time it is asked for."""
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(module), name)

    return __getattr__


class _DeferredSubmodule(ModuleType):
    """A stand-in for a library's submodule that imports the real one on its first attribute look-up."""

    def __getattr__(self, name: str) -> Any:
        if sys.modules.get(self.__name__) is self:
            del sys.modules[self.__name__]
        return getattr(importlib.import_module(self.__name__), name)


def defer_submodule(name: str) -> None:
    """Let the package that imports submodule *name* on its own import (as colour-science imports
    ``colour.plotting``, and with it Matplotlib's pyplot: about 0.4 s of CPU per process) load it only
    when one of its names is first used. Nothing changes for code that uses the submodule; a submodule
    already imported is left as it is."""
    if name not in sys.modules:
        sys.modules[name] = _DeferredSubmodule(name)
