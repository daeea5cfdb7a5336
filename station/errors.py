"""Root of every exception the core raises.

Each core package derives its own hierarchy from :class:`StationError`, so a front (CLI, service,
viewer) can catch one type and show the message. Errors about bad input subclass :class:`ValueError`
as well and carry the offending *field* and the *accepted* range, so the message always names both.
"""

from __future__ import annotations


class StationError(Exception):
    """Base class of every error raised by the ``station`` core."""


class InputError(StationError, ValueError):
    """Bad input: names the field, the accepted range and what was given.

    Parameters
    ----------
    field
        Dotted name of the offending input, e.g. ``"lab[2].L"`` or ``"travel_deg"``.
    accepted
        Human-readable accepted range, e.g. ``"15 < travel_deg <= 180"``.
    got
        The value received (rendered with ``repr``), or ``None`` to omit it.
    """

    def __init__(self, field: str, accepted: str, got: object = None, detail: str = "") -> None:
        self.field = field
        self.accepted = accepted
        self.got = got
        msg = f"{field}: expected {accepted}"
        if got is not None:
            msg += f", got {got!r}"
        if detail:
            msg += f" ({detail})"
        super().__init__(msg)
