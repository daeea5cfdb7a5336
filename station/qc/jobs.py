"""Jobs, parts, standards and measurement search in the measurement database (SQLAlchemy 2 style).

A **job** is the ``job`` text its panels carry; its **parts** are the panels' ``part`` values
(:data:`db.models.PARTS`); a panel's measurements are the samples. A **standard**
(:class:`db.models.Standard`) per job and part is either a reference measurement or a design; a design
standard gives the Lab of its model at each sample's aspecular angles
(:meth:`station.model.FaceFlopTravelGloss.lab_at`, latest design version).

QC judges the 45° illumination block (``station.model.domain.ILLUMINATION_DEG``): the rows of another
block of a two-illumination instrument (an MA-T12's 15° block, stored as its own measurement on the same
panel) are left out of searches and summaries and refused as a standard. Corrected measurements count once: a measurement superseded by a correction is left out of searches
and summaries (the correction stands for it). Every query works on SQLite and PostgreSQL.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from sqlalchemy import and_, func, or_, select
from sqlalchemy.orm import Session, aliased

from db.models import PARTS, Design, DesignVersion, Instrument, Measurement, Panel, Standard
from station.model.design_io import design_from_dict
from station.model.domain import ANGLES_6, ILLUMINATION_DEG, QC_FORMULA
from station.model.errors import ModelInputError
from station.qc.check import check_pair, formula_name
from station.qc.errors import QcInputError, StandardMissingError
from station.qc.illuminant_rows import check_illuminants
from station.qc.illuminant_rows import illuminant_limits as booth_limits
from station.qc.panels import panel_mean, panel_means, standard_repeats
from station.qc.readings import Reading, reading_from_measurement
from station.qc.results import JobSummary, MeasurementRow, PartSummary, SampleResult, StandardInfo
from station.qc.texture import TextureTolerance, judge_texture
from station.qc.tolerance import ToleranceSet
from station.wire import iso_time, wire_form

__all__ = [
    "JobInfo",
    "JobSummary",
    "MeasurementRow",
    "PartSummary",
    "SampleResult",
    "StandardInfo",
    "get_standard",
    "job_summary",
    "list_jobs",
    "search_measurements",
    "set_standard",
    "standard_reading",
]

#: Step of a design standard's curve in the report, degrees.
CURVE_STEP_DEG = 1.0
#: Most rows one search returns (a page); callers page with *offset*.
SEARCH_LIMIT_MAX = 10_000
_TEXT_MAX = 64


def _text(value: str, name: str) -> str:
    if not isinstance(value, str) or not value.strip() or len(value) > _TEXT_MAX:
        raise QcInputError(name, f"a non-empty name of at most {_TEXT_MAX} characters", value)
    return value


def _part(value: str) -> str:
    if value not in PARTS:
        raise QcInputError("part", " | ".join(PARTS), value)
    return value


def _aware(value: dt.datetime | None, name: str) -> dt.datetime | None:
    if value is not None and (not isinstance(value, dt.datetime) or value.tzinfo is None):
        raise QcInputError(name, "a timezone-aware time", value)
    return value


def _instrument_name(inst: Instrument) -> str:
    return f"{inst.model} {inst.serial}"


def _search_query(
    job: str | None,
    part: str | None,
    instrument: str | None,
    since: dt.datetime | None,
    until: dt.datetime | None,
    panel_id: int | None = None,
) -> Any:
    newer = aliased(Measurement)
    q = (
        select(Measurement, Panel, Instrument)
        .join(Instrument, Instrument.id == Measurement.instrument_id)
        .outerjoin(Panel, Panel.id == Measurement.panel_id)
        .where(~select(newer.id).where(newer.supersedes_id == Measurement.id).exists())
        .where(Measurement.illumination_deg == ILLUMINATION_DEG)  # the block QC judges
    )
    if job is not None:
        q = q.where(Panel.job == _text(job, "job"))
    if part is not None:
        q = q.where(Panel.part == _part(part))
    if instrument is not None:
        name = _text(instrument, "instrument")
        q = q.where(or_(Instrument.serial == name, Instrument.model == name))
    if panel_id is not None:
        if isinstance(panel_id, bool) or not isinstance(panel_id, int) or panel_id < 1:
            raise QcInputError("panel_id", "a panel id >= 1", panel_id)
        q = q.where(Measurement.panel_id == panel_id)
    if since is not None:
        q = q.where(Measurement.measured_at >= since)
    if until is not None:
        q = q.where(Measurement.measured_at < until)
    return q


def search_measurements(
    session: Session,
    *,
    job: str | None = None,
    part: str | None = None,
    instrument: str | None = None,
    since: dt.datetime | None = None,
    until: dt.datetime | None = None,
    limit: int = 1000,
    offset: int = 0,
    panel_id: int | None = None,
) -> list[MeasurementRow]:
    """Measurements by job, part, panel, instrument (serial or model, exact) and time range, oldest first.

    *since* is inclusive, *until* exclusive (timezone-aware); superseded measurements and those of
    another illumination block than 45° are left out.
    *limit* 1 … :data:`SEARCH_LIMIT_MAX`, *offset* >= 0.
    """
    _aware(since, "since")
    _aware(until, "until")
    if since is not None and until is not None and until <= since:
        raise QcInputError("until", f"a time after since ({since.isoformat()})", until.isoformat())
    if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= SEARCH_LIMIT_MAX:
        raise QcInputError("limit", f"an integer, 1 <= limit <= {SEARCH_LIMIT_MAX}", limit)
    if isinstance(offset, bool) or not isinstance(offset, int) or offset < 0:
        raise QcInputError("offset", "an integer >= 0", offset)
    q = _search_query(job, part, instrument, since, until, panel_id)
    q = q.order_by(Measurement.measured_at, Measurement.id).limit(limit).offset(offset)
    out = []
    for m, panel, inst in session.execute(q).all():
        name = _instrument_name(inst)
        sample = f"panel {panel.id}" if panel is not None else f"measurement {m.id}"
        out.append(
            MeasurementRow(
                m.id,
                m.panel_id,
                None if panel is None else panel.job,
                None if panel is None else panel.part,
                name,
                m.operator,
                m.measured_at,
                reading_from_measurement(m, instrument=name, sample=sample),
            )
        )
    return out


@dataclass(frozen=True)
class JobInfo:
    """A job: its parts, how many panels and measurements it has, its first and last reading time."""

    job: str
    parts: tuple[str, ...]
    panels: int
    measurements: int
    first_measured: dt.datetime | None
    last_measured: dt.datetime | None

    def to_dict(self) -> dict[str, Any]:
        return wire_form(self, convert={"first_measured": iso_time, "last_measured": iso_time})


def list_jobs(session: Session, contains: str | None = None) -> list[JobInfo]:
    """Every job (optionally whose name contains *contains*, case-insensitive), by name."""
    q = (
        select(
            Panel.job,
            func.count(func.distinct(Panel.id)),
            func.count(Measurement.id),
            func.min(Measurement.measured_at),
            func.max(Measurement.measured_at),
        )
        .outerjoin(Measurement, Measurement.panel_id == Panel.id)
        .group_by(Panel.job)
        .order_by(Panel.job)
    )
    if contains:
        q = q.where(func.lower(Panel.job).contains(contains.lower(), autoescape=True))
    parts: dict[str, set[str]] = {}
    for job, part in session.execute(select(Panel.job, Panel.part).distinct()).all():
        parts.setdefault(job, set()).add(part)
    out = []
    for job, n_panels, n_meas, first, last in session.execute(q).all():
        # min/max of a typed column lose the UTC type decorator on some backends: restore the zone
        out.append(
            JobInfo(job, tuple(sorted(parts.get(job, ()))), n_panels, n_meas, _as_utc(first), _as_utc(last))
        )
    return out


def _as_utc(value: Any) -> dt.datetime | None:
    if value is None:
        return None
    if isinstance(value, str):
        value = dt.datetime.fromisoformat(value)
    if value.tzinfo is None:
        return value.replace(tzinfo=dt.UTC)
    return value.astimezone(dt.UTC)


def get_standard(session: Session, job: str, part: str) -> Standard | None:
    """The standard of *job* and *part*, or ``None``."""
    return session.scalars(
        select(Standard).where(and_(Standard.job == _text(job, "job"), Standard.part == _part(part)))
    ).first()


def set_standard(
    session: Session,
    job: str,
    part: str,
    *,
    measurement_id: int | None = None,
    design_id: int | None = None,
    notes: str = "",
    created_by_id: int | None = None,
    replace: bool = False,
) -> Standard:
    """Make a measurement or a design the standard of *job* and *part* (exactly one of the two ids).

    The measurement must exist (and not be superseded by a correction); the design must exist. An
    existing standard is only replaced with ``replace=True`` (:class:`QcInputError` naming ``replace``
    otherwise). The caller commits; nothing is written when this raises.
    """
    job, part = _text(job, "job"), _part(part)
    if (measurement_id is None) == (design_id is None):
        raise QcInputError(
            "standard", "either a measurement id or a design id", "both" if measurement_id else "neither"
        )
    if measurement_id is not None:
        m = session.get(Measurement, measurement_id)
        if m is None:
            raise QcInputError("measurement_id", "the id of a stored measurement", measurement_id)
        newer = session.scalars(select(Measurement.id).where(Measurement.supersedes_id == m.id)).first()
        if newer is not None:
            raise QcInputError(
                "measurement_id", f"a current measurement (it is superseded by {newer})", measurement_id
            )
        if m.illumination_deg != ILLUMINATION_DEG:
            raise QcInputError(
                "measurement_id",
                f"a measurement of the {ILLUMINATION_DEG:g}° illumination block "
                f"(measurement {m.id} is the {m.illumination_deg:g}° block)",
                measurement_id,
            )
    elif session.get(Design, design_id) is None:
        raise QcInputError("design_id", "the id of a stored design", design_id)
    existing = get_standard(session, job, part)
    if existing is not None:
        if not replace:
            raise QcInputError(
                "replace", f"replace=True to replace the standard of {job}/{part} (id {existing.id})", False
            )
        existing.measurement_id = measurement_id
        existing.design_id = design_id
        existing.notes = notes
        existing.created_by_id = created_by_id
        existing.created_at = dt.datetime.now(dt.UTC)
        session.flush()
        return existing
    std = Standard(
        job=job,
        part=part,
        measurement_id=measurement_id,
        design_id=design_id,
        notes=notes,
        created_by_id=created_by_id,
    )
    session.add(std)
    session.flush()
    return std


def current_measurement(session: Session, measurement_id: int) -> Measurement | None:
    """The measurement *measurement_id* stands for now: itself, or the last correction in its chain."""
    m = session.get(Measurement, measurement_id)
    seen = set()
    while m is not None and m.id not in seen:
        seen.add(m.id)
        newer = session.scalars(select(Measurement).where(Measurement.supersedes_id == m.id)).first()
        if newer is None:
            return m
        m = newer
    return m


def standard_reading(session: Session, standard: Standard, angles: Sequence[float] | None = None) -> Reading:
    """The standard as a reading: the reference measurement, or the design's Lab at *angles*.

    A reference measurement corrected since it was made the standard stands through its newest
    correction. A design standard needs *angles* (the sample's aspecular angles, degrees).
    """
    where = f"standard {standard.job}/{standard.part}"
    if standard.measurement_id is not None:
        m = current_measurement(session, standard.measurement_id)
        if m is None:  # the foreign key prevents it; kept for a clear message
            raise QcInputError(f"{where}.measurement_id", "a stored measurement", standard.measurement_id)
        inst = session.get(Instrument, m.instrument_id)
        name = "" if inst is None else _instrument_name(inst)
        return reading_from_measurement(m, instrument=name, sample=f"standard (measurement {m.id})")
    version = session.scalars(
        select(DesignVersion)
        .where(DesignVersion.design_id == standard.design_id)
        .order_by(DesignVersion.version.desc())
    ).first()
    if version is None:
        raise QcInputError(f"{where}.design_id", "a design with a saved version", standard.design_id)
    if not angles:
        raise QcInputError("angles", "the aspecular angles to evaluate a design standard at", angles)
    try:
        design = design_from_dict(version.body)
    except ModelInputError as exc:
        raise QcInputError(f"{where}.design", "a valid cacad.design/1 body", str(exc)) from exc
    lab = design.lab_at(list(angles))
    return Reading(
        tuple(float(a) for a in angles),
        tuple((float(r[0]), float(r[1]), float(r[2])) for r in lab),
        sample=f"standard (design {standard.design_id} v{version.version})",
        where=where,
    )


def job_summary(
    session: Session,
    job: str,
    tolerance: ToleranceSet | None = None,
    formula: str | None = None,
    parts: Sequence[str] | None = None,
    average_panels: bool = False,
    illuminant_limits: Mapping[str, float] | None = None,
    keep_outliers: bool = False,
    texture_limits: TextureTolerance | None = None,
) -> JobSummary:
    """Every part of *job* with its standard and each sample's verdict (:func:`check_pair`).

    The reference measurement of a standard and its repeats (:func:`station.qc.panels.standard_repeats`)
    are not judged as samples of their own part. A part without a standard is listed with its
    measurements unjudged. A sample that cannot be judged (a geometry of the standard or tolerance
    missing) is listed unjudged with the reason in the part's note. With *average_panels* the repeat
    readings of each panel, and of the standard, are averaged without the flagged outliers (with them
    when *keep_outliers*; :mod:`station.qc.panels`) and the panel is judged once, at the time of its
    newest reading. With *illuminant_limits* (``{illuminant: metamerism-index limit}``) each sample also
    gets its illuminant rows (:func:`station.qc.illuminant_rows.check_illuminants`) and its verdict is
    the worse of the two; a sample or standard without spectra is then listed unjudged with the reason.
    With *texture_limits* each sample's vendor texture values are judged against the standard's
    (:mod:`station.qc.texture`, ΔS and ΔG); the overall verdict is the worst, and a sample whose values
    come from another vendor than the standard's is listed unjudged with the reason.
    :class:`QcInputError` when the job has no panels.
    """
    limits = None if illuminant_limits is None else booth_limits(illuminant_limits)
    job = _text(job, "job")
    rows = search_measurements(session, job=job, limit=SEARCH_LIMIT_MAX)
    known = session.scalars(select(Panel.part).where(Panel.job == job).distinct()).all()
    if not known:
        raise QcInputError("job", "a job with stored panels (station qc jobs lists them)", job)
    wanted = sorted(set(known)) if parts is None else [_part(p) for p in parts]
    if formula is not None:
        name = formula_name(formula)
    else:
        name = tolerance.formula if tolerance is not None else formula_name(QC_FORMULA)
    judging = _Judging(tolerance, formula, limits, average_panels, keep_outliers, texture_limits)
    out = [_part_summary(session, job, part, [r for r in rows if r.part == part], judging) for part in wanted]
    return JobSummary(
        job,
        name,
        tolerance,
        tuple(out),
        dt.datetime.now(dt.UTC),
        limits,
        texture_limits,
        average_panels,
        average_panels and keep_outliers,
    )


@dataclass(frozen=True)
class _Judging:
    tolerance: ToleranceSet | None
    formula: str | None
    limits: dict[str, float] | None
    average_panels: bool
    keep_outliers: bool
    texture: TextureTolerance | None


def _part_summary(
    session: Session, job: str, part: str, part_rows: list[MeasurementRow], how: _Judging
) -> PartSummary:
    """One part of :func:`job_summary`: its standard (averaged when asked) and its samples' verdicts."""
    std = get_standard(session, job, part)
    if std is None:
        return PartSummary(part, None, (), tuple(part_rows), "no standard set")
    samples, unjudged, notes = [], [], []
    ref_id = None
    if std.measurement_id is not None:
        current = current_measurement(session, std.measurement_id)
        ref_id = None if current is None else current.id
    std_rows = standard_repeats(part_rows, ref_id)
    many = how.average_panels and len(std_rows) > 1
    averaged = panel_mean(std_rows, how.keep_outliers, "standard panel") if many else None
    skip = {r.measurement_id for r in std_rows} | {ref_id}
    candidates = [r for r in part_rows if r.measurement_id not in skip]
    info: StandardInfo | None = None
    for pm in panel_means(candidates, how.average_panels, how.keep_outliers):
        r = pm.row
        if averaged is not None:
            ref = dataclasses.replace(averaged.row.reading, sample="standard (mean of its repeats)")
        else:
            ref = standard_reading(session, std, r.reading.aspecular_deg)
        if info is None:
            info = StandardInfo(
                job, part, std.measurement_id, std.design_id, std.created_at, ref, None, averaged
            )
        try:
            verdict = check_pair(ref, r.reading, how.tolerance, how.formula)
            booth = (
                None if how.limits is None else check_illuminants(ref, r.reading, how.limits, verdict.formula)
            )
            tex = None if how.texture is None else judge_texture(ref.texture, r.reading.texture, how.texture)
            samples.append(SampleResult(r, verdict, pm.repeats, pm.measurement_ids, booth, pm.left_out, tex))
        except (QcInputError, ModelInputError) as exc:
            unjudged.append(r)
            notes.append(f"measurement {r.measurement_id}: {exc}")
    if info is None:
        angles = part_rows[0].reading.aspecular_deg if part_rows else tuple(ANGLES_6)  # the first sample's
        ref = standard_reading(session, std, angles)
        info = StandardInfo(job, part, std.measurement_id, std.design_id, std.created_at, ref, None, averaged)
    if std.design_id is not None:
        info = dataclasses.replace(info, curve=_curve(session, std, samples))
    return PartSummary(part, info, tuple(samples), tuple(unjudged), "; ".join(notes))


def _curve(session: Session, std: Standard, samples: Sequence[SampleResult]) -> Reading:
    """A design standard every CURVE_STEP_DEG over its samples' angle range (the 6-angle set's without)."""
    angles = [a for smp in samples for a in smp.row.reading.aspecular_deg] or list(ANGLES_6)
    lo, hi = min(angles), max(angles)
    grid = np.arange(lo, hi + CURVE_STEP_DEG / 2, CURVE_STEP_DEG)
    return standard_reading(session, std, [float(a) for a in grid])


def require_standard(session: Session, job: str, part: str) -> Standard:
    """The standard of *job*/*part*, or :class:`StandardMissingError` naming them."""
    std = get_standard(session, job, part)
    if std is None:
        raise StandardMissingError("standard", f"a standard for {job}/{part} (station qc standard set)", None)
    return std
