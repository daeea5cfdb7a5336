"""Waiting for something in a test: poll a condition until a deadline, never sleep a guessed time.

A fixed sleep is either too short on a loaded machine (the test fails) or too long on an idle one (the
suite crawls). :func:`wait_until` polls instead and returns as soon as the condition holds; its
*timeout* only bounds how long a failure takes to show, it never changes what the test decides. This is
the one place in the suite where a test pauses (``tests/test_suite_hygiene.py`` keeps it so).

:func:`pause` is for the other kind of pause, the one that is itself the behaviour under test and waits
for nothing: a slow client trickling bytes, a device that answers late, a stand-in that holds a slot
for a while so that callers overlap. Such a pause never decides a result by the clock; the hygiene test
lets only the files it names call it, each with its reason.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")

#: Seconds between two polls unless the caller says otherwise.
POLL_INTERVAL_S = 0.05


class WaitTimeout(AssertionError):
    """The condition did not hold before the deadline (a test failure, with what was last seen)."""


def wait_until(
    predicate: Callable[[], T],
    timeout: float,
    interval: float = POLL_INTERVAL_S,
    what: str = "",
) -> T:
    """Call *predicate* every *interval* seconds until it returns a true value, and return that value.

    Raises :class:`WaitTimeout` naming *what* (or the predicate) and the last value seen once *timeout*
    seconds have passed; the predicate is always called at least once, and once more at the deadline.
    """
    if timeout < 0 or interval <= 0:
        raise ValueError(f"timeout must be >= 0 and interval > 0 (got {timeout}, {interval})")
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        left = deadline - time.monotonic()
        if left <= 0:
            name = what or getattr(predicate, "__qualname__", repr(predicate))
            raise WaitTimeout(f"not true within {timeout:g} s: {name} (last seen: {value!r})")
        time.sleep(min(interval, left))


def pause(seconds: float, why: str) -> None:
    """Pause *seconds* seconds as part of what a test does (never to wait for something: that is
    :func:`wait_until`); *why* says what the pause plays, e.g. "a slow client between two bytes"."""
    if seconds < 0 or not why:
        raise ValueError(f"a pause needs seconds >= 0 and a reason (got {seconds}, {why!r})")
    time.sleep(seconds)
