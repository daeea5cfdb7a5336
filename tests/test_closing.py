"""``station.closing.Closing``: ``with`` gives the object itself and closes it on the way out, exception or not."""

from __future__ import annotations

import pytest

from station.closing import Closing


class _Held(Closing):
    def __init__(self) -> None:
        self.closed = 0

    def close(self) -> None:
        self.closed += 1


def test_the_block_gets_the_object_and_closes_it_once() -> None:
    held = _Held()
    with held as got:
        assert got is held and held.closed == 0
    assert held.closed == 1


def test_an_exception_in_the_block_still_closes_and_propagates() -> None:
    held = _Held()
    with pytest.raises(KeyError), held:
        raise KeyError("x")
    assert held.closed == 1


def test_a_class_without_close_says_so() -> None:
    with pytest.raises(NotImplementedError, match="Bare must define close"), type("Bare", (Closing,), {})():
        pass
