"""Colour QC through the service: gloss readings and the measurement view that pairs them with colour.

The pairing rule is ``station.ingest.pair_gloss`` (linked reading first, else the same panel's
nearest in time within ``station.ingest.PAIR_WINDOW``); it runs over every colour measurement of the
panels on the page, so a reading pairs the same way whatever page it is seen on.
"""

from __future__ import annotations

from collections.abc import Sequence

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import GlossReading, Measurement, Panel, User
from station.api.errors import NotFoundError
from station.api.schemas.measurements import MeasurementPublic, MeasurementQuery
from station.api.schemas.qc import CheckRequest, CheckResult, GlossPublic, LabSource, QcMeasurement
from station.api.services import measurements as measurement_service
from station.errors import InputError
from station.ingest import GlossRecord, GlossRow, pair_gloss, store_gloss
from station.model.difference import validate_method
from station.model.domain import QC_DE_LIMIT, QC_FORMULA
from station.model.errors import ModelInputError
from station.model.tolerance import FORMULAS, ToleranceSet, judge


def get_gloss(*, session: Session, gloss_id: int) -> GlossPublic:
    """Gloss reading *gloss_id* or :class:`NotFoundError`."""
    row = session.get(GlossReading, gloss_id)
    if row is None:
        raise NotFoundError(f"gloss reading {gloss_id} not found")
    return GlossPublic.model_validate(row)


def ingest_gloss(*, session: Session, actor: User, record: GlossRecord) -> tuple[GlossPublic, bool]:
    """Store *record* once with its audit row; ``(reading, created)``."""
    result = store_gloss(session, record, created_by_id=actor.id)
    stored = get_gloss(session=session, gloss_id=result.measurement_id)
    session.commit()
    return stored, result.created


def list_gloss(
    *, session: Session, job: str | None, part: str | None, panel_id: int | None, limit: int, offset: int
) -> tuple[list[GlossPublic], int]:
    """Gloss readings of a job, part and/or panel, newest first."""
    query = select(GlossReading).outerjoin(Panel, Panel.id == GlossReading.panel_id)
    if job:
        query = query.where(Panel.job == job)
    if part:
        query = query.where(Panel.part == part)
    if panel_id is not None:
        query = query.where(GlossReading.panel_id == panel_id)
    total = session.scalar(
        select(func.count()).select_from(query.with_only_columns(GlossReading.id).subquery())
    )
    rows = session.scalars(
        query.order_by(GlossReading.measured_at.desc(), GlossReading.id.desc()).limit(limit).offset(offset)
    ).all()
    return [GlossPublic.model_validate(r) for r in rows], total or 0


def paired(*, session: Session, measurements: Sequence[MeasurementPublic]) -> list[QcMeasurement]:
    """*measurements* with their panel's job and part and their paired gloss reading (or ``None``)."""
    panel_ids = {m.panel_id for m in measurements if m.panel_id is not None}
    ids = {m.id for m in measurements}
    colour_rows = session.execute(
        select(Measurement.id, Measurement.panel_id, Measurement.measured_at).where(
            Measurement.panel_id.in_(panel_ids) | Measurement.id.in_(ids)
        )
    ).all()
    gloss_rows = session.scalars(
        select(GlossReading).where(
            GlossReading.panel_id.in_(panel_ids) | GlossReading.measurement_id.in_(ids)
        )
    ).all()
    pairs = pair_gloss(
        [GlossRow(r.id, r.panel_id, r.measured_at) for r in colour_rows],
        [GlossRow(g.id, g.panel_id, g.measured_at, g.measurement_id) for g in gloss_rows],
    )
    gloss_by_id = {g.id: g for g in gloss_rows}
    panels = {p.id: p for p in session.scalars(select(Panel).where(Panel.id.in_(panel_ids))).all()}
    out: list[QcMeasurement] = []
    for m in measurements:
        g = gloss_by_id.get(pairs[m.id]) if m.id in pairs else None
        panel = panels.get(m.panel_id) if m.panel_id is not None else None
        out.append(
            QcMeasurement(
                **m.model_dump(),
                job=panel.job if panel else None,
                part=panel.part if panel else None,
                gloss=GlossPublic.model_validate(g) if g is not None else None,
            )
        )
    return out


def list_measurements(
    *, session: Session, q: MeasurementQuery, limit: int, offset: int
) -> tuple[list[QcMeasurement], int]:
    """Measurements matching *q* (job, part, panel, instrument, time), newest first, gloss paired."""
    rows, total = measurement_service.query(session=session, q=q, limit=limit, offset=offset)
    return paired(session=session, measurements=rows), total


def get_measurement(*, session: Session, measurement_id: int) -> QcMeasurement:
    """One measurement with its gloss reading, or :class:`NotFoundError`."""
    m = measurement_service.get_measurement(session=session, measurement_id=measurement_id)
    return paired(session=session, measurements=[m])[0]


def _lab_of(session: Session, source: LabSource, field: str) -> tuple[dict[float, list[float]], int | None]:
    """Lab by aspecular angle (degrees) of *source*; a stored measurement must exist (404)."""
    if source.measurement_id is not None:
        m = session.get(Measurement, source.measurement_id)
        if m is None:
            raise NotFoundError(f"{field}.measurement_id: measurement {source.measurement_id} not found")
        pairs = zip(m.geometries_deg, m.lab, strict=True)
        return {float(a): [float(v) for v in lab] for a, lab in pairs}, m.id
    angles, labs = source.geometries_deg or [], source.lab or []  # both given: the schema's rule
    return {float(a): list(lab) for a, lab in zip(angles, labs, strict=True)}, None


def tolerance_for(request: CheckRequest, angles: Sequence[float]) -> ToleranceSet:
    """The tolerance set of *request*: its own, or ``de_limit`` at every angle with ``formula``."""
    if request.tolerance is not None:
        return ToleranceSet.from_dict(request.tolerance)
    formula = QC_FORMULA
    if request.formula is not None:
        try:
            formula = validate_method(request.formula)
        except ModelInputError as exc:
            raise InputError("formula", " | ".join(FORMULAS), request.formula) from exc
        if formula not in FORMULAS and formula != "audi2000":
            raise InputError("formula", " | ".join(FORMULAS), request.formula)
    return ToleranceSet.uniform(
        angles,
        QC_DE_LIMIT if request.de_limit is None else request.de_limit,
        formula=formula,
        mean_limit=QC_DE_LIMIT if request.de_limit is None else request.de_limit,
    )


def check(*, session: Session, request: CheckRequest) -> CheckResult:
    """Verdict of the sample against the standard over their common geometries (``station.model.tolerance.judge``).

    A tolerance set given with the request must cover those geometries (422 naming ``angles``).
    """
    std, std_id = _lab_of(session, request.standard, "standard")
    smp, smp_id = _lab_of(session, request.sample, "sample")
    angles = sorted(set(std) & set(smp))
    if not angles:
        raise InputError(
            "sample.geometries_deg",
            "at least one aspecular angle the standard has ("
            + ", ".join(f"{a:g}" for a in sorted(std))
            + ")",
            sorted(smp),
        )
    verdict = judge(
        [std[a] for a in angles], [smp[a] for a in angles], angles, tolerance_for(request, angles)
    )
    return CheckResult.model_validate(
        verdict.to_dict() | {"standard_measurement_id": std_id, "sample_measurement_id": smp_id}
    )
