"""Repeat readings of a panel as one sample, and a standard as the mean of its repeat readings.

A panel is one physical object; its readings on one instrument are repeats. With panels averaged
(:func:`station.qc.jobs.job_summary` ``average_panels=True``):

* each sample panel is judged once, at the mean of its readings **without** the readings
  :func:`station.qc.repeats.summarise` flags as outliers (modified z-score > 3.5, Iglewicz & Hoaglin);
  the flagged readings are named (``left_out``) and ``keep_outliers=True`` averages them in;
* a measurement standard whose panel was read more than once on the standard's instrument is the
  mean of those readings, by the same rule.

Whether averaged or not, the standard's repeat readings (same panel, same instrument) are never
judged as samples of their own part; a reading of the standard panel on another instrument is (it is
the instrument-to-instrument check).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Generic, Protocol, TypeVar

from station.qc.readings import Reading
from station.qc.repeats import RepeatSummary, summarise


class _Row(Protocol):
    """What a stored reading carries (:class:`station.qc.jobs.MeasurementRow` is one; a dataclass)."""

    __dataclass_fields__: ClassVar[dict[str, Any]]

    @property
    def measurement_id(self) -> int: ...
    @property
    def panel_id(self) -> int | None: ...
    @property
    def instrument(self) -> str: ...
    @property
    def measured_at(self) -> dt.datetime: ...
    @property
    def reading(self) -> Reading: ...


MeasurementRow = TypeVar("MeasurementRow", bound=_Row)

__all__ = ["PanelMean", "panel_mean", "panel_means", "standard_repeats"]


@dataclass(frozen=True)
class PanelMean(Generic[MeasurementRow]):
    """One sample: a single reading, or a panel's mean (*row* carries it, timed at the newest reading).

    *measurement_ids* are every reading of the panel, *left_out* those not averaged (outliers), and
    *repeats* the repeat statistics (``None`` for a single reading).
    """

    row: MeasurementRow
    repeats: RepeatSummary | None = None
    measurement_ids: tuple[int, ...] = ()
    left_out: tuple[int, ...] = ()


def panel_mean(
    group: Sequence[MeasurementRow], keep_outliers: bool = False, label: str = "panel"
) -> PanelMean:
    """The mean of one panel's readings; flagged outliers left out unless *keep_outliers*."""
    if len(group) == 1:
        return PanelMean(group[0])
    rep = summarise([g.reading for g in group])
    left = (
        ()
        if keep_outliers
        else tuple(g.measurement_id for g, o in zip(group, rep.outliers, strict=True) if o)
    )
    newest = max(group, key=lambda g: (g.measured_at, g.measurement_id))
    base = rep.mean if keep_outliers else rep.mean_kept
    mean = dataclasses.replace(
        base,
        measured_at=newest.measured_at,
        sample=newest.reading.sample,
        instrument=", ".join(dict.fromkeys(g.instrument for g in group)),
        where=f"{label} {newest.panel_id}",
    )
    row = dataclasses.replace(newest, reading=mean, instrument=mean.instrument)
    return PanelMean(row, rep, tuple(g.measurement_id for g in group), left)


def panel_means(
    rows: Sequence[MeasurementRow], average_panels: bool, keep_outliers: bool = False
) -> list[PanelMean[MeasurementRow]]:
    """Each row alone, or with *average_panels* one :class:`PanelMean` per panel, oldest first."""
    if not average_panels:
        return [PanelMean(r) for r in rows]
    groups: dict[int | None, list[MeasurementRow]] = {}
    for r in rows:
        groups.setdefault(r.panel_id, []).append(r)
    out = [panel_mean(g, keep_outliers) for g in groups.values()]
    out.sort(key=lambda p: (p.row.measured_at, p.row.measurement_id))
    return out


def standard_repeats(rows: Sequence[MeasurementRow], reference_id: int | None) -> list[MeasurementRow]:
    """The reference reading and its repeats among *rows*: same panel, same instrument (empty if absent)."""
    ref = next((r for r in rows if r.measurement_id == reference_id), None)
    if ref is None:
        return []
    if ref.panel_id is None:
        return [ref]
    return [r for r in rows if r.panel_id == ref.panel_id and r.instrument == ref.instrument]
