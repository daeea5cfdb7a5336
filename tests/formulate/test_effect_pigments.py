"""Effect physics a colourist recognises: pearls show their complementary colour off-specular, and −15°
differs from +15° as on a real multi-angle instrument.

Independent expectations: the Airy formula of a single thin film (s and p, oblique incidence) integrated
over diffuse light by quadrature instead of colour-science's transfer matrix; Snell's law by hand for the
flake tilts; a root search for the angle whose flakes are tilted as much as −15°'s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from station.formulate import colorants as C
from station.model import FaceFlopTravelGloss
from station.model.angles import flake_equivalent_aspecular, flake_tilt_deg

DB = C.default_database()
INTERFERENCE = ("interference_blue", "interference_green", "interference_red", "interference_gold")
#: CIELAB hue angles of complementary colours (R and 1 − R) are not exactly opposite: the space is not linear
#: in reflectance and the white point is not at the centre of every hue's chroma range.
COMPLEMENT_TOLERANCE_DEG = 60.0
LIGHT_BASE = {"white_tio2": 0.10}  # L*110 ≈ 84
DARK_BASE = {"white_tio2": 0.02, "black_carbon": 0.004}  # a dark grey, L*110 ≈ 44


def _airy(beta: float, lam: np.ndarray, n_film: np.ndarray, d_nm: float, n1: float = 1.5) -> np.ndarray:
    """Unpolarised reflectance of one film (n_film, thickness d) between two media n1, light at beta (rad)."""
    sin_t = n1 * math.sin(beta) / n_film
    cos_t = np.sqrt(1.0 - sin_t**2)
    cos_b = math.cos(beta)
    out = np.zeros_like(lam)
    for r in (
        (n1 * cos_b - n_film * cos_t) / (n1 * cos_b + n_film * cos_t),
        (n_film * cos_b - n1 * cos_t) / (n_film * cos_b + n1 * cos_t),
    ):
        two_delta = 4 * np.pi * n_film * d_nm * cos_t / lam
        out += (2 * r**2 - 2 * r**2 * np.cos(two_delta)) / (1 + r**4 - 2 * r**2 * np.cos(two_delta)) / 2
    return out


def _diffuse_airy(name: str) -> np.ndarray:
    """r̄(λ): the two-faced platelet's reflectance for Lambertian light, ∫ R sin 2β dβ (0–90°) by quadrature."""
    tf = DB.colorants[DB.names.index(name)].flake.thin_film  # type: ignore[union-attr]
    lam = C.WAVELENGTHS_NM
    assert tf is not None
    n_film = tf.cauchy_a + tf.cauchy_b_nm2 / lam**2
    out = np.empty(lam.size)
    for k in range(lam.size):

        def faces(b: float, k: int = k) -> float:
            one = _airy(b, lam[k : k + 1], n_film[k : k + 1], tf.thickness_nm)[0]
            return 2 * one / (1 + one) * math.sin(2 * b)

        out[k] = quad(faces, 0.0, math.pi / 2, limit=200)[0]  # ∫ sin 2β dβ = 1
    return out


def _hue(lab: np.ndarray) -> np.ndarray:
    return np.degrees(np.arctan2(lab[..., 2], lab[..., 1])) % 360.0


@pytest.mark.parametrize("name", [*INTERFERENCE, "pearl_white"])
def test_body_seen_through_the_platelets_is_filtered_by_their_transmission(name: str) -> None:
    r_bar = _diffuse_airy(name)
    flake = DB.colorants[DB.names.index(name)].flake
    assert flake is not None and flake.thin_film is not None
    np.testing.assert_allclose(flake.thin_film.diffuse_reflectance(), r_bar, atol=2e-3)
    c = DB.vector({name: 0.08, "white_tio2": 0.1})
    area = 1 - math.exp(-DB.colorants[DB.names.index(name)].flake.coverage_per_fraction * 0.08)  # type: ignore[union-attr]
    want = 1 - area * (1 - (1 - r_bar) ** 2)  # down and up through a film that transmits 1 − r̄
    np.testing.assert_allclose(C.body_filter(c, DB), want, atol=2e-3)


