"""The edited design with an undo/redo stack of immutable designs.

Every edit goes through :meth:`DesignDocument.apply` (or :meth:`set_design`) and pushes the previous
:class:`~station.model.FaceFlopTravelGloss` onto the undo stack. Designs are frozen dataclasses, so
undo restores the exact object that was current (identity and every float bit). Consecutive edits
that share a ``merge_key`` (one drag of a plot point, one slider movement) collapse into one undo step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from station.errors import InputError
from station.model import FaceFlopTravelGloss
from ui.models.events import EventGroup

DEFAULT_DESIGN = FaceFlopTravelGloss((55.0, 8.0, -38.0), (28.0, 2.0, -30.0), 70.0, 85.0)
UNDO_LIMIT = 500


@dataclass(frozen=True)
class Edit:
    """One undo step: the design before, the design after and a label for the menu."""

    label: str
    before: FaceFlopTravelGloss
    after: FaceFlopTravelGloss
    merge_key: str | None = None


class DesignDocument:
    """The current design, its name and the undo/redo history (Qt-free).

    Events: ``changed(design)`` after every change (edit, undo, redo); ``error(message)`` when an edit
    was refused by the core (the design is left unchanged); ``history()`` when undo/redo availability
    may have changed.
    """

    def __init__(self, design: FaceFlopTravelGloss = DEFAULT_DESIGN, name: str = "untitled") -> None:
        self._design = design
        self.name = name
        self._undo: list[Edit] = []
        self._redo: list[Edit] = []
        self.events = EventGroup("changed", "error", "history")

    @property
    def design(self) -> FaceFlopTravelGloss:
        """The current design."""
        return self._design

    @property
    def can_undo(self) -> bool:
        """Whether an undo step exists."""
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        """Whether a redo step exists."""
        return bool(self._redo)

    @property
    def undo_label(self) -> str | None:
        """Label of the step :meth:`undo` would revert."""
        return self._undo[-1].label if self._undo else None

    def set_design(
        self, design: FaceFlopTravelGloss, label: str = "edit", merge_key: str | None = None
    ) -> None:
        """Make *design* current as one undoable edit (no-op when equal to the current one)."""
        if not isinstance(design, FaceFlopTravelGloss):
            raise TypeError(f"expected FaceFlopTravelGloss, got {type(design).__name__}")
        if design == self._design:
            return
        last = self._undo[-1] if self._undo else None
        if merge_key is not None and last is not None and last.merge_key == merge_key and not self._redo:
            self._undo[-1] = Edit(label, last.before, design, merge_key)
        else:
            self._undo.append(Edit(label, self._design, design, merge_key))
            del self._undo[:-UNDO_LIMIT]
        self._redo.clear()
        self._design = design
        self.events.changed.emit(design)
        self.events.history.emit()

    def apply(
        self,
        op: Callable[[FaceFlopTravelGloss], FaceFlopTravelGloss],
        label: str,
        merge_key: str | None = None,
    ) -> bool:
        """Run a core operation on the current design and keep the result; False (and an ``error``
        event with the core's message) when the core refuses the input."""
        try:
            new = op(self._design)
        except InputError as exc:
            self.events.error.emit(str(exc))
            return False
        self.set_design(new, label, merge_key)
        return True

    def end_merge(self) -> None:
        """Close the current merge group (mouse released): the next edit starts a new undo step."""
        if self._undo and self._undo[-1].merge_key is not None:
            e = self._undo[-1]
            self._undo[-1] = Edit(e.label, e.before, e.after, None)

    def undo(self) -> bool:
        """Restore the design before the last edit; False when there is none."""
        if not self._undo:
            return False
        e = self._undo.pop()
        self._redo.append(e)
        self._design = e.before
        self.events.changed.emit(self._design)
        self.events.history.emit()
        return True

    def redo(self) -> bool:
        """Re-apply the last undone edit; False when there is none."""
        if not self._redo:
            return False
        e = self._redo.pop()
        self._undo.append(e)
        self._design = e.after
        self.events.changed.emit(self._design)
        self.events.history.emit()
        return True
