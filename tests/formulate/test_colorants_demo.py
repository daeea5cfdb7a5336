"""Colorant model (Kubelka–Munk + Saunderson) against closed forms, and the demo library."""

from __future__ import annotations

import time

import numpy as np
import pytest

from station.formulate import colorants as C
from station.formulate.demo import DEMO_NAME, demo_library, generate_library
from station.formulate.errors import FormulateInputError
from station.model.spectra import reflectance_to_lab

DB = C.default_database()
A3 = (15.0, 45.0, 110.0)


def test_single_pigment_reflectance_matches_closed_form() -> None:
    c = DB.vector({"white_tio2": 0.3})
    white = DB.colorants[DB.names.index("white_tio2")]
    k = C.K_BINDER + 0.3 * white.k
    s = C.S_BINDER + 0.3 * white.s
    r_inf = 1 + k / s - np.sqrt((k / s) ** 2 + 2 * k / s)  # Kubelka–Munk, opaque layer
    assert np.allclose((1 - r_inf) ** 2 / (2 * r_inf), k / s)  # the K/S inversion holds
    k1 = 0.0502  # Fresnel reflectance of n = 1.5 at 45° (hand value: mean of s 9.20 % and p 0.85 %)
    assert C.K1_SAUNDERSON == pytest.approx(k1, abs=1e-4)
    want = (1 - C.K1_SAUNDERSON) * 0.4 * r_inf / (1 - 0.6 * r_inf)  # Saunderson, specular excluded
    got = C.predict_reflectance(c, A3)
    assert np.allclose(got, want[None, :], rtol=1e-12)


def test_fast_lab_equals_the_model_conversion() -> None:
    rng = np.random.default_rng(0)
    r = rng.uniform(0.0, 1.0, (50, 31))
    assert np.allclose(C.lab_from_reflectance(r), reflectance_to_lab(r), atol=1e-9)


def test_solids_are_angle_independent_and_metallics_flop() -> None:
    solid = C.predict_lab(DB.vector({"white_tio2": 0.1, "red_pr": 0.03}), A3)
    assert np.array_equal(solid[0], solid[1]) and np.array_equal(solid[1], solid[2])
    met = C.predict_lab(DB.vector({"alu_coarse": 0.1, "blue_pb": 0.02}), A3)
    assert met[0, 0] > met[1, 0] + 10 > met[2, 0] + 20
    fine = C.predict_lab(DB.vector({"alu_fine": 0.1}), A3)
    coarse = C.predict_lab(DB.vector({"alu_coarse": 0.1}), A3)
    assert coarse[0, 0] - coarse[2, 0] > fine[0, 0] - fine[2, 0]  # coarse flakes: stronger flop


def test_interference_pigment_shifts_hue_with_angle() -> None:
    lab = C.predict_lab(DB.vector({"interference_gold": 0.1, "black_carbon": 0.01}), (15.0, 45.0, 75.0))
    hue = np.degrees(np.arctan2(lab[:, 2], lab[:, 1])) % 360
    assert abs((hue[0] - hue[2] + 180) % 360 - 180) > 2  # the face's band sits at shorter λ than the flop's


@pytest.mark.parametrize(
    "recipe",
    [
        {"white_tio2": -0.1},
        {"black_carbon": 0.5},
        {"alu_coarse": 0.2, "pearl_white": 0.1},
        {"unobtainium": 0.1},
    ],
)
def test_infeasible_recipes_are_refused(recipe: dict) -> None:
    with pytest.raises(FormulateInputError):
        DB.check(DB.vector(recipe))


def test_demo_library_is_reproducible_labelled_and_cached() -> None:
    t0 = time.perf_counter()
    lib = demo_library()
    first = time.perf_counter() - t0
    assert len(lib) == 6000 and int(np.sum(lib.types == "solid")) == 3000
    assert lib.synthetic and "SYNTHETIC" in lib.name and lib.name == DEMO_NAME
    assert all(code.startswith("SYN-") for code in lib.codes) and len(set(lib.codes)) == 6000
    assert lib.recipes is not None and lib.recipes.shape == (6000, len(DB.names))
    DB.check(lib.recipes)
    again = generate_library(300, 200, 100)  # same seed, smaller: the first rows differ, so compare itself
    assert np.array_equal(again.lab, generate_library(300, 200, 100).lab)
    demo_library.cache_clear()
    t1 = time.perf_counter()
    cached = demo_library()  # from the .npz written by the first call
    load = time.perf_counter() - t1
    assert np.array_equal(cached.lab, lib.lab) and cached.codes.tolist() == lib.codes.tolist()
    assert load < max(0.5, first)
    recomputed = C.predict_lab(lib.recipes[:50], lib.angles_deg)
    assert np.allclose(recomputed, lib.lab[:50])  # every paint's colour is its recipe's prediction


def test_munsell_library_is_real_and_ordered() -> None:
    from station.formulate.munsell import munsell_library
    from station.formulate.snap import color_snap

    lib = munsell_library()
    assert len(lib) == 2734 and set(lib.types) == {"solid"} and not lib.synthetic
    assert len(set(lib.codes)) == len(lib)
    value = np.array([float(c.split()[2].split("/")[0]) for c in lib.codes])
    lab = lib.angle_columns()
    assert np.array_equal(lab[:, 0], lab[:, 2])
    five = lab[value == 5.0, 0, 0]
    assert 47.0 < five.min() and five.max() < 54.0  # Munsell value 5 is mid-grey lightness (L* ≈ 51)
    hue = np.degrees(np.arctan2(lab[:, 0, 2], lab[:, 0, 1])) % 360
    red = np.array([c.split()[1] == "5R" for c in lib.codes]) & (value == 5.0)
    assert np.all((hue[red] < 40) | (hue[red] > 340))
    result = color_snap(lib, lab[100], k=1)
    assert result.matches[0].code == lib.codes[100]


def test_demo_metallics_blend_the_aluminium_grades_without_traces() -> None:
    lib = demo_library()
    assert lib.recipes is not None and lib.colorant_names is not None
    grades = [lib.colorant_names.index(g) for g in ("alu_bright", "alu_coarse", "alu_fine")]
    alu = lib.recipes[lib.types == "metallic"][:, grades]
    total = alu.sum(1)
    assert np.all((total > 0.02 - 1e-9) & (total < 0.15 + 1e-9))  # 2–12 % aluminium, bright silvers 6–15 %
    share = alu / total[:, None]
    assert np.all((share == 0.0) | (share >= 0.05 - 1e-12))  # no trace grade in a batch
    assert np.mean(np.sum(share > 0, axis=1) >= 2) > 0.5  # most metallics are blends
    fi = lib.indices()["flop"][lib.types == "metallic"]
    hard, coarse, soft = share[:, 0] >= 0.9, share[:, 1] >= 0.9, share[:, 2] >= 0.5
    # the grades' own order (silver dollar flops hardest, fine softest) carries over to the blends
    assert np.nanmean(fi[hard]) > np.nanmean(fi[coarse]) > np.nanmean(fi[soft])
