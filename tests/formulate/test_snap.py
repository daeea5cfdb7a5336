"""ColorSnap: exactness against a brute-force scan through station.model.difference.delta_e, bound
validity, the Fig. 5.10 warnings, view data and input errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from station.formulate.de_kernels import KERNELS
from station.formulate.errors import FormulateInputError
from station.formulate.library import Library
from station.formulate.snap import (
    METHODS,
    SnapIndex,
    brute_force,
    color_snap,
    view_data,
)
from station.formulate.snap.bounds import box_bounds, point_bounds_cie2000
from station.formulate.snap.results import SnapStats
from station.model.difference import delta_e
from station.model.domain import ANGLES_3

#: |aspecular angle| of the three Lab columns (read by din6175).
ALPHA = np.abs(np.asarray(ANGLES_3))

lab_el = st.floats(-120, 120, allow_nan=False, width=32)


def _labs(n: int) -> st.SearchStrategy[np.ndarray]:
    return arrays(np.float64, (n, 3, 3), elements=lab_el).map(_fix_l)


def _fix_l(a: np.ndarray) -> np.ndarray:
    a = a.copy()
    a[..., 0] = np.abs(a[..., 0]) % 100.0
    return a


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(1, 300),
    data=st.data(),
    k=st.integers(1, 12),
    method=st.sampled_from(METHODS),
    leaf=st.sampled_from([None, 2, 5]),
    group=st.sampled_from([None, 1, 3]),
)
def test_top_k_is_identical_to_brute_force(n, data, k, method, leaf, group) -> None:
    lib = data.draw(_labs(n))
    if n > 3 and data.draw(st.booleans()):  # duplicates make exact ties: broken by row, as brute force
        lib[n // 2] = lib[0]
        lib[n - 1] = lib[0]
    q = data.draw(_labs(1))[0]
    if data.draw(st.booleans()):
        q = lib[data.draw(st.integers(0, n - 1))].copy()
    index = SnapIndex(lib, leaf_size=leaf, group=group)
    rows, sums, per = index.query(q, k, method)
    b_rows, b_sums, b_per = brute_force(lib, q, k, method)
    assert rows.tolist() == b_rows.tolist()
    assert np.array_equal(sums, b_sums)
    assert np.array_equal(per, b_per)


def test_exact_on_a_clustered_library_with_groups(small_library: Library) -> None:
    std = small_library.angle_columns()
    rng = np.random.default_rng(3)
    big = np.repeat(std, 20, axis=0) + rng.normal(0, 1.0, (len(std) * 20, 3, 3))
    big[..., 0] = np.clip(big[..., 0], 0, 100)
    index = SnapIndex(big, leaf_size=8, group=16)
    assert index.n_groups > 1
    for q in std[:25] + rng.normal(0, 2.0, (25, 3, 3)):
        q[:, 0] = np.clip(q[:, 0], 0, 100)
        for method in METHODS:
            rows, sums, _ = index.query(q, 7, method)
            b_rows, b_sums, _ = brute_force(big, q, 7, method)
            assert rows.tolist() == b_rows.tolist()
            assert np.array_equal(sums, b_sums)


@settings(max_examples=80, deadline=None)
@given(pts=_labs(40), q=_labs(1), method=st.sampled_from(METHODS))
def test_box_and_point_bounds_never_exceed_the_exact_sum(pts, q, method) -> None:
    q = q[0]
    exact = delta_e(q[None], pts, method, aspecular_deg=ANGLES_3).sum(-1)
    chroma = np.hypot(pts[..., 1], pts[..., 2])
    box = box_bounds(q, pts.min(0), pts.max(0), chroma.max(0), method, alpha=ALPHA)
    assert box <= exact.min() + 1e-12
    assert box_bounds(q, pts.min(0), pts.max(0), chroma.max(0), method, hue=False, alpha=ALPHA) <= box + 1e-12
    point = box_bounds(q, pts, pts, chroma, method, alpha=ALPHA)
    assert np.all(point <= exact + 1e-12)
    if method == "cie2000":
        assert np.all(point_bounds_cie2000(q, pts) <= exact + 1e-12)


@settings(max_examples=100, deadline=None)
@given(
    a=arrays(np.float64, (50, 3), elements=lab_el),
    b=arrays(np.float64, (50, 3), elements=lab_el),
    angles=arrays(np.float64, (50,), elements=st.floats(-90, 180).filter(lambda x: abs(x) >= 1e-3)),
)
def test_kernels_are_bit_identical_to_the_model(a, b, angles) -> None:
    b[::5] = a[::5]  # identical pairs
    b[1::7, 1:] = 0.0  # achromatic samples
    a[2::9, 0] = 0.0  # black standards (L̄ = 0)
    alpha = np.abs(angles)
    for method, kernel in KERNELS.items():
        assert np.array_equal(kernel(a, b, alpha), delta_e(a, b, method, aspecular_deg=angles)), method


def test_match_of_a_library_paint_is_itself(small_library: Library) -> None:
    std = small_library.angle_columns()
    result = color_snap(small_library, std[17], k=3)
    assert result.matches[0].code == small_library.codes[17]
    assert result.matches[0].sum_de == 0.0
    assert result.warnings == ()
    d = result.to_dict()
    assert isinstance(d["matches"], list)
    assert set(d["matches"][0]) >= {"code", "sum_de", "de_per_angle"}
    assert len(d["matches"]) == 3


def test_far_outside_warning_for_a_too_saturated_design(small_library: Library) -> None:
    design = np.array([[45.0, 95.0, 60.0], [35.0, 90.0, 55.0], [20.0, 70.0, 40.0]])
    result = color_snap(small_library, design, k=1, method="cie2000")
    assert any("far outside the library" in w and "more chromatic" in w for w in result.warnings)


def test_off_radial_travel_warning() -> None:
    # a library of radial metallics (hue constant from face to flop) and a design whose hue turns 90°
    lab = np.array([[[70.0, 30.0, 0.0], [50.0, 25.0, 0.0], [30.0, 20.0, 0.0]]])
    lib = Library(
        "radial", np.array(["R1"]), np.array(["metallic"]), np.array([80.0]), (15.0, 45.0, 110.0), lab
    )
    design = np.array([[70.0, 30.0, 0.0], [50.0, 22.0, 8.0], [30.0, 22.0, 14.0]])
    result = color_snap(lib, design, k=1)
    assert any("travel direction" in w for w in result.warnings)
    radial = color_snap(lib, lab[0] + [0.5, 0.5, 0.0], k=1)
    assert not any("travel" in w for w in radial.warnings)


def test_view_data_has_design_matches_and_cloud(small_library: Library) -> None:
    result = color_snap(small_library, small_library.angle_columns()[3], k=2)
    data = view_data(small_library, result, max_cloud=100)
    assert isinstance(data["design"], list) and isinstance(data["matches"], list)
    assert isinstance(data["cloud"], dict)
    assert len(data["design"]) == 3 and len(data["matches"]) == 2
    assert len(data["cloud"]["lab"]) == 100 and data["cloud"]["sampled"] is True
    assert data["synthetic"] is True


@pytest.mark.parametrize(
    ("lab", "k", "method", "field"),
    [
        ([[50, 0, 0]] * 2, 5, "cie76", "lab"),
        ([[50, 0, 0], [50, 0, 0], [float("nan"), 0, 0]], 5, "cie76", "lab.L"),
        ([[50, 0, 0], [50, 0, 0], [50, 0, 900]], 5, "cie76", "lab.b"),
        ([[50, 0, 0]] * 3, 0, "cie76", "k"),
        ([[50, 0, 0]] * 3, 5, "cie94x", "de"),
    ],
)
def test_bad_queries_raise_typed_errors(small_library: Library, lab, k, method, field) -> None:
    index = SnapIndex(small_library)
    with pytest.raises(FormulateInputError) as err:
        index.query(lab, k, method)
    assert err.value.field == field


@settings(max_examples=300, deadline=None)
@given(
    centre=arrays(np.float64, (3, 3), elements=st.floats(-90, 90, width=32)),
    spread=st.floats(0.01, 8.0),
    q=arrays(np.float64, (3, 3), elements=st.floats(-90, 90, width=32)),
    seed=st.integers(0, 2**31),
)
def test_cie2000_hue_aware_bound_on_small_chromatic_boxes(centre, spread, q, seed) -> None:
    # small boxes away from the neutral axis are where the hue-dependent R_T bound is used
    rng = np.random.default_rng(seed)
    centre[:, 0] = np.abs(centre[:, 0]) % 100
    q[:, 0] = np.abs(q[:, 0]) % 100
    pts = centre + rng.uniform(-spread, spread, (20, 3, 3))
    exact = delta_e(q[None], pts, "cie2000").sum(-1)
    chroma = np.hypot(pts[..., 1], pts[..., 2])
    box = box_bounds(q, pts.min(0), pts.max(0), chroma.max(0), "cie2000")
    assert box <= exact.min() + 1e-12
    assert np.all(point_bounds_cie2000(q, pts) <= exact + 1e-12)


@pytest.mark.parametrize(
    ("method", "use_numba", "path"),
    [("cie76", True, "bounded"), ("cie2000", True, "compiled"), ("cie2000", False, "flat")],
)
def test_concurrent_queries_get_their_own_statistics(method: str, use_numba: bool, path: str) -> None:
    """Two queries that open very different parts of one shared index, run together from many threads,
    each report the statistics the same query reports when it runs alone."""
    import sys
    from concurrent.futures import ThreadPoolExecutor
    from threading import Barrier

    rng = np.random.default_rng(3)
    lib = rng.uniform(-80, 80, (4000, 3, 3))
    lib[..., 0] = rng.uniform(0, 100, (4000, 3))
    index = SnapIndex(lib, group=1)
    near = lib[17] + 0.01  # next to one paint: few leaves opened
    far = np.array([[50.0, 0.0, 0.0]] * 3)  # the library's centre: the bounds prune little
    alone = {name: index.snap(q, 5, method, use_numba).stats for name, q in (("near", near), ("far", far))}
    assert alone["near"] != alone["far"] and {s.path for s in alone.values()} == {path}
    for s in alone.values():  # counts within the index searched (the compiled walk uses a finer one)
        assert 1 <= s.leaves_visited <= s.leaves and s.leaves >= index.n_buckets and s.candidates >= 5
    rounds = 100
    barrier = Barrier(2)

    def run(name: str) -> list[SnapStats]:
        q = near if name == "near" else far
        out = []
        for _ in range(rounds):
            barrier.wait()
            out.append(index.snap(q, 5, method, use_numba).stats)
        return out

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # switch threads as often as possible: a shared counter would be caught
    try:
        with ThreadPoolExecutor(2) as pool:
            got = dict(zip(("near", "far"), pool.map(run, ("near", "far")), strict=True))
    finally:
        sys.setswitchinterval(interval)
    for name, stats in got.items():
        assert stats == [alone[name]] * rounds, name
    b_rows = brute_force(lib, near, 5, method)[0]  # and the shared index still answers exactly
    assert index.query(near, 5, method, use_numba)[0].tolist() == b_rows.tolist()


def test_a_query_writes_nothing_to_the_shared_index(small_library) -> None:
    """Deterministic half of the concurrency guarantee: no query of any path rebinds an attribute of
    the index (the finer CIEDE2000 index is built once, on first use, before the snapshot)."""
    index = SnapIndex(small_library)
    q = small_library.angle_columns()[5] + 0.2
    index.query(q, 3, "cie2000")
    before = {name: id(value) for name, value in vars(index).items()}
    for method in METHODS:
        for use_numba in (True, False):
            index.snap(q, 3, method, use_numba)
    assert {name: id(value) for name, value in vars(index).items()} == before


@settings(max_examples=300, deadline=None)
@given(
    centre=arrays(np.float64, (3, 3), elements=st.floats(-90, 90, allow_nan=False)),
    spread=st.floats(0.01, 30.0),
    q=_labs(1),
    angles=arrays(np.float64, (3,), elements=st.floats(0.5, 180.0)),
    seed=st.integers(0, 2**31 - 1),
    scale=st.sampled_from([0.0, 0.05, 1.0]),
)
def test_din6175_box_bound_is_a_lower_bound_at_any_angle(centre, spread, q, angles, seed, scale) -> None:
    """Grey and chromatic clusters, both blend branches, any aspecular angle: bound ≤ the exact sums."""
    q = q[0].copy()
    rng = np.random.default_rng(seed)
    centre[:, 0] = np.abs(centre[:, 0])
    centre[:, 1:] *= scale  # scale 0 / 0.05: grey clusters (σ → 1) around a grey or chromatic design
    q[:, 1:] *= rng.choice([scale, 1.0])
    pts = centre[None] + rng.normal(0.0, spread, (30, 3, 3))
    pts[..., 0] = np.abs(pts[..., 0])
    exact = delta_e(q[None], pts, "din6175", aspecular_deg=angles).sum(-1)
    chroma = np.hypot(pts[..., 1], pts[..., 2])
    assert (
        box_bounds(q, pts.min(0), pts.max(0), chroma.max(0), "din6175", alpha=angles) <= exact.min() + 1e-12
    )
    assert np.all(box_bounds(q, pts, pts, chroma, "din6175", alpha=angles) <= exact + 1e-12)
