"""Face/flop/travel fit inside the Lab domain (thesis §3.3.3, docs/design.md erratum 5): every demo
paint fits (one batch), an extrapolated vertex is constrained, and paints that fitted unconstrained are unchanged.

The demo library's flops level off by 110° (flake reflection dies out, the diffuse body remains), so
none of its paints needs the constraint; the extrapolation case is a measured dark red metallic whose
lightness is still falling at 110°, where the unconstrained vertex would lie below L* = 0."""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

from station.formulate import demo_library
from station.formulate.library import Library
from station.model import AspecularMeasurements, fit_fftg
from station.model.domain import FACE_ANGLE_DEG, LAB_HI, LAB_LO, TRAVEL_MAX_DEG, lab_within
from station.model.fit import fit_fftg_batch


def _measurements(lib: Library, i: int) -> AspecularMeasurements:
    order = np.argsort(lib.angles_deg)
    angles = tuple(float(lib.angles_deg[j]) for j in order)
    return AspecularMeasurements(angles, lib.lab[i][order], float(lib.gloss_gu[i]))


def _design_matrix(angles: np.ndarray, tc: float) -> np.ndarray:
    """[s², 1 − s²] per angle, s = (θ_c − min(θ, θ_c)) / (θ_c − 15°), written out here (eq 3.3.4)."""
    s = (tc - np.minimum(np.abs(angles), tc)) / (tc - FACE_ANGLE_DEG)
    return np.stack([s**2, 1.0 - s**2], axis=1)


def _cost(m: AspecularMeasurements, face, flop, tc: float) -> float:
    a = _design_matrix(np.asarray(m.angles_deg), tc)
    model = a @ np.stack([np.asarray(face), np.asarray(flop)])
    return float(np.sum((model - np.asarray(m.lab)) ** 2))


def test_every_demo_paint_fits_inside_the_bound() -> None:
    """All 6000 demo paints in one batch: none refused, face and flop inside the bound, and each
    reported residual is the model's miss at the measured angles (recomputed here, eq 3.3.4)."""
    lib = demo_library()
    order = np.argsort(lib.angles_deg)
    angles = np.asarray(lib.angles_deg)[order]
    lab = lib.lab[:, order]
    batch = fit_fftg_batch(tuple(angles), lab, lib.gloss_gu)
    assert len(batch) == len(lib) and not [c for c, e in zip(lib.codes, batch.errors, strict=True) if e]
    assert lab_within(np.stack([batch.face, batch.flop]))
    assert batch.residual_de.shape == (len(lib), len(angles))
    for i in range(len(lib)):
        tc = batch.travel_deg[i]
        if np.isnan(tc):  # a solid: the same Lab at every angle
            np.testing.assert_array_equal(lab[i], np.broadcast_to(batch.face[i], lab[i].shape))
            continue
        assert FACE_ANGLE_DEG < tc <= TRAVEL_MAX_DEG, lib.codes[i]
        model = _design_matrix(angles, tc) @ np.stack([batch.face[i], batch.flop[i]])
        np.testing.assert_allclose(batch.residual_de[i], np.linalg.norm(model - lab[i], axis=1), atol=1e-9)


