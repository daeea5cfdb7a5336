"""Standards, measurement search and job summaries on SQLite and PostgreSQL."""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Iterator

import pytest
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from db.engine import make_engine, make_sessionmaker
from db.models import Standard
from station.qc.errors import QcInputError, StandardMissingError
from station.qc.jobs import (
    get_standard,
    job_summary,
    list_jobs,
    require_standard,
    search_measurements,
    set_standard,
)
from station.qc.tolerance import ToleranceSet
from tests.qc.conftest import FENDER_OFFSETS, T0, Job, populate


@pytest.fixture
def session(database_url: str) -> Iterator[Session]:
    engine = make_engine(database_url)
    with make_sessionmaker(engine)() as s:
        yield s
    engine.dispose()


@pytest.fixture
def job(session: Session) -> Job:
    j = populate(session)
    session.commit()
    return j


def test_search_by_job_part_instrument_and_time(session: Session, job: Job) -> None:
    fender = search_measurements(session, job="J-100", part="fender")
    assert [r.measurement_id for r in fender] == [job.standard_id, *job.sample_ids]  # oldest first
    bumper = search_measurements(session, job="J-100", part="bumper")
    assert [r.measurement_id for r in bumper] == list(job.bumper_ids)  # the superseded one left out
    assert job.superseded_id not in {r.measurement_id for r in search_measurements(session)}
    by_b = search_measurements(session, instrument="700200")
    assert [r.measurement_id for r in by_b] == [job.bumper_ids[1]]
    assert search_measurements(session, instrument="MA3") == by_b
    window = search_measurements(
        session, job="J-100", part="fender", since=T0 + dt.timedelta(days=2), until=T0 + dt.timedelta(days=4)
    )
    assert [r.measurement_id for r in window] == list(job.sample_ids[1:3])  # since inclusive, until exclusive
    assert search_measurements(session, job="J-999") == []
    page = search_measurements(session, job="J-100", part="fender", limit=2, offset=1)
    assert [r.measurement_id for r in page] == list(job.sample_ids[:2])


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"part": "wing"}, "part"),
        ({"since": dt.datetime(2026, 1, 1)}, "since"),
        ({"since": T0, "until": T0}, "until"),
        ({"limit": 0}, "limit"),
        ({"offset": -1}, "offset"),
        ({"job": ""}, "job"),
    ],
)
def test_search_refuses_bad_filters(kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(QcInputError) as err:  # refused before any query: an unbound session suffices
        search_measurements(Session(), **kwargs)  # type: ignore[arg-type]
    assert err.value.field == field


def test_list_jobs(session: Session, job: Job) -> None:
    jobs = {j.job: j for j in list_jobs(session)}
    assert set(jobs) == {"J-100", "J-200"}
    j = jobs["J-100"]
    # 1 standard + 7 fender panels + 1 bumper panel; 8 fender + 3 bumper rows (the superseded counted)
    assert j.parts == ("bumper", "fender") and j.panels == 9 and j.measurements == 11
    assert j.first_measured == T0 and j.last_measured == T0 + dt.timedelta(days=len(FENDER_OFFSETS))
    assert [x.job for x in list_jobs(session, contains="j-2")] == ["J-200"]


def test_standards_set_replace_and_refuse(session: Session, job: Job) -> None:
    std = set_standard(session, "J-100", "fender", measurement_id=job.standard_id)
    session.commit()
    assert get_standard(session, "J-100", "fender") is not None and std.design_id is None
    with pytest.raises(QcInputError, match="replace") as err:
        set_standard(session, "J-100", "fender", design_id=job.design_id)
    assert err.value.field == "replace"
    again = set_standard(session, "J-100", "fender", design_id=job.design_id, replace=True)
    session.commit()
    assert again.id == std.id and again.design_id == job.design_id and again.measurement_id is None
    for kwargs, field in (
        ({}, "standard"),
        ({"measurement_id": 1, "design_id": 1}, "standard"),
        ({"measurement_id": 99_999}, "measurement_id"),
        ({"design_id": 99_999}, "design_id"),
        ({"measurement_id": job.superseded_id}, "measurement_id"),
    ):
        with pytest.raises(QcInputError) as e:
            set_standard(session, "J-100", "bumper", **kwargs)  # type: ignore[arg-type]
        assert e.value.field == field
    session.rollback()
    assert get_standard(session, "J-100", "bumper") is None  # nothing written by the refusals
    with pytest.raises(StandardMissingError):
        require_standard(session, "J-100", "bumper")


def test_database_refuses_a_standard_with_both_or_neither(session: Session, job: Job) -> None:
    for m, d in ((None, None), (job.standard_id, job.design_id)):
        session.add(Standard(job="J-1", part="door", measurement_id=m, design_id=d))
        with pytest.raises(IntegrityError):
            session.flush()
        session.rollback()
    session.add(Standard(job="J-1", part="door", measurement_id=job.standard_id))
    session.add(Standard(job="J-1", part="door", design_id=job.design_id))
    with pytest.raises(IntegrityError):  # one standard per job and part
        session.flush()
    session.rollback()
    assert session.scalars(select(Standard)).all() == []


def test_job_summary_verdicts_by_hand(session: Session, job: Job) -> None:
    set_standard(session, "J-100", "fender", measurement_id=job.standard_id)
    set_standard(session, "J-100", "bumper", design_id=job.design_id)
    session.commit()
    tol = ToleranceSet.uniform([15.0, 45.0, 110.0], de=1.0, formula="cie76")
    s = job_summary(session, "J-100", tol)
    fender = next(p for p in s.parts if p.part == "fender")
    # the same ΔLab at every angle, so ΔE*ab = |offset| at each; limit 1, warn over 0.8
    expected = [
        "fail" if math.hypot(*o) > 1 else "warn" if math.hypot(*o) > 0.8 else "pass" for o in FENDER_OFFSETS
    ]
    assert [x.verdict.verdict for x in fender.samples] == expected == ["pass"] * 5 + ["fail", "pass"]
    assert [x.verdict.max_de for x in fender.samples] == pytest.approx(
        [math.hypot(*o) for o in FENDER_OFFSETS]
    )
    assert job.standard_id not in {x.row.measurement_id for x in fender.samples}
    bumper = next(p for p in s.parts if p.part == "bumper")
    # design standard: grey L* 50 at every angle; the correction (50.3) and the MA3 reading (a* 0.6)
    assert [x.verdict.max_de for x in bumper.samples] == pytest.approx([0.3, 0.6])
    assert bumper.standard is not None and bumper.standard.curve is not None
    assert bumper.standard.curve.lab[0] == pytest.approx((50.0, 0.0, 0.0))
    assert s.counts() == {"pass": 8, "warn": 0, "fail": 1}
    only = job_summary(session, "J-100", tol, parts=["bumper"])
    assert [p.part for p in only.parts] == ["bumper"]
    with pytest.raises(QcInputError, match="job"):
        job_summary(session, "J-404")


def test_part_without_standard_is_listed_unjudged(session: Session, job: Job) -> None:
    s = job_summary(session, "J-100")
    assert all(p.standard is None and not p.samples for p in s.parts)
    fender = next(p for p in s.parts if p.part == "fender")
    assert len(fender.unjudged) == 1 + len(FENDER_OFFSETS) and fender.note == "no standard set"
    assert s.formula == "din6175"


def test_repeats_of_a_panel_are_averaged_when_asked(session: Session, job: Job) -> None:
    set_standard(session, "J-100", "bumper", design_id=job.design_id)
    session.commit()
    rows = search_measurements(session, job="J-100", part="bumper")
    panel = rows[0].panel_id
    assert panel is not None and [
        r.measurement_id for r in search_measurements(session, panel_id=panel)
    ] == list(job.bumper_ids)
    s = job_summary(session, "J-100", formula="cie76", parts=["bumper"], average_panels=True)
    (sample,) = s.parts[0].samples
    # mean of (50.3, 0, 0) and (50, 0.6, 0) is (50.15, 0.3, 0): ΔE*ab to grey 50 = √(0.15² + 0.3²)
    assert sample.verdict.max_de == pytest.approx(math.hypot(0.15, 0.3))
    assert sample.measurement_ids == job.bumper_ids and sample.repeats is not None and sample.repeats.n == 2
    assert sample.row.measured_at == T0 + dt.timedelta(days=2)  # the newest reading's time
    assert sample.row.instrument == "MA6 600123, MA3 700200"
    with pytest.raises(QcInputError, match="panel_id"):
        search_measurements(session, panel_id=0)


def test_a_corrected_reference_stands_through_its_correction(session: Session, job: Job) -> None:
    # the superseded bumper reading (50.4) was corrected to 50.3: a standard set on it before the
    # correction judges against 50.3, and the correction is not judged as a sample of its own part
    std = Standard(job="J-100", part="bumper", measurement_id=job.superseded_id)
    session.add(std)
    session.commit()
    s = job_summary(session, "J-100", formula="cie76", parts=["bumper"])
    part = s.parts[0]
    assert part.standard is not None and part.standard.reading.lab[0] == pytest.approx((50.3, 0.0, 0.0))
    assert [x.row.measurement_id for x in part.samples] == [job.bumper_ids[1]]
    # the MA3 reading (50, 0.6, 0) against 50.3: ΔE*ab = √(0.3² + 0.6²)
    assert part.samples[0].verdict.max_de == pytest.approx(math.hypot(0.3, 0.6))
