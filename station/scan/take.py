"""Measure and pair: a gloss meter paired with a spectrophotometer is read first, then the colour.

:func:`take` is the one place a gloss reading is paired with a colour reading; :func:`make_records`
the one place they become ingest records (``station.ingest.record_from_reading`` with the 60° gloss,
and ``station.ingest.gloss_record_from_reading`` for the gloss meter's full reading).
"""

from __future__ import annotations

import uuid
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Literal, Unpack

from station.drivers import GlossReading, Instrument, SpectralReading
from station.scan.errors import ScanInputError
from station.scan.result import ScanResult

if TYPE_CHECKING:
    from station.ingest.records import ReadingTarget

__all__ = ["GLOSS_GEOMETRY_DEG", "Progress", "gloss_client_id", "make_records", "take"]

#: The gloss geometry stored with a colour reading (degrees, ISO 2813).
GLOSS_GEOMETRY_DEG = 60
#: ``progress(steps done, text)``; it may raise (a user's cancel) before anything is stored.
Progress = Callable[[int, str], None]
_GLOSS_NAMESPACE = uuid.UUID("5f0c2e47-8d1b-4a6e-9c3f-71b2d4e8a905")


def gloss_client_id(colour_client_id: uuid.UUID) -> uuid.UUID:
    """The client id of the gloss record taken with the colour reading *colour_client_id*: derived, so a
    retry of the scan names the same gloss record and stores nothing new."""
    return uuid.uuid5(_GLOSS_NAMESPACE, str(colour_client_id))


def take(
    instrument: Instrument[Any],
    gloss_meter: Instrument[Any] | None = None,
    *,
    device: str = "",
    gloss_device: str = "",
    progress: Progress | None = None,
    gloss_field: str = "gloss_device",
) -> ScanResult:
    """Measure one panel: the paired *gloss_meter* first (20/60/85° GU, haze, DOI), then *instrument*.

    A gloss meter as *instrument* gives a gloss-only result (a paired meter is not read). The paired
    meter must give a :class:`GlossReading` with a 60° value, else :class:`ScanInputError` naming
    *gloss_field*. *progress* hears step 0 before each measurement and step 1 once measured.
    """
    say = progress or (lambda _s, _t: None)
    gloss: GlossReading | None = None
    if gloss_meter is not None and instrument.kind != "gloss":
        say(0, f"reading the gloss meter {gloss_device}".rstrip())
        got = gloss_meter.measure()
        if not isinstance(got, GlossReading) or GLOSS_GEOMETRY_DEG not in got.gloss_gu:
            raise ScanInputError(gloss_field, "a gloss meter with a 60° geometry", gloss_device or None)
        gloss = got
    say(0, f"measuring with {device}".rstrip())
    reading = instrument.measure()
    say(1, "measured")
    if isinstance(reading, GlossReading):
        return ScanResult(device, None, reading)
    if not isinstance(reading, SpectralReading):
        raise ScanInputError("instrument", "a spectrophotometer or a gloss meter", type(reading).__name__)
    return ScanResult(device, reading, gloss)


def make_records(
    result: ScanResult,
    *,
    measurement_id: int | None = None,
    refused: Literal["raise", "note"] = "raise",
    **target: Unpack[ReadingTarget],
) -> ScanResult:
    """*result* with its ingest records; *target* holds the keywords of ``record_from_reading``
    (``operator`` required; ``illumination_deg``, ``client_id``, ``instrument``, ``panel_id``, ``panel``).

    Colour: ``record_from_reading`` of the *illumination_deg* block (degrees) with the paired meter's
    60° gloss (GU), under *client_id* (a fresh one by default), on *panel_id* or *panel*; the gloss
    meter's full reading then becomes a gloss record under :func:`gloss_client_id`, joined to the colour
    measurement when that is stored. Gloss alone: a gloss record of its own under *client_id*, on
    *panel_id* or *panel*, naming the colour measurement *measurement_id* when given. A record the ingest schema refuses raises (``InputError`` or pydantic's
    ``ValidationError``, both ``ValueError``), or with ``refused="note"`` is left out with the reason in
    :attr:`ScanResult.note` (the viewer shows the reading all the same).
    """
    from dataclasses import replace

    from station.ingest import gloss_record_from_reading, record_from_reading

    try:
        if result.colour is None:
            if result.gloss is None:
                return result
            gloss_only = gloss_record_from_reading(
                result.gloss,
                operator=target["operator"],
                client_id=target.get("client_id"),
                panel_id=target.get("panel_id"),
                panel=target.get("panel"),
                measurement_id=measurement_id,
            )
            return replace(result, gloss_record=gloss_only)
        record = record_from_reading(result.colour, gloss=result.gloss, **target)
    except ValueError as exc:
        if refused == "raise":
            raise
        return replace(result, note=f"not stored: {exc}")
    gloss_record = None
    if result.gloss is not None:
        gloss_record = gloss_record_from_reading(
            result.gloss, operator=target["operator"], client_id=gloss_client_id(record.client_id)
        )
    return replace(result, record=record, gloss_record=gloss_record)
