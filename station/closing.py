"""A ``with`` block for an object that holds something it must give back (a file, a process, a connection).

A class with a ``close()`` method inherits :class:`Closing` instead of writing ``__enter__`` and ``__exit__``
itself::

    class Outbox(Closing):
        def close(self) -> None: ...

    with Outbox(path) as box:  # box.close() runs on the way out, exception or not
        ...
"""

from __future__ import annotations

from typing import Self


class Closing:
    """``with obj:`` gives *obj* itself and calls its :meth:`close` on the way out (exceptions propagate)."""

    def close(self) -> None:
        """Give back what the object holds; a subclass defines it."""
        raise NotImplementedError(f"{type(self).__name__} must define close()")

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
