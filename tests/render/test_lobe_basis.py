"""Basis selection (eq 2.3.4) and the shipped basis table."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from station.errors import InputError
from station.render import basis_selection as bs
from station.render import lobe_fit as lf
from station.render.design_db import design_database
from station.render.lobes import EXPONENT_RANGE, MAX_LOBES, basis_for_count, basis_table, default_basis


def test_design_database_spans_the_required_range() -> None:
    db = design_database()
    assert len(db) >= 30
    assert len({d.name for d in db}) == len(db)
    gloss = [d.gloss_gu for d in db]
    assert min(gloss) <= 5.0 and max(gloss) >= 95.0
    solids = [d for d in db if d.travel_deg is None]
    metallic = [d for d in db if d.travel_deg is not None]
    assert len(solids) >= 5 and len(metallic) >= 20
    assert any(d.travel_deg is not None and d.travel_deg >= 150 for d in metallic)  # high travel
    # hue-shifting pearls: face and flop hue angles differ by more than 40°
    hue = lambda lab: np.degrees(np.arctan2(lab[2], lab[1]))  # noqa: E731
    shifts = [
        abs((hue(d.face) - hue(d.flop) + 180) % 360 - 180)
        for d in metallic
        if np.hypot(*d.face[1:]) > 10 and np.hypot(*d.flop[1:]) > 10
    ]
    assert sum(s > 40 for s in shifts) >= 5
    assert design_database() is db  # deterministic, built once


def test_shipped_table_is_consistent() -> None:
    table = basis_table()
    rows = table["bases"]
    assert [r["lobes"] for r in rows] == list(range(1, MAX_LOBES + 1))
    for r in rows:
        e = r["exponents"]
        assert len(e) == r["lobes"] and e == sorted(e)
        assert EXPONENT_RANGE[0] <= e[0] and e[-1] <= EXPONENT_RANGE[1]
    objective = [r["objective"] for r in rows]
    assert all(b <= a + 1e-6 for a, b in itertools.pairwise(objective))
    row = basis_for_count(int(table["default_lobes"])).exponents
    assert set(row) <= set(default_basis().exponents)  # the library calibration adds to the row
    with pytest.raises(InputError):
        basis_for_count(12)


def test_default_basis_is_calibrated_on_the_library() -> None:
    """The default basis is the table's row plus the lobes its calibration on the demo library moved
    (bench.library_basis), chosen on a training split the held-out benchmark never sees."""
    import json

    from station.render.lobes import LIBRARY_BASIS

    doc = json.loads(LIBRARY_BASIS.read_text())
    assert default_basis().exponents == tuple(sorted(float(e) for e in doc["exponents"]))
    start = basis_for_count(int(basis_table()["default_lobes"])).exponents
    assert doc["start"] == list(start) and len(doc["calibrated"]) == len(start)
    assert set(default_basis().exponents) == set(start) | set(doc["calibrated"])
    assert "training split" in doc["calibration"] and "disjoint" in doc["calibration"]


def test_shipped_errors_are_reproduced_by_the_code() -> None:
    brdfs = [lf.designed_brdf(d) for d in design_database()]
    errors = bs.make_objective(brdfs)
    row = next(r for r in basis_table()["bases"] if r["lobes"] == basis_table()["default_lobes"])
    mx, mean = errors(np.asarray(row["exponents"]))
    assert mx == pytest.approx(row["max_error_de"], abs=2e-3)
    assert mean == pytest.approx(row["mean_error_de"], abs=2e-3)


def test_greedy_selection_never_gets_worse() -> None:
    brdfs = [lf.designed_brdf(d) for d in design_database()[::7]]
    rows = bs.select_bases(brdfs, max_lobes=3, max_evals=40)
    assert [r.lobes for r in rows] == [1, 2, 3]
    assert rows[1].objective <= rows[0].objective + 1e-9
    assert rows[2].objective <= rows[1].objective + 1e-9
    # Lobes are reused: the 2-lobe optimum started from the 1-lobe one and moves little in log space.
    assert min(abs(np.log(rows[1].exponents) - np.log(rows[0].exponents[0]))) < 1.5
    doc = bs.table_json(rows, 2, "test")
    assert isinstance(doc["bases"], list)
    assert doc["default_lobes"] == 2 and len(doc["bases"]) == 3
