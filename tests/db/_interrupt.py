"""A Ctrl-C that lands inside a database statement, for tests: KeyboardInterrupt raised from a
``before_cursor_execute`` hook, inside the statement's error handling as a signal would be."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from sqlalchemy import event


@contextmanager
def interrupt_at(target: Any, prefix: str) -> Iterator[list[bool]]:
    """While open, raise KeyboardInterrupt in the next statement on *target* (an engine, or the Engine class
    for every engine) whose text starts with *prefix* (case-insensitive); yields the flag, True until it
    fired."""
    armed = [True]
    prefix = prefix.upper()

    def boom(conn, cursor, statement, parameters, context, executemany) -> None:
        if armed[0] and statement.lstrip().upper().startswith(prefix):
            armed[0] = False
            raise KeyboardInterrupt

    event.listen(target, "before_cursor_execute", boom)
    try:
        yield armed
    finally:
        event.remove(target, "before_cursor_execute", boom)
