"""The batched face/flop/travel fit (``fit_fftg_batch``) gives every paint the fit ``fit_fftg`` gives it
alone — designs, residuals, exact flags, methods, warnings and refusals — on the demo library and on
input that takes every branch of the fit, and its θ_clamp is the least-cost one (checked against
an independent grid search with numpy's least squares)."""

from __future__ import annotations

import numpy as np
import pytest

from station.formulate import demo_library
from station.model import AspecularMeasurements, fit_fftg
from station.model.domain import FACE_ANGLE_DEG, TRAVEL_MAX_DEG
from station.model.errors import FitError, ModelInputError
from station.model.fit import FitBatch, fit_fftg_batch


def _sorted_library():
    lib = demo_library()
    order = np.argsort(lib.angles_deg)
    return lib, tuple(float(lib.angles_deg[j]) for j in order), lib.lab[:, order]


def _assert_same(batch: FitBatch, n: int, angles, lab, gloss) -> None:
    """Row *n* of *batch* equals fit_fftg of the same measurements (or both refuse, with one message)."""
    m = AspecularMeasurements(tuple(angles), lab, gloss)
    try:
        single = fit_fftg(m)
    except FitError as exc:
        with pytest.raises(FitError) as info:
            batch.result(n)
        assert str(info.value) == str(exc)
        return
    got = batch.result(n)
    d, e = single.design, got.design
    assert (d.travel_deg is None) == (e.travel_deg is None)
    if d.travel_deg is not None:
        assert e.travel_deg == pytest.approx(d.travel_deg, abs=1e-6)
    np.testing.assert_allclose(e.face, d.face, rtol=0, atol=1e-9)
    np.testing.assert_allclose(e.flop, d.flop, rtol=0, atol=1e-9)
    assert e.gloss_gu == d.gloss_gu
    np.testing.assert_allclose(got.residual_de, single.residual_de, rtol=0, atol=1e-9)
    assert (got.exact, got.method, got.warnings) == (single.exact, single.method, single.warnings)


def _cost(angles: np.ndarray, lab: np.ndarray, tc: float) -> float:
    """Unconstrained projected cost at θ_clamp, written out here: [s², 1 − s²] and numpy's lstsq."""
    s = (tc - np.minimum(np.abs(angles), tc)) / (tc - FACE_ANGLE_DEG)
    a = np.stack([s**2, 1.0 - s**2], axis=1)
    coef, *_ = np.linalg.lstsq(a, lab, rcond=None)
    return float(np.sum((a @ coef - lab) ** 2))


def test_demo_library_batch_equals_the_per_paint_fit() -> None:
    lib, angles, lab = _sorted_library()
    batch = fit_fftg_batch(angles, lab, lib.gloss_gu)
    assert len(batch) == len(lib) and not any(batch.errors)
    rng = np.random.default_rng(18)
    rows = set(rng.choice(len(lib), 300, replace=False).tolist())
    rows |= {int(np.flatnonzero(lib.codes == "SYN-NM0003")[0])}  # the neutral metallic of the issue
    rows |= {i for i, w in enumerate(batch.warnings) if w and "near-solid" not in w[0]}  # every warned paint
    rows |= set(np.flatnonzero(lib.types == "pearl")[:20].tolist())
    for i in sorted(rows):
        _assert_same(batch, i, angles, lab[i], float(lib.gloss_gu[i]))


def test_a_paint_fits_the_same_in_any_batch() -> None:
    """Shuffled and split into other batches, every row comes out bit for bit the same."""
    lib, angles, lab = _sorted_library()
    rows = np.random.default_rng(3).choice(len(lib), 700, replace=False)
    whole = fit_fftg_batch(angles, lab[rows], lib.gloss_gu[rows])
    perm = np.random.default_rng(4).permutation(rows.size)
    shuffled = fit_fftg_batch(angles, lab[rows[perm]], lib.gloss_gu[rows[perm]])
    inverse = np.argsort(perm)
    for name in ("face", "flop", "travel_deg", "residual_de", "exact"):
        np.testing.assert_array_equal(getattr(shuffled, name)[inverse], getattr(whole, name), err_msg=name)
    assert [shuffled.warnings[i] for i in inverse] == list(whole.warnings)
    for part in np.array_split(np.arange(rows.size), 7):
        piece = fit_fftg_batch(angles, lab[rows[part]], lib.gloss_gu[rows[part]])
        np.testing.assert_array_equal(piece.travel_deg, whole.travel_deg[part])
        np.testing.assert_array_equal(piece.face, whole.face[part])


