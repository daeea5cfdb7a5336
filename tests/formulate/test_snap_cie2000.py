"""CIEDE2000 ColorSnap: the per-paint lower/upper bounds hold against the exact kernel (hypothesis over
random, near-neutral, blue-region (h' ≈ 275°, where R_T peaks) and near-identical pairs), and the
one-kernel-call flat search equals a brute-force scan through station.model.difference.delta_e, ties
included."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from station.formulate.de_kernels import cie2000
from station.formulate.snap import SnapIndex, brute_force
from station.formulate.snap.bounds import W_AB, W_L, box_bounds_cie2000_fast, point_bounds_cie2000
from station.formulate.snap.kernel import best_first_cie2000, compiled_search

_l = st.floats(0.0, 100.0, allow_nan=False)


@st.composite
def _lab(draw: st.DrawFn, region: str) -> tuple[float, float, float]:
    """One Lab colour of a region: anywhere, near-neutral (C* < 1.5) or blue (hue 250–300°)."""
    if region == "any":
        return draw(_l), draw(st.floats(-128, 128)), draw(st.floats(-128, 128))
    c = draw(st.floats(0.0, 1.5)) if region == "neutral" else draw(st.floats(0.0, 120.0))
    h = draw(st.floats(0.0, 360.0)) if region == "neutral" else draw(st.floats(250.0, 300.0))
    a, b = c * math.cos(math.radians(h)), c * math.sin(math.radians(h))
    if draw(st.booleans()):
        a = 0.0 if draw(st.booleans()) else -0.0
    return draw(_l), a, b


@st.composite
def _pairs(draw: st.DrawFn, n: int = 24) -> tuple[np.ndarray, np.ndarray]:
    regions = st.sampled_from(["any", "neutral", "blue"])
    q = np.array([draw(_lab(draw(regions))) for _ in range(3)])
    p = np.array([[draw(_lab(draw(regions))) for _ in range(3)] for _ in range(n)])
    tiny = draw(st.floats(0.0, 1e-3))
    p[: n // 4] = q + tiny * np.sign(p[: n // 4] - 50.0)  # near-identical pairs (ΔH' ≈ 0, cancellation)
    p[n // 4] = q  # identical
    p[..., 0] = np.clip(p[..., 0], 0.0, 100.0)
    return q, p


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pair=_pairs())
def test_point_bounds_bracket_the_exact_sum(pair) -> None:
    q, p = pair
    exact = cie2000(q[None], p).sum(-1)
    lower, upper = point_bounds_cie2000(q, p, upper=True)
    assert np.all(lower <= exact), (lower - exact).max()
    assert np.all(upper >= exact), (exact - upper).max()
    assert np.array_equal(lower, point_bounds_cie2000(q, p))


def test_bounds_are_tight_enough_to_prune() -> None:
    rng = np.random.default_rng(5)
    q = rng.uniform(-60, 60, (3, 3))
    q[:, 0] = 50.0
    p = q + rng.normal(0, 3.0, (2000, 3, 3))
    exact = cie2000(q[None], p).sum(-1)
    lower, upper = point_bounds_cie2000(q, p, upper=True)
    assert np.median(lower / exact) > 0.6 and np.median(upper / exact) < 1.6


def _fix_l(a: np.ndarray) -> np.ndarray:
    a = a.copy()
    a[..., 0] = np.abs(a[..., 0]) % 100.0
    return a


@settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    lib=arrays(
        np.float64,
        st.tuples(st.integers(1, 400), st.just(3), st.just(3)),
        elements=st.floats(-120, 120, width=32),
    ).map(_fix_l),
    data=st.data(),
    k=st.integers(1, 40),
    leaf=st.sampled_from([None, 1, 3, 16]),
)
@pytest.mark.parametrize("compiled", [True, False], ids=["numba", "numpy"])
def test_flat_cie2000_search_equals_brute_force_with_ties(lib, data, k, leaf, compiled) -> None:
    n = lib.shape[0]
    if n > 4:  # exact ties (duplicates) and near ties
        lib[n // 3] = lib[1]
        lib[n - 1] = lib[1]
        lib[n // 2] = lib[0] + 1e-9
    q = (
        lib[data.draw(st.integers(0, n - 1))].copy()
        if data.draw(st.booleans())
        else _fix_l(data.draw(arrays(np.float64, (3, 3), elements=st.floats(-120, 120, width=32))))
    )
    index = SnapIndex(lib, leaf_size=leaf, group=1)
    rows, sums, per = index.query(q, k, "cie2000", use_numba=compiled)
    b_rows, b_sums, b_per = brute_force(lib, q, k, "cie2000")
    assert rows.tolist() == b_rows.tolist()
    assert np.array_equal(sums, b_sums) and np.array_equal(per, b_per)


@pytest.mark.parametrize("compiled", [True, False], ids=["numba", "numpy"])
def test_cie2000_on_a_clustered_library(small_library, compiled) -> None:
    std = small_library.angle_columns()
    rng = np.random.default_rng(9)
    lib = np.repeat(std, 25, axis=0) + rng.normal(0, 1.5, (len(std) * 25, 3, 3))
    lib[..., 0] = np.clip(lib[..., 0], 0, 100)
    index = SnapIndex(lib)
    assert index.n_groups == 1 or index.group == 1
    for q in std[:40] + rng.normal(0, 3.0, (40, 3, 3)):
        q[:, 0] = np.clip(q[:, 0], 0, 100)
        for k in (1, 5, 30):
            rows, sums, _ = index.query(q, k, "cie2000", use_numba=compiled)
            b_rows, b_sums, _ = brute_force(lib, q, k, "cie2000")
            assert rows.tolist() == b_rows.tolist() and np.array_equal(sums, b_sums)


def test_compiled_walk_equals_its_python_form_and_visits_few_leaves(small_library) -> None:
    # the same function run as plain Python (no numba) returns the same candidates as the compiled one
    std = small_library.angle_columns()
    index = SnapIndex(std, leaf_size=8, group=4)
    args = (
        index._glo,
        index._ghi,
        index._gcmax,
        index._lo,
        index._hi,
        index._cmax,
        index.group,
        index._rows,
        index._blab,
        index.size,
    )
    compiled = compiled_search()
    assert compiled is not None
    rng = np.random.default_rng(2)
    for q in std[:6] + rng.normal(0, 2.0, (6, 3, 3)):
        q[:, 0] = np.clip(q[:, 0], 0, 100)
        py_rows, py_visited = best_first_cie2000(q, *args, 5)
        c_rows, c_visited = compiled(q, *args, 5)
        assert sorted(py_rows.tolist()) == sorted(c_rows.tolist()) and py_visited == c_visited
        assert c_visited < index.n_buckets
        top = brute_force(std, q, 5, "cie2000")[0]
        assert set(top.tolist()) <= set(c_rows.tolist())


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pair=_pairs(n=20))
def test_table_box_bound_and_table_point_bound_never_exceed_the_exact_sum(pair) -> None:
    q, p = pair
    exact = cie2000(q[None], p).sum(-1)
    chroma = np.hypot(p[..., 1], p[..., 2])
    lo, hi = p.min(0), p.max(0)
    box = box_bounds_cie2000_fast(q, lo[None], hi[None], lo[None, :, 0], hi[None, :, 0], chroma.max(0)[None])
    assert box[0] <= exact.min()
    points = box_bounds_cie2000_fast(
        q, p, p, np.ascontiguousarray(p[..., 0]), np.ascontiguousarray(p[..., 0]), chroma
    )
    assert np.all(points <= exact)
    index = SnapIndex(p, leaf_size=4, group=1)
    rows, lower = index._cheap_bounds(q, index._tile(q), np.arange(index.n_buckets))
    assert np.all(lower <= exact[rows])


def test_weight_tables_rest_on_monotone_functions() -> None:
    # the tables assume (1 + G(C̄)) C̄ increasing and both weights decreasing (docstring of the tables)
    c = np.linspace(0.0, 600.0, 600_001)
    c7 = c**7
    f = (1.0 + 0.5 * (1.0 - np.sqrt(c7 / (c7 + 25.0**7)))) * c
    assert np.all(np.diff(f) > 0)
    assert np.all(np.diff(W_L) <= 0) and np.all(np.diff(W_AB) <= 0)


def test_one_bound_arithmetic_brackets_colour_science_on_random_pairs() -> None:
    """pair_bounds2 is the only copy of the per-pair bound arithmetic: called on arrays (the NumPy path)
    and on floats (what the numba walk compiles inline) it gives the same numbers, and both bracket
    colour-science's delta_E_CIE2000 on random Lab pairs; the compiled walk's per-paint bounds bracket
    colour's summed ΔE00 too."""
    import colour

    from station.formulate.snap.bounds import SAFETY, pair_bounds2
    from station.formulate.snap.kernel import paint_bounds_one

    rng = np.random.default_rng(2000)
    n = 4000
    ref = np.column_stack([rng.uniform(0, 100, n), rng.uniform(-128, 128, n), rng.uniform(-128, 128, n)])
    smp = ref + rng.normal(0.0, 1.0, (n, 1)) * rng.normal(0.0, 6.0, (n, 3))  # near and far pairs
    smp[: n // 8, 1:] = rng.uniform(-1.5, 1.5, (n // 8, 2))  # near-neutral samples
    smp[:, 0] = np.clip(smp[:, 0], 0.0, 100.0)
    exact = np.asarray(colour.delta_E(ref, smp, method="CIE 2000"))
    cols = (*ref.T, np.hypot(ref[:, 1], ref[:, 2]), *smp.T, np.hypot(smp[:, 1], smp[:, 2]))
    lo2, hi2 = pair_bounds2(*cols)
    assert np.all(np.sqrt(lo2) * SAFETY - 1e-10 <= exact) and np.all(
        np.sqrt(hi2) * (2 - SAFETY) + 1e-10 >= exact
    )
    for j in range(0, n, 97):  # the scalar call: the same floating-point operations
        one = pair_bounds2(*(float(c[j]) for c in cols))
        assert one == (lo2[j], hi2[j])
    # the walk's per-paint bounds (three angles), compiled as the search compiles them
    assert compiled_search() is not None
    import numba

    per_paint = numba.njit(paint_bounds_one)
    q = ref[:3]
    cq = np.hypot(q[:, 1], q[:, 2])
    blab = smp[: (n // 3) * 3].reshape(1, -1, 3, 3)
    total = np.asarray(colour.delta_E(q[None], blab[0], method="CIE 2000")).sum(-1)
    for w in range(blab.shape[1]):
        lower, upper = per_paint(q, cq, blab, 0, w)
        assert lower <= total[w] <= upper