@pytest.mark.parametrize("base", [LIGHT_BASE, DARK_BASE, {}], ids=["light", "dark", "binder"])
@pytest.mark.parametrize("name", INTERFERENCE)
def test_interference_pigments_show_their_complementary_colour_at_the_flop(name: str, base: dict) -> None:
    lab = C.predict_lab(DB.vector({name: 0.08, **base}), (15.0, 110.0), DB)
    chroma = np.hypot(lab[:, 1], lab[:, 2])
    assert chroma[1] > 0.5  # C*110 was 0.0 with a neutral platelet albedo
    apart = abs((_hue(lab[0]) - _hue(lab[1]) + 180.0) % 360.0 - 180.0)
    assert apart >= 180.0 - COMPLEMENT_TOLERANCE_DEG, (name, _hue(lab))


@pytest.mark.parametrize("name", INTERFERENCE)
def test_the_face_keeps_the_airy_reflection_hue(name: str) -> None:
    lab = C.predict_lab(DB.vector({name: 0.08, "black_carbon": 0.005}), (15.0,), DB)[0]
    tf = DB.colorants[DB.names.index(name)].flake.thin_film  # type: ignore[union-attr]
    lam = C.WAVELENGTHS_NM
    n = 1.5  # the light meets the flakes that serve 15° at β = (φ_i′ + φ_v′)/2 ≈ 23.8° inside the film
    beta = (math.asin(math.sin(math.radians(45)) / n) + math.asin(math.sin(math.radians(30)) / n)) / 2
    assert tf is not None
    one = _airy(beta, lam, tf.cauchy_a + tf.cauchy_b_nm2 / lam**2, tf.thickness_nm)
    airy = C.lab_from_reflectance(2 * one / (1 + one))
    assert abs((_hue(lab) - _hue(airy) + 180.0) % 360.0 - 180.0) < 15.0


def test_minus_15_is_lighter_than_plus_15_by_the_flake_tilts() -> None:
    n = 1.5
    phi_i = math.asin(math.sin(math.radians(45)) / n)
    for theta, view in ((-15.0, 60.0), (15.0, 30.0)):
        alpha = (phi_i - math.asin(math.sin(math.radians(view)) / n)) / 2  # Snell by hand
        assert C.flake_geometry((theta,)).tilt[0] == pytest.approx(alpha, abs=1e-12)
        assert math.radians(float(flake_tilt_deg(theta))) == pytest.approx(alpha, abs=1e-12)
    silver = C.predict_lab(DB.vector({"alu_coarse": 0.08, "black_carbon": 0.005}), (-15.0, 15.0), DB)
    assert silver[0, 0] > silver[1, 0] + 2.0  # MA-T12 panels: L* 67.9 at 45as-15 against 63.7 at 45as15
    for name in ("pearl_white", "alu_bright"):
        lab = C.predict_lab(DB.vector({name: 0.1}), (-15.0, 15.0), DB)
        assert lab[0, 0] > lab[1, 0]


def test_equivalent_angle_has_the_same_tilt_and_the_simulator_uses_it() -> None:
    from simulators.physics import SpectroPhysics
    from station.model.spectra import reflectance_to_lab

    root = brentq(lambda t: float(flake_tilt_deg(t)) + float(flake_tilt_deg(-15.0)), 0.0, 45.0, xtol=1e-12)
    assert float(flake_equivalent_aspecular(-15.0)) == pytest.approx(root, abs=1e-9)
    assert flake_equivalent_aspecular([0.0, 15.0, 110.0]).tolist() == [0.0, 15.0, 110.0]
    design = FaceFlopTravelGloss((78.0, -0.8, -1.5), (32.0, -0.4, -4.5), 80.0, 88.0)
    lab = reflectance_to_lab(SpectroPhysics(design=design).true_reflectance((-15.0, 15.0, 45.0)))
    np.testing.assert_allclose(lab, design.lab_at(np.array([root, 15.0, 45.0])), atol=0.05)
    assert lab[0, 0] > lab[1, 0] + 2.0