def _mixed_three_angle() -> np.ndarray:
    """15/45/110 rows taking each branch: closed form, no monotone quadratic, L* flat, a solid, a
    near-solid, an extrapolated vertex below L* = 0 (constrained), a retroreflective one."""
    return np.array(
        [
            [[90.0, 2.0, -3.0], [40.0, 3.0, -1.0], [25.0, 4.0, 0.0]],  # closed form
            [[50.0, 1.0, 1.0], [60.0, 2.0, 2.0], [40.0, 1.0, 0.0]],  # L* not monotone
            [[50.0, 10.0, 1.0], [50.0, 5.0, 2.0], [50.0, 1.0, 3.0]],  # L* flat
            [[40.0, 5.0, 5.0], [40.0, 5.0, 5.0], [40.0, 5.0, 5.0]],  # a solid
            [[40.1, 5.0, 5.0], [40.0, 5.0, 5.0], [40.0, 5.0, 5.1]],  # near-solid
            [[67.2, -1.25, -5.6], [40.0, -1.45, -6.7], [1.0, -0.81, -4.1]],  # constrained
            [[20.0, 0.0, 0.0], [40.0, 0.0, 0.0], [60.0, 1.0, 1.0]],  # flop brighter than face
        ]
    )


@pytest.mark.parametrize("gloss", [None, "per paint"])
def test_every_branch_of_the_fit_matches_per_paint(gloss) -> None:
    lab = _mixed_three_angle()
    g = None if gloss is None else np.linspace(10.0, 95.0, len(lab))
    batch = fit_fftg_batch((15.0, 45.0, 110.0), lab, g)
    methods = set(batch.method)
    assert methods == {"closed-form", "least-squares", "constrained"}
    assert batch.travel_deg[3] != batch.travel_deg[3]  # NaN: the solid has no travel
    for n in range(len(lab)):
        _assert_same(batch, n, (15.0, 45.0, 110.0), lab[n], None if g is None else float(g[n]))
    if gloss is None:
        assert all(w[0].startswith("gloss not measured") for w in batch.warnings)


def test_refused_paints_keep_their_message_and_the_rest_fit() -> None:
    """Angles below the face angle let the best vertex fall to 15°: those rows are refused, as alone."""
    rng = np.random.default_rng(1)
    lab = np.zeros((300, 4, 3))
    lab[:, :, 0] = rng.uniform(0, 100, (300, 4))
    lab[:, :, 1:] = rng.uniform(-20, 20, (300, 4, 2))
    angles = (5.0, 15.0, 20.0, 45.0)
    batch = fit_fftg_batch(angles, lab, None)
    refused = [i for i, e in enumerate(batch.errors) if e is not None]
    assert 0 < len(refused) < len(lab)
    assert all(np.isnan(batch.face[i]).all() and np.isnan(batch.travel_deg[i]) for i in refused)
    for n in range(0, len(lab), 3):
        _assert_same(batch, n, angles, lab[n], None)


def test_travel_is_the_least_cost_one_against_a_fine_grid() -> None:
    """Independent check: no θ_clamp of a 0.02° grid (numpy lstsq at each) beats the batch's, and the
    batch's θ_clamp is a local minimum to within 1e-5°."""
    lib, angles, lab = _sorted_library()
    rows = np.flatnonzero(lib.types != "solid")[::97]
    batch = fit_fftg_batch(angles, lab[rows], lib.gloss_gu[rows])
    ang = np.asarray(angles)
    grid = np.arange(FACE_ANGLE_DEG + 0.02, TRAVEL_MAX_DEG + 1e-9, 0.02)
    for n, i in enumerate(rows):
        tc = float(batch.travel_deg[n])
        ours = _cost(ang, lab[i], tc)
        np.testing.assert_allclose(
            ours, float(np.sum(np.square(batch.residual_de[n]))), rtol=1e-9, atol=1e-12
        )
        near = grid[np.abs(grid - tc) < 3.0]
        assert ours <= min(_cost(ang, lab[i], t) for t in near) + 1e-9, lib.codes[i]
        step = 1e-5
        assert ours <= _cost(ang, lab[i], tc - step) + 1e-12 and ours <= _cost(ang, lab[i], tc + step) + 1e-12


def test_bad_input_names_the_paint_and_the_field() -> None:
    lab = _mixed_three_angle()
    with pytest.raises(ModelInputError, match="lab"):
        fit_fftg_batch((15.0, 45.0, 110.0), lab[:, :2], None)
    bad = lab.copy()
    bad[4, 1, 0] = -3.0
    with pytest.raises(ModelInputError, match=r"lab\[4\]\[1\]\.L"):
        fit_fftg_batch((15.0, 45.0, 110.0), bad, None)
    with pytest.raises(ModelInputError, match="gloss_gu"):
        fit_fftg_batch((15.0, 45.0, 110.0), lab, [50.0])
    with pytest.raises(ModelInputError, match=r"gloss_gu\[2\]"):
        fit_fftg_batch((15.0, 45.0, 110.0), lab, [50.0, 50.0, -1.0, 50.0, 50.0, 50.0, 50.0])
    with pytest.raises(FitError, match="at least 3"):
        fit_fftg_batch((15.0, 45.0), lab[:, :2], None)
    assert len(fit_fftg_batch((15.0, 45.0, 110.0), np.zeros((0, 3, 3)), None)) == 0
