"""Illuminant rows of QC verdicts (station.qc.illuminant_rows): the metamerism index from D65 per geometry judged
against the user's limit per test illuminant, in the check, the job summary and the PDF report.

The index is checked against colour-science's own integration of the same spectra (ASTM E308,
CIELAB relative to each illuminant's white, CIEDE2000, additive correction from D65); the pair is
constructed metameric: equal under D65 (a metameric black added), different under A.
"""

from __future__ import annotations

import datetime as dt
import json
import uuid
import warnings
from collections.abc import Iterator
from pathlib import Path

import colour
import numpy as np
import pytest
from numpy.typing import NDArray
from sqlalchemy.orm import Session

from db.engine import make_engine, make_sessionmaker
from db.models import Instrument, Measurement, Panel
from station.model.spectra import WAVELENGTHS, reflectance_to_lab, weighting_factors
from station.qc.check import check_pair
from station.qc.errors import QcInputError
from station.qc.illuminant_rows import PairVerdict, check_illuminants, parse_illuminant_limits
from station.qc.jobs import job_summary, set_standard
from station.qc.readings import reading_from_dict
from tests.user_cli import run_station

WL = [float(w) for w in WAVELENGTHS]
GEOMETRIES = ["45as15", "45as45", "45as110"]
ANGLES = [15.0, 45.0, 110.0]
_CS = {"D65": "D65", "A": "A", "F11": "FL11"}