def test_extrapolated_vertex_is_constrained_and_no_worse_than_brute_force() -> None:
    lab = np.array(
        [[30.0, 40.0, 0.0], [20.0, 35.0, 0.0], [8.0, 25.0, 0.0], [2.0, 15.0, 0.0], [0.2, 10.0, 0.0]]
    )
    m = AspecularMeasurements((15.0, 25.0, 45.0, 75.0, 110.0), lab, 90.0)
    angles = np.asarray(m.angles_deg)
    fit = fit_fftg(m)
    d = fit.design
    assert fit.method == "constrained" and any("constrained fit" in w for w in fit.warnings)
    assert lab_within(np.stack([d.face, d.flop])) and d.travel_deg is not None
    assert FACE_ANGLE_DEG < d.travel_deg <= TRAVEL_MAX_DEG
    # the reported residual is the model's miss at each measured angle
    model = _design_matrix(angles, d.travel_deg) @ np.stack([d.face, d.flop])
    np.testing.assert_allclose(fit.residual_de, np.linalg.norm(model - lab, axis=1), atol=1e-9)
    ours = _cost(m, d.face, d.flop, d.travel_deg)
    # brute force 1: θ_clamp on a 0.05° grid, the closed-form (unconstrained) face/flop at each θ,
    # keeping only those inside the bound
    best_free = np.inf
    for tc in np.arange(FACE_ANGLE_DEG + 0.05, TRAVEL_MAX_DEG + 1e-9, 0.05):
        coef, *_ = np.linalg.lstsq(_design_matrix(angles, tc), lab, rcond=None)
        if lab_within(coef):
            best_free = min(best_free, _cost(m, coef[0], coef[1], tc))
    # brute force 2: θ_clamp on a 0.5° grid, scipy's bounded linear least squares at each θ
    best_box = np.inf
    for tc in np.arange(FACE_ANGLE_DEG + 0.5, TRAVEL_MAX_DEG + 1e-9, 0.5):
        a = _design_matrix(angles, tc)
        coef = np.stack([lsq_linear(a, lab[:, c], bounds=(LAB_LO[c], LAB_HI[c])).x for c in range(3)], axis=1)
        best_box = min(best_box, _cost(m, coef[0], coef[1], tc))
    assert ours <= best_free + 1e-9
    assert ours <= best_box + 1e-9
    assert max(fit.residual_de) < 5.0


def test_paints_inside_the_bound_keep_the_unconstrained_fit() -> None:
    lib = demo_library()
    rows = np.random.default_rng(18).choice(len(lib), 500, replace=False)
    checked = 0
    for i in rows:
        m = _measurements(lib, int(i))
        fit = fit_fftg(m)
        if fit.method == "constrained":
            continue
        checked += 1
        assert not any("constrained" in w for w in fit.warnings)
        d = fit.design
        angles, lab = np.asarray(m.angles_deg), np.asarray(m.lab)
        if d.travel_deg is None:  # a solid: the same Lab at every angle
            np.testing.assert_array_equal(lab, np.broadcast_to(d.face, lab.shape))
            continue
        # face/flop are the plain linear least squares at the reported θ_clamp (no bound active)
        coef, *_ = np.linalg.lstsq(_design_matrix(angles, d.travel_deg), lab, rcond=None)
        np.testing.assert_allclose(np.stack([d.face, d.flop]), coef, atol=1e-9)
        # and θ_clamp is the unconstrained optimum: no point of a 1° grid does better
        grid = np.arange(FACE_ANGLE_DEG + 1.0, TRAVEL_MAX_DEG + 1e-9, 1.0)
        best = min(
            _cost(m, c[0], c[1], tc)
            for tc in grid
            for c in [np.linalg.lstsq(_design_matrix(angles, tc), lab, rcond=None)[0]]
        )
        assert _cost(m, d.face, d.flop, d.travel_deg) <= best + 1e-9
    assert checked > 480


def test_three_angle_closed_form_vertex_beyond_the_bound_is_constrained() -> None:
    lab = np.array([[67.2, -1.25, -5.6], [40.0, -1.45, -6.7], [1.0, -0.81, -4.1]])
    m = AspecularMeasurements((15.0, 45.0, 110.0), lab, 60.0)
    angles = np.asarray(m.angles_deg)
    # the exact parabola through L* (eq 3.3.4) has its vertex below L* = 0
    xa, xb, xc = np.polyfit(angles, lab[:, 0], 2)
    assert xc - xb**2 / (4 * xa) < 0.0
    fit = fit_fftg(m)
    d = fit.design
    assert fit.method == "constrained" and lab_within(np.stack([d.face, d.flop]))
    best = np.inf
    for tc in np.arange(FACE_ANGLE_DEG + 0.05, TRAVEL_MAX_DEG + 1e-9, 0.05):
        coef, *_ = np.linalg.lstsq(_design_matrix(angles, tc), lab, rcond=None)
        if lab_within(coef):
            best = min(best, _cost(m, coef[0], coef[1], tc))
    assert d.travel_deg is not None
    assert _cost(m, d.face, d.flop, d.travel_deg) <= best + 1e-9
