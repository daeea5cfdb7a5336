"""Texture QC within one vendor: ΔS and ΔG against their own limits, never across vendors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from station.qc.texture import (
    TextureTolerance,
    TextureValue,
    TextureVendorError,
    judge_texture,
    mean_texture,
    parse_texture_limits,
)
from tests.qc.test_cli import _refused, inproc, set_standard

BYK = "BYK-Gardner"


def _tex(vendor: str, si15: float, sa15: float, g: float) -> list[TextureValue]:
    return [
        TextureValue(vendor, "sparkle intensity", "45as15", si15),
        TextureValue(vendor, "sparkle area", "45as15", sa15),
        TextureValue(vendor, "graininess", "", g),
    ]


def test_texture_verdict_by_hand() -> None:
    tol = TextureTolerance(ds=1.0, dg=0.5)
    v = judge_texture(_tex(BYK, 4.0, 10.0, 5.0), _tex(BYK, 4.9, 11.2, 5.3), tol)
    rows = {(r.name, r.geometry): r for r in v.rows}
    # ΔS intensity 0.9: above 0.8 × 1 → warn; ΔS area 1.2 > 1 → fail; ΔG 0.3 ≤ 0.4 → pass
    assert rows[("sparkle intensity", "45as15")].delta == pytest.approx(0.9)
    assert rows[("sparkle intensity", "45as15")].verdict == "warn"
    assert (
        rows[("sparkle area", "45as15")].verdict == "fail"
        and rows[("sparkle area", "45as15")].tolerance == "ΔS"
    )
    assert rows[("graininess", "")].verdict == "pass" and rows[("graininess", "")].limit == 0.5
    assert v.verdict == "fail" and v.vendor == BYK
    # graininess alone judged: the sparkle rows are listed unjudged
    only_g = judge_texture(_tex(BYK, 4.0, 10.0, 5.0), _tex(BYK, 9.0, 19.0, 5.3), TextureTolerance(dg=0.5))
    assert only_g.verdict == "pass" and [r.verdict for r in only_g.rows].count(None) == 2


def test_values_of_two_vendors_are_never_compared() -> None:
    with pytest.raises(TextureVendorError, match="one vendor"):
        judge_texture(_tex(BYK, 4.0, 10.0, 5.0), _tex("X-Rite", 4.0, 10.0, 5.0), TextureTolerance(1.0, 1.0))


def test_limits_and_means() -> None:
    assert parse_texture_limits("ds=1.5, dg=0.4") == TextureTolerance(1.5, 0.4)
    for bad in ("", "dx=1", "ds=0", "ds=a", "ds=1,ds=2"):
        with pytest.raises(Exception, match="texture_limits"):
            parse_texture_limits(bad)
    m = mean_texture([_tex(BYK, 4.0, 10.0, 5.0), _tex(BYK, 5.0, 12.0, 6.0)])
    assert {(v.name, v.value) for v in m} == {
        ("sparkle intensity", 4.5),
        ("sparkle area", 11.0),
        ("graininess", 5.5),
    }


def _file(path: Path, vendor: str, si: float) -> None:
    tex = [{"vendor": vendor, "name": "sparkle intensity", "geometry": "45as15", "value": si}]
    body = {"geometries": ["45as15", "45as45"], "lab": [[80.0, 1.0, 2.0], [50.0, 1.0, 2.0]], "texture": tex}
    path.write_text(json.dumps(body))


def test_check_judges_texture(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _file(tmp_path / "std.json", BYK, 4.0)
    _file(tmp_path / "smp.json", BYK, 5.5)
    _file(tmp_path / "other.json", "X-Rite", 4.0)
    base = ("qc", "check", "--standard", "std.json", "--formula", "cie76", "--texture-limits", "ds=1")
    res = inproc(capsys, tmp_path, *base, "--sample", "smp.json", "--json")
    out = json.loads(res.stdout)
    # colour identical (pass), sparkle ΔS 1.5 > 1: the texture fails the sample
    assert out["max_de"] == 0 and out["texture"]["verdict"] == "fail" and out["verdict"] == "fail"
    assert out["texture"]["rows"][0]["delta"] == pytest.approx(1.5)
    text = inproc(capsys, tmp_path, *base, "--sample", "smp.json").stdout
    assert "texture (BYK-Gardner): fail" in text and "ΔS ≤ 1" in text
    _refused(inproc(capsys, tmp_path, *base, "--sample", "other.json"), "texture")


def test_summary_judges_texture_within_the_standard_vendor(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import datetime as dt
    import uuid

    from db.engine import make_engine, make_sessionmaker
    from db.migrate import ensure_at_head
    from db.models import Instrument, Measurement, Panel

    url = f"sqlite:///{tmp_path / 'qc.sqlite3'}"
    ensure_at_head(url)
    engine = make_engine(url)
    t0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.UTC)
    with make_sessionmaker(engine)() as s:
        inst = Instrument(serial="900100", model="BYK-mac i", kind="spectrophotometer")
        s.add(inst)
        s.flush()
        for i, (vendor, si) in enumerate(((BYK, 4.0), (BYK, 5.5), ("X-Rite", 4.0))):
            p = Panel(job="J-T", part="fender")
            s.add(p)
            s.flush()
            tex = [{"vendor": vendor, "name": "sparkle intensity", "geometry": "45as15", "value": si}]
            s.add(
                Measurement(
                    client_id=uuid.uuid4(), instrument_id=inst.id, panel_id=p.id, operator="ana",
                    measured_at=t0 + dt.timedelta(days=i), geometries_deg=[15.0, 45.0],
                    lab=[[80.0, 1.0, 2.0], [50.0, 1.0, 2.0]], payload_sha256="0" * 64, texture=tex,
                )
            )  # fmt: skip
            s.flush()
        s.commit()
    engine.dispose()
    db = ("--db", url)
    res = set_standard(capsys, tmp_path, "J-T", "1", url)
    assert res.returncode == 0, res.stderr
    args = ("qc", "summary", "--job", "J-T", "--formula", "cie76", "--texture-limits", "ds=1", *db)
    out = json.loads(inproc(capsys, tmp_path, *args, "--json").stdout)
    (part,) = out["parts"]
    (sample,) = part["samples"]  # the X-Rite panel is not compared with the BYK standard
    assert (
        sample["qc"]["verdict"] == "pass"
        and sample["texture"]["verdict"] == "fail"
        and sample["overall"] == "fail"
    )
    assert part["unjudged"] == [3] and "one vendor" in part["note"]
    text = inproc(capsys, tmp_path, *args).stdout
    assert "FAIL" in text and "texture" in text
