"""Names of a package loaded on first use (PEP 562), so that importing the package stays cheap.

A package whose public names pull in heavy libraries (colour-science, SciPy) keeps its cheap names
imported eagerly and hands the others to :func:`lazy_getattr`::

    __getattr__ = lazy_getattr(__name__, {"FitResult": "station.model.fit"})

The module is imported the first time one of its names is asked for; Python caches it, so later
look-ups cost a dictionary read.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any


def lazy_getattr(package: str, names: Mapping[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for *package* that loads each name of *names* from its module.

    *names* maps a public name to the dotted module that defines it. A name not in *names* raises
    :class:`AttributeError` naming *package*, as a module without ``__getattr__`` does.
    """
    table = MappingProxyType(dict(names))

    def __getattr__(name: str) -> Any:
        """Load *name* from its module the first time it is asked for."""
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(module), name)

    return __getattr__
