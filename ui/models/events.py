"""A minimal observer: named events with connect/disconnect, and a blocker against feedback loops.

The view models never import Qt; widgets subscribe with ``model.events.changed.connect(self._on_changed)``
and unsubscribe on close (napari's pattern, see docs/viewer.md).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

Callback = Callable[..., Any]


class Event:
    """One event: an ordered list of callbacks called with the emitted arguments."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._callbacks: list[Callback] = []
        self._blocked = 0

    def connect(self, callback: Callback) -> None:
        """Subscribe *callback* (once; connecting twice is a no-op)."""
        if callback not in self._callbacks:
            self._callbacks.append(callback)

    def disconnect(self, callback: Callback) -> None:
        """Unsubscribe *callback* (absent callbacks are ignored)."""
        if callback in self._callbacks:
            self._callbacks.remove(callback)

    @property
    def callbacks(self) -> tuple[Callback, ...]:
        """The subscribed callbacks, in call order."""
        return tuple(self._callbacks)

    def emit(self, *args: Any) -> None:
        """Call every callback with *args* unless blocked."""
        if self._blocked:
            return
        for cb in list(self._callbacks):
            cb(*args)

    @contextmanager
    def blocker(self) -> Iterator[None]:
        """Suppress emissions inside the ``with`` block."""
        self._blocked += 1
        try:
            yield
        finally:
            self._blocked -= 1


class EventGroup:
    """A namespace of events: ``EventGroup("changed", "undo")`` gives ``.changed`` and ``.undo``."""

    def __init__(self, *names: str) -> None:
        self._names = names
        for n in names:
            setattr(self, n, Event(n))

    def __getattr__(self, name: str) -> Event:  # only reached for unknown names
        raise AttributeError(f"no event {name!r}; events are {self._names}")

    def disconnect_all(self, owner: object) -> None:
        """Disconnect every bound method of *owner* from every event."""
        for n in self._names:
            ev: Event = getattr(self, n)
            for cb in ev.callbacks:
                if getattr(cb, "__self__", None) is owner:
                    ev.disconnect(cb)
