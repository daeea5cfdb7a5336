"""station.jit.CompiledLoops: numba compiles plain loops once, inline helpers included; a loop numba
cannot compile gives None (the caller's plain loop runs)."""

from __future__ import annotations

import threading

import numpy as np

from station.jit import CompiledLoops


def _square(x: float) -> float:
    return x * x


def _sum_of_squares(a: np.ndarray) -> float:
    total = 0.0
    for v in a:
        total += _square(v)
    return total


def _not_compilable(a: np.ndarray) -> object:
    return {"a": object(), "n": len(a)}  # arbitrary Python objects: numba's nopython mode refuses them


def test_compiled_loop_equals_the_plain_loop_and_is_built_once() -> None:
    warmed: list[int] = []
    loops = CompiledLoops(
        (_sum_of_squares,), inline=(_square,), warm_up=lambda f: warmed.append(f(np.ones(2)))
    )
    got: list[object] = []
    threads = [threading.Thread(target=lambda: got.append(loops.get())) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert got[0] is not None and all(g is got[0] for g in got)  # one compilation for four callers
    assert warmed == [2]
    first = got[0]
    assert isinstance(first, tuple) and len(first) == 1
    compiled = first[0]
    a = np.random.default_rng(3).normal(size=1000)
    assert compiled(a) == _sum_of_squares(a) == sum(float(v) * float(v) for v in a)
    assert compiled is not _sum_of_squares


def test_a_loop_numba_cannot_compile_gives_none() -> None:
    loops = CompiledLoops((_not_compilable,), warm_up=lambda f: f(np.ones(1)))
    assert loops.get() is None and loops.get() is None
