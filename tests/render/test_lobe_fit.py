"""Lobe basis, sample geometries and the non-negative weight fits (thesis eqs 2.3.1–2.4.2)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from scipy.optimize import nnls

from station.errors import InputError
from station.render import lobe_fit as lf
from station.render.lobes import LobeBasis, default_basis, sample_geometries
from station.render.weights import LobeWeights

BASIS = LobeBasis((2.0, 10.0, 60.0, 400.0, 2500.0))


def exact_brdf(k_d: np.ndarray, k_dd: np.ndarray, n: float, rho_s: float) -> lf.DesignedBRDF:
    """A designed BRDF that the lobe model represents exactly (colour from known weights)."""
    cos_a = np.cos(np.radians(lf.ALPHA_GRID_DEG))
    rho = np.pi * (k_d + BASIS.lobes(cos_a) @ k_dd)
    return lf.DesignedBRDF(rho, n, rho_s, "exact")


def test_sample_geometries_are_documented_angles() -> None:
    g = sample_geometries()
    # α recomputed from the vectors equals the nominal grid, every view is above the horizon.
    assert np.all(g.n_dot_v >= np.sin(np.radians(3.0)) - 1e-12)
    nominal = np.concatenate([np.asarray(lf.COLOUR_ALPHAS_DEG), np.asarray(lf.GLOSS_ALPHAS_DEG)])
    assert np.min(np.abs(g.alpha_deg[:, None] - nominal[None, :]), axis=1).max() < 1e-6
    assert np.allclose(np.linalg.norm(g.view, axis=1), 1.0)
    # 45as15 and 45as110 (in plane, towards the light) are among the colour rows.
    for alpha in (15.0, 110.0):
        hit = (~g.gloss) & np.isclose(g.n_dot_l, np.cos(np.radians(45))) & np.isclose(g.alpha_deg, alpha)
        assert np.any(hit & (np.abs(g.view[:, 1]) < 1e-12))
    # Cells tile the polar cap: gloss rows of one incidence cover 2π(1 − cos 45°) (last edge 40 + 10/2).
    rows = g.gloss & np.isclose(g.n_dot_l, np.cos(np.radians(20.0)))
    assert np.sum(g.weight[rows] ** 2) == pytest.approx(2 * np.pi * (1 - np.cos(np.radians(45.0))), rel=1e-9)


def test_basis_validation() -> None:
    assert LobeBasis((100.0, 3.0)).exponents == (3.0, 100.0)
    for bad in ((), (0.1,), (np.nan,), tuple(range(1, 14))):
        with pytest.raises(InputError):
            LobeBasis(bad)


@pytest.mark.parametrize("method", lf.METHODS)
def test_exactly_representable_brdf_is_recovered(method: str) -> None:
    k_d = np.array([0.05, 0.02, 0.01])
    k_dd = np.zeros((5, 3))
    k_dd[1] = [0.20, 0.10, 0.05]
    k_dd[3] = [0.30, 0.30, 0.30]
    brdf = exact_brdf(k_d, k_dd, n=400.0, rho_s=0.1)
    rep = lf.fit_targets(lf.targets_from_brdfs([brdf]), BASIS, method)
    w = rep.weights(0)
    assert w.k_d == pytest.approx(k_d, abs=2e-4)
    assert w.k_dd == pytest.approx(k_dd, abs=2e-3)
    assert w.k_g == pytest.approx([0, 0, 0, 0.1 * 401 / (2 * np.pi), 0], abs=1e-3)
    assert lf.fit_error_de([brdf], rep)[0] < 0.05


def test_enumeration_equals_lawson_hanson_and_is_optimal() -> None:
    rng = np.random.default_rng(7)
    part = lf.fit_problem(BASIS).colour
    b = rng.normal(size=(40, part.a.shape[0], 3)) * 0.2 + part.a @ rng.random(int(part.a.shape[1]))[:, None]
    x_enum = (
        lf._solve_enum(part, np.einsum("rk,drc->kdc", part.q, b).reshape(part.q.shape[1], -1))
        .reshape(part.q.shape[1], b.shape[0], 3)
        .transpose(1, 0, 2)
    )
    for i in range(b.shape[0]):
        for c in range(3):
            ref = nnls(part.a, b[i, :, c])[0]
            r_enum = np.linalg.norm(part.a @ x_enum[i, :, c] - b[i, :, c])
            r_ref = np.linalg.norm(part.a @ ref - b[i, :, c])
            assert r_enum <= r_ref * (1 + 1e-9) + 1e-12
            assert x_enum[i, :, c] == pytest.approx(ref, abs=1e-7)
    assert np.all(x_enum >= 0.0)
    d_all = np.einsum("rk,drc->kdc", part.q, b).reshape(part.q.shape[1], -1)
    assert lf._solve_kkt(part, d_all) == pytest.approx(lf._solve_enum(part, d_all), abs=1e-9)
    assert lf._solve_kkt(part, d_all, rounds=0) == pytest.approx(lf._solve_enum(part, d_all), abs=1e-9)


def test_database_fits_are_non_negative_and_nnls_beats_clamped(design_db) -> None:
    brdfs = [lf.designed_brdf(d) for d in design_db]
    targets = lf.targets_from_brdfs(brdfs)
    errors = {}
    for method in ("auto", "kkt", "enum", "nnls", "clamped-lsq"):
        rep = lf.fit_targets(targets, BASIS, method)
        assert np.all(rep.k_d >= 0) and np.all(rep.k_dd >= 0) and np.all(rep.k_g >= 0)
        errors[method] = lf.fit_error_de(brdfs, rep)
    for method in ("auto", "kkt", "enum"):
        assert np.allclose(errors[method], errors["nnls"], atol=1e-6)
    # The thesis's reason for linear programming: clamping least squares accumulates error.
    assert errors["clamped-lsq"].mean() > errors["nnls"].mean()
    assert np.all(errors["clamped-lsq"] >= errors["nnls"] - 1e-6)


def test_lp_l1_is_time_limited_and_feasible(design_db) -> None:
    brdfs = [lf.designed_brdf(d) for d in design_db[:4]]
    t0 = time.perf_counter()
    rep = lf.fit_targets(lf.targets_from_brdfs(brdfs), BASIS, "lp-l1")
    assert time.perf_counter() - t0 < 4 * 4 * (lf.LP_TIME_LIMIT_S + 0.2)
    assert np.all(rep.k_dd >= 0) and np.all(rep.k_g >= 0)
    assert np.all(lf.fit_error_de(brdfs, rep) < 40)


@pytest.mark.parametrize("method", lf.METHODS)
def test_stability_where_methods_fail(method: str) -> None:
    from station.model import FaceFlopTravelGloss

    designs = [
        FaceFlopTravelGloss((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), None, 95.0, "black"),
        FaceFlopTravelGloss((1.0, 0.0, 0.0), (0.2, 0.0, 0.0), 110.0, 100.0, "near-black-mirror"),
        FaceFlopTravelGloss((120.0, 0.0, 0.0), (20.0, 0.0, 0.0), 180.0, 0.0, "extreme-travel-matte"),
        FaceFlopTravelGloss((90.0, 0.0, 0.0), (10.0, 0.0, 0.0), 15.01, 50.0, "travel-at-face"),
    ]
    near_duplicate = LobeBasis((4.0, 4.0 * (1 + 1e-9), 60.0, 60.0001, 2500.0, 2500.0))
    for basis in (BASIS, near_duplicate):
        t0 = time.perf_counter()
        rep = lf.fit_designs(designs, basis, method)
        assert time.perf_counter() - t0 < 10.0
        for arr in (rep.k_d, rep.k_dd, rep.k_g):
            assert np.all(np.isfinite(arr)) and np.all(arr >= 0.0)
        largest = max(float(np.max(a)) for a in (rep.k_d, rep.k_dd, rep.k_g))
        if method == "clamped-lsq" and basis is near_duplicate:
            # The thesis's rejected baseline: least squares splits near-duplicate lobes into huge
            # opposite weights and clamping keeps the positive half. Documented, not hidden.
            assert largest > 1e4
        else:
            assert largest < 1e4  # no blow-up from the ill-conditioned columns
        black = rep.weights(0)
        assert np.max(black.k_d) < 1e-3 and np.max(black.k_dd) < 1e-2


def test_fit_design_default_basis_and_errors(design_db) -> None:
    w = lf.fit_design(design_db[8])
    assert isinstance(w, LobeWeights)
    assert w.exponents == default_basis().exponents
    with pytest.raises(InputError):
        lf.fit_design(design_db[0], method="simplex")
    with pytest.raises(InputError):
        lf.fit_targets(lf.sample_targets(design_db[:1]), BASIS, "enum", gloss_form="none")


def test_designed_lobe_is_the_model_mapping() -> None:
    from station.model import FaceFlopTravelGloss
    from station.model.gloss import lobe_from_gloss

    for gu in (37.5, 93.3, 99.5):
        brdf = lf.designed_brdf(FaceFlopTravelGloss((60.0, 0.0, 0.0), (30.0, 0.0, 0.0), 60.0, gu))
        ref = lobe_from_gloss(gu)
        assert brdf.phong_exponent == pytest.approx(ref.phong_exponent, rel=1e-4)
        assert brdf.specular_albedo == pytest.approx(ref.specular_albedo, rel=1e-9)
        targets = lf.sample_targets([FaceFlopTravelGloss((60.0, 0.0, 0.0), (30.0, 0.0, 0.0), 60.0, gu)])
        assert float(targets.phong_exponent[0]) == brdf.phong_exponent


def test_designed_brdf_closed_forms(design_db) -> None:
    from station.model.colorimetry import lab_to_linear_srgb

    d = design_db[16]  # blue metallic
    brdf = lf.designed_brdf(d)
    assert brdf.rho(np.array([45.0])) == pytest.approx(lab_to_linear_srgb(d.lab_at([45.0])), abs=1e-9)
    # A constant environment of radiance 1: the gloss term of a narrow lobe integrates to ρ_s.
    n = brdf.phong_exponent
    psi = np.linspace(0, np.pi / 2, 200001)
    integral = np.trapezoid(brdf.gloss_cos(np.cos(psi)) * 2 * np.pi * np.sin(psi), psi)
    assert integral == pytest.approx(brdf.specular_albedo * (1 - 0.0 ** (n + 1)), rel=1e-4)
    assert np.all(brdf.brdf_cos(np.array([-0.2]), np.array([1.0])) == 0.0)


@pytest.fixture(scope="module")
def design_db():
    from station.render.design_db import design_database

    return design_database()


def test_vectorised_sampling_equals_the_model(design_db) -> None:
    targets = lf.sample_targets(design_db)
    ref = lf.targets_from_brdfs([lf.designed_brdf(d) for d in design_db])
    assert targets.rho == pytest.approx(ref.rho, rel=1e-9, abs=1e-12)
    assert targets.phong_exponent == pytest.approx(ref.phong_exponent)


def test_horizon_factors_closed_forms() -> None:
    from station.render.lobes import horizon_factors

    for e in (1.0, 2.0, 10.0, 300.0):
        g, h = horizon_factors(e, np.array([1.0, 0.0, -1.0]))
        assert g[0] == pytest.approx((e + 1) / (e + 2), rel=1e-4)  # lobe about N: ∫p cos = (E+1)/(E+2)
        assert h == pytest.approx([1.0, 0.5, 0.0], abs=1e-9)  # half the lobe above a grazing horizon
        assert g[2] == pytest.approx(0.0, abs=1e-12)
    # brute force on the sphere for one oblique case
    e, c = 5.0, 0.4
    rng = np.random.default_rng(1)
    w = rng.normal(size=(400000, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    r = np.array([np.sqrt(1 - c * c), 0.0, c])
    p = (e + 1) / (2 * np.pi) * np.maximum(w @ r, 0) ** e
    g_mc = np.mean(p * np.maximum(w[:, 2], 0)) * 4 * np.pi
    h_mc = np.mean(p * (w[:, 2] > 0)) * 4 * np.pi
    g, h = horizon_factors(e, c)
    assert float(g) == pytest.approx(g_mc, rel=0.02)
    assert float(h) == pytest.approx(h_mc, rel=0.02)


def test_perceptual_fit_weighs_the_dark_flop(design_db) -> None:
    """The default fit weighs each row by (target)^(-2/3) (dL*/dY ∝ Y^(-2/3)): against the radiance-
    weighted NNLS it must lower (measured 0.86×) the CIEDE2000 error where a silver's flop is dark (α ≥ 60°) and the
    database's mean RMS error (eq 2.3.4's Error), and be the optimum of its own weighted problem (KKT)."""
    from station.model.colorimetry import linear_srgb_to_lab
    from station.model.difference import delta_e
    from station.render.design_db import design_classes
    from station.render.lobes import basis_for_count, basis_table

    assert lf.METHODS[0] == "perceptual"
    brdfs = [lf.designed_brdf(d) for d in design_db]
    targets = lf.targets_from_brdfs(brdfs)
    # the basis chosen on this database (eq 2.3.4): the default one is calibrated on the demo library
    basis = basis_for_count(int(basis_table()["default_lobes"]))
    perc, rad = lf.fit_targets(targets, basis), lf.fit_targets(targets, basis, "auto")
    assert perc.method == "perceptual"
    ref = linear_srgb_to_lab(lf.designed_reflectance(brdfs))
    g = lf.sample_geometries()
    flop = (g.alpha_deg >= 60.0) & ~g.gloss
    silvers = list(design_classes()["silver"])
    de = {
        k: delta_e(ref, linear_srgb_to_lab(lf.fitted_reflectance(rep)), "cie2000")
        for k, rep in (("perc", perc), ("rad", rad))
    }
    assert de["perc"][silvers][:, flop].mean() < 0.9 * de["rad"][silvers][:, flop].mean()
    assert lf.fit_error_de(brdfs, perc).mean() < lf.fit_error_de(brdfs, rad).mean()
    # KKT of min ‖S(A x − b)‖², x ≥ 0, built here from the documented weights for one silver's red
    prob = lf.fit_problem(basis)
    i = silvers[0]
    rows = prob.colour_rows
    value = targets.rho[i, prob.alpha_index[rows], 0] * g.n_dot_l[rows] / np.pi
    s = np.maximum(value, lf.PERCEPTUAL_FLOOR) ** (-2.0 / 3.0)
    a = prob.colour.a * s[:, None]
    b = value * g.weight[rows] * s
    assert perc.k_a is not None
    x = np.concatenate([[perc.k_d[i, 0]], perc.k_dd[i, :, 0], [perc.k_a[i, 0]]])
    grad = a.T @ (a @ x - b)
    scale = np.abs(a.T @ b).max()
    assert np.all(grad >= -1e-8 * scale)
    assert np.all(np.abs(grad[x > 0]) <= 1e-8 * scale)