def _lab_cs(rows: NDArray[np.float64], illuminant: str) -> NDArray[np.float64]:
    """Lab (10°, white Y = 1) of reflectance rows by colour-science's ASTM E308 integration alone."""
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"]
    ill = colour.SDS_ILLUMINANTS[_CS[illuminant]]
    shape = colour.SpectralShape(400, 700, 10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ones = colour.SpectralDistribution(dict(zip(WL, np.ones(31), strict=True)))
        white = colour.sd_to_XYZ(ones, cmfs, ill, method="ASTM E308", shape=shape)
        out = [
            colour.XYZ_to_Lab(
                colour.sd_to_XYZ(
                    colour.SpectralDistribution(dict(zip(WL, r, strict=True))),
                    cmfs,
                    ill,
                    method="ASTM E308",
                    shape=shape,
                )
                / white[1],
                colour.XYZ_to_xy(white),
            )
            for r in rows
        ]
    return np.asarray(out)


def _pair() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A standard (three geometries) and a sample equal to it under D65 but not under A."""
    base = 0.3 + 0.12 * np.cos((WAVELENGTHS - 480.0) / 70.0)
    std = np.stack([1.3 * base, base, 0.6 * base])
    w = weighting_factors("D65")
    q, _ = np.linalg.qr(w)
    ripple = np.sin(WAVELENGTHS / 12.0)
    black = ripple - q @ (q.T @ ripple)
    black /= np.max(np.abs(black))
    return std, std + 0.9 * std.min(axis=1, keepdims=True) * black


def _mi_cs(std: NDArray[np.float64], smp: NDArray[np.float64], ill: str) -> NDArray[np.float64]:
    corr = _lab_cs(smp, "D65") - _lab_cs(std, "D65")
    return np.asarray(colour.delta_E(_lab_cs(std, ill), _lab_cs(smp, ill) - corr, method="CIE 2000"))


def _reading_dict(spectra: NDArray[np.float64]) -> dict[str, object]:
    return {"geometries": GEOMETRIES, "spectra": spectra.tolist(), "wavelengths_nm": WL}


def test_rows_pass_at_or_below_the_limit_and_fail_above_it() -> None:
    std, smp = _pair()
    np.testing.assert_allclose(_lab_cs(std, "D65"), _lab_cs(smp, "D65"), atol=1e-9)
    mi_a = _mi_cs(std, smp, "A")
    assert mi_a.min() > 0.5
    a, b = reading_from_dict(_reading_dict(std)), reading_from_dict(_reading_dict(smp))
    d65 = check_pair(a, b, formula="cie2000")
    assert d65.verdict == "pass" and d65.max_de < 1e-6
    loose = check_illuminants(a, b, {"A": float(mi_a.max()) + 0.01}, "cie2000")
    np.testing.assert_allclose([r.index for r in loose.rows], mi_a, atol=1e-6)
    assert [r.geometry for r in loose.rows] == GEOMETRIES
    assert loose.verdict == "pass" and PairVerdict(d65, loose).verdict == "pass"
    tight = check_illuminants(a, b, {"A": float(mi_a.min()) - 0.01, "F11": 100.0}, "cie2000")
    a_rows = [r for r in tight.rows if r.illuminant == "A"]
    assert [r.verdict for r in a_rows] == ["fail"] * 3
    assert a_rows[0].text == f"A 45as15: MI {mi_a[0]:.2f} > {mi_a.min() - 0.01:.2f} fail"
    f11 = [r.index for r in tight.rows if r.illuminant == "F11"]
    np.testing.assert_allclose(f11, _mi_cs(std, smp, "F11"), atol=1e-6)
    pair = PairVerdict(d65, tight).to_dict()
    assert pair["verdict"] == "fail" and pair["d65_verdict"] == "pass"
    assert "A 45as15: MI" in pair["reason"]
    # a limit between the smallest and largest index: the rows split at it
    mid = float(np.median(mi_a))
    split = check_illuminants(a, b, {"A": mid}, "cie2000")
    assert [r.verdict for r in split.rows] == ["pass" if v <= mid else "fail" for v in mi_a]


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("A=x", "illuminant_limits"),
        ("Q9=1", "illuminant_limits.Q9"),
        ("D65=1", "illuminant_limits.D65"),
        ("A=0", "illuminant_limits.A"),
        ("A=1,A=2", "illuminant_limits.A"),
        ("", "illuminant_limits"),
    ],
)
def test_bad_limits_are_refused_naming_the_field(text: str, field: str) -> None:
    with pytest.raises(QcInputError) as err:
        parse_illuminant_limits(text)
    assert err.value.field == field


def test_rows_need_spectra() -> None:
    lab_only = reading_from_dict({"geometries": GEOMETRIES, "lab": [[50.0, 0.0, 0.0]] * 3})
    with pytest.raises(QcInputError, match="spectra"):
        check_illuminants(lab_only, lab_only, {"A": 1.0}, "cie2000")


def test_cli_check_adds_illuminant_rows(tmp_path: Path) -> None:
    std, smp = _pair()
    (tmp_path / "std.json").write_text(json.dumps(_reading_dict(std)))
    (tmp_path / "smp.json").write_text(json.dumps(_reading_dict(smp)))
    mi_a = _mi_cs(std, smp, "A")
    args = ("qc", "check", "--standard", "std.json", "--sample", "smp.json", "--formula", "cie2000")
    limit = float(mi_a.min()) - 0.01
    r = run_station(tmp_path, *args, "--illuminant-limits", f"A={limit},F11=50", "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["verdict"] == "fail" and out["d65_verdict"] == "pass"
    rows = out["illuminants"]["rows"]
    assert [(x["illuminant"], x["geometry"]) for x in rows[:3]] == [("A", g) for g in GEOMETRIES]
    np.testing.assert_allclose([x["metamerism_index"] for x in rows[:3]], mi_a, atol=1e-6)
    assert all(x["verdict"] == "fail" for x in rows[:3]) and all(x["verdict"] == "pass" for x in rows[3:])
    text = run_station(tmp_path, *args, "--illuminant-limits", f"A={float(mi_a.max()) + 0.01}")
    assert text.returncode == 0, text.stderr
    assert f"A 45as15: MI {mi_a[0]:.2f} <= " in text.stdout and "verdict: pass" in text.stdout
    bad = run_station(tmp_path, *args, "--illuminant-limits", "XYZ=1")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "illuminant_limits.XYZ" in bad.stderr


@pytest.fixture
def session(database_url: str) -> Iterator[Session]:
    engine = make_engine(database_url)
    with make_sessionmaker(engine)() as s:
        yield s
    engine.dispose()


def _stored(session: Session, inst: int, panel: int, spectra: NDArray[np.float64], day: int) -> int:
    m = Measurement(
        client_id=uuid.uuid4(),
        instrument_id=inst,
        panel_id=panel,
        operator="ana",
        measured_at=dt.datetime(2026, 12, 1, 8, tzinfo=dt.UTC) + dt.timedelta(days=day),
        geometries_deg=ANGLES,
        lab=reflectance_to_lab(spectra).tolist(),
        wavelengths_nm=WL,
        spectra=spectra.tolist(),
        payload_sha256="0" * 64,
    )
    session.add(m)
    session.flush()
    return m.id


def _job(session: Session) -> tuple[int, int, int]:
    """Job J-300's door: a standard, the metameric sample and a sample equal to the standard."""
    std, smp = _pair()
    inst = Instrument(serial="600900", model="MA6", kind="spectrophotometer")
    session.add(inst)
    session.flush()
    ids = []
    for day, spectra in enumerate((std, smp, std.copy())):
        panel = Panel(job="J-300", part="door")
        session.add(panel)
        session.flush()
        ids.append(_stored(session, inst.id, panel.id, spectra, day))
    set_standard(session, "J-300", "door", measurement_id=ids[0])
    session.commit()
    return ids[0], ids[1], ids[2]


def test_job_summary_and_pdf_carry_the_rows(session: Session, tmp_path: Path) -> None:
    from station.qc.report import report_figures, write_pdf

    _, metameric, equal = _job(session)
    std, smp = _pair()
    mi_a = _mi_cs(std, smp, "A")
    limit = float(mi_a.min()) - 0.01
    plain = job_summary(session, "J-300", formula="cie2000")
    assert plain.counts() == {"pass": 2, "warn": 0, "fail": 0}  # equal under D65
    booth = job_summary(session, "J-300", formula="cie2000", illuminant_limits={"A": limit})
    assert booth.counts() == {"pass": 1, "warn": 0, "fail": 1}
    by_id = {s.row.measurement_id: s for s in booth.parts[0].samples}
    assert by_id[metameric].overall == "fail" and by_id[equal].overall == "pass"
    rows = by_id[metameric].illuminants.rows  # type: ignore[union-attr]
    np.testing.assert_allclose([r.index for r in rows], mi_a, atol=1e-6)
    data = booth.to_dict()
    assert data["illuminant_limits"] == {"A": limit}
    sample = next(s for s in data["parts"][0]["samples"] if s["measurement_id"] == metameric)
    assert sample["qc"]["verdict"] == "fail" and sample["qc"]["illuminants"]["rows"][0]["verdict"] == "fail"
    assert len(report_figures(booth)) == 1 + 4 and len(report_figures(plain)) == 1 + 3
    pdf = write_pdf(booth, tmp_path / "report.pdf")
    assert pdf.read_bytes()[:5] == b"%PDF-"
