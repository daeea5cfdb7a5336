"""The effect-pigment colorant model against closed forms, and the batch / tinting / gamut helpers.

Independent expectations: Snell and Fresnel by hand, the Beckmann normalisation by quadrature, the
Airy (single thin film) reflectance instead of colour-science's transfer matrix, the batch arithmetic
by hand; the formulation bars against the model's own prediction of the returned recipe.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from station.formulate import colorants as C
from station.formulate.batch import batch_masses, tinting_additions
from station.formulate.errors import FormulateInputError
from station.formulate.formulation import formulate
from station.formulate.gamut import colorant_gamut
from station.model import FaceFlopTravelGloss
from station.model.examples import BRIGHT_SILVER
from station.model.spectra import reflectance_to_lab

DB = C.default_database()
A3 = (15.0, 45.0, 110.0)


def test_every_parameter_comes_from_the_one_labelled_data_file() -> None:
    data = C.colorant_data()
    assert data["synthetic"] is True and DB.synthetic
    assert [r["name"] for r in data["colorants"]] == list(DB.names)
    for rec, col in zip(data["colorants"], DB.colorants, strict=True):
        assert rec["doc"] and col.doc == rec["doc"]  # documented pigment by pigment
        np.testing.assert_array_equal(col.k, rec["k"])
        assert (col.flake is not None) == ("flake" in rec)
    assert json.dumps(data)  # plain JSON
    assert C.N_BINDER == data["model"]["n_binder"] and DB.flake_depth == data["model"]["flake_depth"]


def test_flake_geometry_by_snell() -> None:
    g = C.flake_geometry((15.0, 45.0, 110.0))
    n = 1.5
    phi_i = math.asin(math.sin(math.radians(45)) / n)
    for k, theta in enumerate((15.0, 45.0, 110.0)):
        phi_v = math.asin(math.sin(math.radians(45 - theta)) / n)
        assert g.tilt[k] == pytest.approx((phi_i - phi_v) / 2, abs=1e-12)
        assert g.incidence[k] == pytest.approx(abs(phi_i + phi_v) / 2, abs=1e-12)
    assert math.degrees(g.tilt[0]) == pytest.approx(4.3, abs=0.05)  # 15°: flakes tilted ~4°
    assert math.degrees(g.tilt[2]) == pytest.approx(32.6, abs=0.1)  # 110°: ~33°, far in the tail


def test_beckmann_density_is_normalised() -> None:
    m = 0.18
    a = np.linspace(0.0, math.pi / 2 - 1e-6, 200001)
    integrand = C.beckmann(a, m) * np.cos(a) * 2 * math.pi * np.sin(a)  # ∫ D cos α dω
    assert float(np.sum(integrand) * (a[1] - a[0])) == pytest.approx(1.0, abs=1e-3)


def test_thin_film_matches_the_airy_formula() -> None:
    pearl = DB.colorants[DB.names.index("interference_blue")]
    tf = pearl.flake.thin_film  # type: ignore[union-attr]
    lam = C.WAVELENGTHS_NM
    assert tf is not None
    n1, n2 = 1.5, tf.cauchy_a + tf.cauchy_b_nm2 / lam**2
    r12 = (n1 - n2) / (n1 + n2)  # normal incidence, binder | TiO2 | binder: r23 = −r12
    delta = 2 * math.pi * n2 * tf.thickness_nm / lam
    one = (2 * r12**2 - 2 * r12**2 * np.cos(2 * delta)) / (1 + r12**4 - 2 * r12**2 * np.cos(2 * delta))
    want = 2 * one / (1 + one)  # two faces, incoherent
    np.testing.assert_allclose(tf.reflectance(np.array([0.0]))[0], want, atol=1e-9)
    # at oblique incidence the band moves to shorter wavelengths (2 n d cos θ_t = const)
    peaks = [lam[np.argmax(tf.reflectance(np.array([math.radians(b)]))[0])] for b in (0.0, 60.0)]
    assert peaks[1] < peaks[0]


def test_flake_term_is_the_hand_radiance_factor_and_exceeds_one() -> None:
    c = DB.vector({"alu_bright": 0.1})
    al = DB.colorants[DB.names.index("alu_bright")].flake
    assert al is not None and al.reflectance is not None
    n = 1.5
    phi_i = math.asin(math.sin(math.radians(45)) / n)
    phi_v = math.asin(math.sin(math.radians(30)) / n)  # 15° aspecular
    alpha = (phi_i - phi_v) / 2
    d = math.exp(-(math.tan(alpha) ** 2) / al.orientation_m**2) / (
        math.pi * al.orientation_m**2 * math.cos(alpha) ** 4
    )

    def fresnel(t: float) -> float:
        tt = math.asin(math.sin(t) / n)
        rs = ((math.cos(t) - n * math.cos(tt)) / (math.cos(t) + n * math.cos(tt))) ** 2
        rp = ((math.cos(tt) - n * math.cos(t)) / (math.cos(tt) + n * math.cos(t))) ** 2
        return (rs + rp) / 2

    transfer = (1 - fresnel(math.radians(45))) * (1 - fresnel(math.radians(30))) / n**2
    area = 1 - math.exp(-al.coverage_per_fraction * 0.1)
    spec = area * al.reflectance * math.pi * d / (4 * math.cos(phi_i) * math.cos(phi_v)) * transfer
    diffuse = area * al.diffuse_albedo * transfer  # nothing above the flakes: no attenuation
    got = C.flake_reflectance(c, (15.0,))[0]
    np.testing.assert_allclose(got, spec + diffuse, rtol=1e-10)
    assert got.min() > 1.0  # a radiance factor above a white diffuser near specular
    lab = C.predict_lab(c, A3)
    np.testing.assert_allclose(lab, reflectance_to_lab(C.predict_reflectance(c, A3)), atol=1e-9)
    assert 110.0 <= lab[0, 0] <= 160.0 and lab[2, 0] < 35.0  # bright face, dark flop


def test_bad_flake_data_is_refused() -> None:
    with pytest.raises(FormulateInputError):
        C.Flake(coverage_per_fraction=-1.0, orientation_m=0.2, reflectance=np.full(31, 0.8))
    with pytest.raises(FormulateInputError):
        C.Flake(coverage_per_fraction=5.0, orientation_m=0.2)  # neither a metal nor a thin film
    with pytest.raises(FormulateInputError):
        C.ThinFilm(cauchy_a=0.9, cauchy_b_nm2=0.0, thickness_nm=100.0)


def test_batch_and_tinting_additions_by_hand() -> None:
    b = batch_masses({"white_tio2": 0.2, "blue_pb": 0.05}, 500.0)
    assert (
        b.colorants_g == {"white_tio2": 100.0, "blue_pb": 25.0} and b.binder_g == 375.0 and b.total_g == 500.0
    )
    # 1000 g at white 0.2 / blue 0.05 / binder 0.75 → blue 0.06: the binder limits growth:
    # M' = 1000 · max(0.2/0.2, 0.05/0.06, 0.75/0.74) = 1013.51 g
    t = tinting_additions({"white_tio2": 0.2, "blue_pb": 0.05}, {"white_tio2": 0.2, "blue_pb": 0.06})
    grow = 0.75 / 0.74
    assert t.new_total_g == pytest.approx(1000 * grow) and not t.remake
    assert t.additions_g["blue_pb"] == pytest.approx(0.06 * 1000 * grow - 50.0)
    assert t.additions_g["white_tio2"] == pytest.approx(0.2 * 1000 * grow - 200.0)
    assert t.binder_g == pytest.approx(0.0, abs=1e-9)
    gone = tinting_additions({"white_tio2": 0.2, "black_carbon": 0.01}, {"white_tio2": 0.2})
    assert gone.remake and "black_carbon" in gone.message
    with pytest.raises(FormulateInputError) as err:
        batch_masses({"white_tio2": 0.2}, -5.0)
    assert err.value.field == "batch_g"


# The showcase designs of the bars (15/45/110°): the README's silver, the bright silver, the thesis's
# Fig 4.6 blue metallic and the viewer's demo red.
README_SILVER = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])
FIG46_BLUE = FaceFlopTravelGloss((60.0, -4.0, -42.0), (18.0, 2.0, -22.0), 55.0, name="blue metallic")
VIEWER_RED = FaceFlopTravelGloss((62.0, 48.0, 30.0), (24.0, 38.0, 18.0), 70.0, 88.0)


@pytest.mark.parametrize(
    ("lab", "max_colorants"),
    [
        (README_SILVER, 5),
        (BRIGHT_SILVER.lab_at(np.array(A3)), 5),
        (FIG46_BLUE.lab_at(np.array(A3)), 5),
        # a red pearl-metallic with a deep flop: within tolerance only with more than the default five
        (VIEWER_RED.lab_at(np.array(A3)), 8),
    ],
    ids=["readme-silver", "bright-silver", "fig46-blue", "viewer-red"],
)
def test_showcase_designs_are_formulable(lab: np.ndarray, max_colorants: int) -> None:
    r = formulate(lab, A3, max_colorants=max_colorants)
    de = C.predict_lab(r.concentrations, A3)
    from station.formulate.de_kernels import cie2000

    np.testing.assert_allclose(r.de_per_angle, cie2000(lab, de), atol=1e-9)  # ΔE of the returned recipe
    assert r.formulable and r.mean_de <= 1.0
    DB.check(r.concentrations)
    d = r.to_dict()
    batch = d["batch"]
    assert isinstance(batch, dict) and batch["total_g"] == 1000.0
    assert sum(batch["colorants_g"].values()) + batch["binder_g"] == pytest.approx(1000.0)


def test_outside_the_gamut_is_refused_with_the_nearest_paint() -> None:
    far = FaceFlopTravelGloss((60.0, 110.0, 0.0), (30.0, 95.0, 0.0), 60.0, 88.0)  # chroma past any colorant
    rep = colorant_gamut(far)
    assert not rep.inside and rep.mean_de > 1.0 and "outside the colorant gamut" in rep.message
    # the nearest paint is what the best recipe makes: its Lab at 15/45/110 is the recipe's prediction
    pred = C.predict_lab(rep.formulation.concentrations, A3)
    near = rep.nearest.lab_at(np.array(A3))
    assert np.max(np.abs(near - pred)) < 3.0  # up to the face/flop/travel fit of the 5 angles
    nearest = rep.to_dict()["nearest_achievable_paint"]
    assert isinstance(nearest, dict) and nearest["face"] == list(rep.nearest.face)
    assert colorant_gamut(BRIGHT_SILVER).inside
