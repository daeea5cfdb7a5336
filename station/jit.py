"""Plain-Python numeric loops compiled by numba: once per process, cached on disk, or not at all.

A module writes its inner loops as plain Python functions in the subset numba compiles (they stay what
tests call, and the fallback where numba is missing or cannot compile) and holds one
:class:`CompiledLoops` for them::

    _LOOPS = CompiledLoops((grid_sum, brute_sum), inline=(sample_cube_one,), warm_up=_warm_up)
    loops = _LOOPS.get()  # the compiled functions in the same order, or None

Helpers called from the loops are compiled inline (``numba.extending.register_jitable``), not rebound.
The first :meth:`CompiledLoops.get` compiles (or loads numba's on-disk cache) and runs *warm_up* on the
compiled functions, so that no query pays for the compilation midway; later calls return the same
functions. Compilation runs once even when two threads ask at once.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["CompiledLoops"]

Loop = Callable[..., Any]


class CompiledLoops:
    """The numba compilation of *functions* (in order), each with ``nogil`` and the on-disk cache, with
    *inline* registered as jitable helpers and *warm_up* called on the compiled functions; None where
    numba is missing or any of these raises (the caller then runs the plain functions)."""

    def __init__(
        self,
        functions: Sequence[Loop],
        inline: Sequence[Loop] = (),
        warm_up: Callable[..., object] | None = None,
    ) -> None:
        self._functions = tuple(functions)
        self._inline = tuple(inline)
        self._warm_up = warm_up
        self._lock = threading.Lock()
        self._done = False
        self._compiled: tuple[Loop, ...] | None = None

    def get(self) -> tuple[Loop, ...] | None:
        """The compiled functions in the order given, or None where numba cannot compile them here."""
        with self._lock:
            if not self._done:
                self._compiled = self._compile()
                self._done = True
            return self._compiled

    def _compile(self) -> tuple[Loop, ...] | None:
        try:
            import numba
            from numba.extending import register_jitable
        except ImportError:  # pragma: no cover - numba is a declared dependency
            return None
        try:
            for helper in self._inline:
                register_jitable(helper)
            compiled = tuple(numba.njit(cache=True, nogil=True)(f) for f in self._functions)
            if self._warm_up is not None:
                self._warm_up(*compiled)
        except Exception:  # pragma: no cover - a numba that cannot compile here: the plain loops run
            return None
        return compiled
