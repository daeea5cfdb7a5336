"""The QC screen's judging options and SPC helpers without a display: bad input names its field, the
service refuses what it does not offer, the report preview (never a silently other verdict); the SPC table's
numbers and the sample numbers of its rule hits."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.errors import InputError
from station.model.domain import ANGLES_3
from station.qc.spc import capability, drift_hits, individuals_chart
from station.qc.spc_part import GeometrySpc, PartSpc
from station.qc.tolerance import ToleranceSet
from ui.models.qc import QcModel, QcSourceError, ServiceQc
from ui.models.qc_views import Judging, spc_hit_lines, spc_png, spc_rows
from ui.models.service import ServiceClient


def test_a_tolerance_file_is_read_and_a_bad_one_is_named(tmp_path):
    tol = ToleranceSet.uniform(ANGLES_3, 0.6, formula="cie2000", mean_limit=0.6)
    good = tmp_path / "tol.json"
    good.write_text(json.dumps(tol.to_dict()))
    got = Judging(tolerance=str(good)).tolerance_set()
    assert got is not None and [g.de for g in got.geometries] == [0.6, 0.6, 0.6] and got.formula == "cie2000"
    for bad in (tmp_path / "missing.json", tmp_path / "notjson.json"):
        bad.parent.joinpath("notjson.json").write_text("{not json")
        with pytest.raises(InputError) as exc:
            Judging(tolerance=str(bad)).checked()
        assert exc.value.field == "tolerance"
    with pytest.raises(InputError) as exc:
        Judging(texture_limits="dz=1").checked()
    assert exc.value.field == "texture_limits"
    assert Judging(texture_limits="ds=1, dg=0.5").texture_tolerance().dg == 0.5  # type: ignore[union-attr]


def test_the_service_refuses_the_report_preview_with_a_message():
    client = ServiceClient("http://127.0.0.1:9")  # nothing answers there: a request would fail differently
    model = QcModel(ServiceQc(client))
    try:
        model.summary_key = ("J-1", "cie2000")
        with pytest.raises(
            QcSourceError, match="the report preview: available with the workstation's database"
        ):
            model.report_preview()
    finally:
        client.close()


def test_spc_rows_and_hit_lines_number_the_samples_from_one():
    # a flat baseline of six, then a steady rise: ΔE 0.10 … and the limit 0.6
    values = [0.10, 0.12, 0.09, 0.11, 0.10, 0.12, 0.20, 0.30, 0.40, 0.52, 0.70]
    chart = individuals_chart(values, baseline=6)
    cap = capability(values[:6], 0.6, chart.sigma_process)
    g = GeometrySpc("45as15", chart, cap, drift_hits(chart), first_fail=10)
    spc = PartSpc("J-1", "door", tuple(f"panel {i}" for i in range(11)), 6, 1, (g,))
    (row,) = spc_rows(spc)
    base = np.array(values[:6])
    sigma = np.abs(np.diff(base)).mean() / 1.128  # d₂(2) as published (Montgomery, Appendix VI)
    assert row.centre == pytest.approx(base.mean()) and row.ucl == pytest.approx(base.mean() + 3 * sigma)
    assert row.cp == pytest.approx(0.6 / (6 * sigma)) and row.cpk == pytest.approx(
        (0.6 - base.mean()) / (3 * sigma)
    )
    # the 7th value is beyond 3σ of the baseline: WE1 names sample #7 (1-based), not point 6
    sd = (np.array(values) - base.mean()) / sigma
    beyond = [f"#{i + 1}" for i in np.flatnonzero(np.abs(sd) > 3)]
    assert row.hits.startswith(f"WE1 @ {', '.join(beyond)}") and beyond[0] == "#7"
    lines = spc_hit_lines(spc)
    assert lines[0] == "J-1 / door: 11 samples, individuals chart, limits from the first 6"
    assert (
        lines[1].startswith("DRIFT 45as15: drift from sample #")
        and "before the first fail (sample #11)" in lines[1]
    )
    assert spc_png(spc).startswith(b"\x89PNG")
