"""Fixtures of the QC tests: the database fixtures of tests/db and a populated job."""

from __future__ import annotations

import datetime as dt
import uuid
from collections.abc import Sequence
from dataclasses import dataclass

from sqlalchemy.orm import Session

from db.models import Design, DesignVersion, Instrument, Measurement, Panel
from station.model import FaceFlopTravelGloss
from station.model.design_io import design_to_dict
from tests.db._fixtures import (  # noqa: F401
    _migrated_pg,
    _migrated_sqlite,
    database_url,
    empty_database_url,
    pg_server,
    pg_url,
)

T0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.UTC)
ANGLES = [15.0, 45.0, 110.0]
#: The standard panel of job J-100's fender, and the offsets (ΔL*, Δa*, Δb* at every angle) of its samples.
FENDER_STD = [[92.0, -1.0, 2.0], [60.0, -0.5, 1.0], [35.0, 0.0, 0.5]]
FENDER_OFFSETS = [
    (0.1, 0.0, 0.0),
    (-0.2, 0.1, 0.0),
    (0.3, 0.0, -0.1),
    (0.0, 0.2, 0.1),
    (0.5, -0.1, 0.0),
    (2.5, 0.0, 0.0),  # far outside the limit and the control limits
    (0.2, 0.0, 0.1),
]


@dataclass(frozen=True)
class Job:
    """Ids of the populated job."""

    standard_id: int
    sample_ids: tuple[int, ...]
    bumper_ids: tuple[int, ...]
    superseded_id: int
    correction_id: int
    design_id: int
    other_instrument_id: int


def _m(
    session: Session,
    inst: int,
    panel: int | None,
    at: dt.datetime,
    lab: Sequence[Sequence[float]],
    **kw: object,
) -> int:
    m = Measurement(
        client_id=uuid.uuid4(),
        instrument_id=inst,
        panel_id=panel,
        operator="ana",
        measured_at=at,
        geometries_deg=list(ANGLES),
        lab=[list(r) for r in lab],
        payload_sha256="0" * 64,
        **kw,
    )
    session.add(m)
    session.flush()
    return m.id


def populate(session: Session) -> Job:
    """Job J-100: a fender standard and 7 samples a day apart (one far off), a bumper with a correction.

    The bumper's second sample is measured on a second instrument (serial 700200); its first sample was
    superseded by a correction, which alone counts. A design (solid grey L* 50) is stored for design
    standards. Another job, J-200, has one panel.
    """
    a = Instrument(serial="600123", model="MA6", kind="spectrophotometer")
    b = Instrument(serial="700200", model="MA3", kind="spectrophotometer")
    session.add_all([a, b])
    session.flush()
    std_panel = Panel(job="J-100", part="fender", substrate="steel")
    session.add(std_panel)
    session.flush()
    std_id = _m(session, a.id, std_panel.id, T0, FENDER_STD)
    samples = []
    for i, off in enumerate(FENDER_OFFSETS):
        p = Panel(job="J-100", part="fender")
        session.add(p)
        session.flush()
        lab = [[r[0] + off[0], r[1] + off[1], r[2] + off[2]] for r in FENDER_STD]
        samples.append(_m(session, a.id, p.id, T0 + dt.timedelta(days=i + 1), lab))
    bp = Panel(job="J-100", part="bumper")
    session.add(bp)
    session.flush()
    grey = [[50.0, 0.0, 0.0]] * 3
    old = _m(session, a.id, bp.id, T0 + dt.timedelta(hours=3), [[50.4, 0.0, 0.0]] * 3)
    fix = _m(
        session,
        a.id,
        bp.id,
        T0 + dt.timedelta(hours=3),
        [[50.3, 0.0, 0.0]] * 3,
        supersedes_id=old,
        correction_reason="white tile was dirty",
    )
    second = _m(session, b.id, bp.id, T0 + dt.timedelta(days=2), [[50.0, 0.6, 0.0]] * 3)
    other = Panel(job="J-200", part="door")
    session.add(other)
    session.flush()
    _m(session, a.id, other.id, T0, grey)
    d = Design(name="grey 50")
    session.add(d)
    session.flush()
    body = design_to_dict(FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None, name="grey 50"))
    session.add(DesignVersion(design_id=d.id, version=1, body=body))
    session.flush()
    return Job(std_id, tuple(samples), (fix, second), old, fix, d.id, b.id)
