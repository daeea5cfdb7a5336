"""Optics of the synthetic colorant model's effect pigments: the data file, Fresnel, the flake geometry
inside the film, the Beckmann tilt density and the thin-film platelets (SYNTHETIC DATA).

The model using them is :mod:`station.formulate.colorants` (its module docstring, steps 1–3); the
pigments are documented one by one in docs/effect-pigments.md.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.errors import FormulateInputError
from station.model.domain import ILLUMINATION_DEG

WAVELENGTHS_NM: NDArray[np.float64] = np.arange(400.0, 701.0, 10.0)
DATA_FILE = "colorants.json"


@functools.lru_cache(maxsize=1)
def colorant_data() -> dict[str, Any]:
    """The parsed data file ``station/formulate/data/colorants.json`` (every model parameter)."""
    text = resources.files("station.formulate").joinpath("data", DATA_FILE).read_text(encoding="utf-8")
    data: dict[str, Any] = json.loads(text)
    return data


def _constants() -> dict[str, float]:
    return {k: float(v) for k, v in colorant_data()["model"].items()}


K2_SAUNDERSON = _constants()["k2_saunderson"]
K_BINDER = _constants()["k_binder"]
S_BINDER = _constants()["s_binder"]
N_BINDER = _constants()["n_binder"]
GLOSS_CLEAR_GU = _constants()["gloss_clear_gu"]
GLOSS_PER_MATTING = _constants()["gloss_per_matting"]
#: Total pigment mass fraction allowed in a basecoat (the rest is binder).
MAX_TOTAL = _constants()["max_total"]


def fresnel_unpolarised(theta_deg: ArrayLike, n: float = N_BINDER) -> NDArray[np.float64]:
    """Fresnel reflectance (mean of s and p) of light in air meeting a medium of index *n* at
    *theta_deg* (degrees from the normal)."""
    ti = np.radians(np.abs(np.asarray(theta_deg, dtype=np.float64)))
    tt = np.arcsin(np.sin(ti) / n)
    ci, ct = np.cos(ti), np.cos(tt)
    rs = ((ci - n * ct) / (ci + n * ct)) ** 2
    rp = ((ct - n * ci) / (ct + n * ci)) ** 2
    return np.asarray(0.5 * (rs + rp), dtype=np.float64)


#: Saunderson k₁: the coat's Fresnel reflectance at the 45° illumination (≈ 0.050 for n = 1.5).
K1_SAUNDERSON = float(fresnel_unpolarised(ILLUMINATION_DEG))


@dataclass(frozen=True)
class FlakeGeometry:
    """Angles inside the film for aspecular angles θ (module docstring, step 2), all shape (A,), radians.

    ``phi_i``/``phi_v``: internal illumination / viewing angles from the normal (``phi_v`` signed,
    negative on the illuminator's side); ``tilt``: flake tilt α that mirrors one into the other;
    ``incidence``: angle β at which the light meets that flake; ``transfer``: T(45°) T(φ_v) / n²
    (Fresnel transmittances and the radiance n² law); ``path``: 1/cos φ_i′ + 1/cos φ_v′.
    """

    phi_i: NDArray[np.float64]
    phi_v: NDArray[np.float64]
    tilt: NDArray[np.float64]
    incidence: NDArray[np.float64]
    transfer: NDArray[np.float64]
    path: NDArray[np.float64]


def flake_geometry(angles_deg: ArrayLike, n: float = N_BINDER) -> FlakeGeometry:
    """Internal flake geometry for signed aspecular *angles_deg* (degrees, positive towards the illumination;
    −44 ≤ θ ≤ 134 is used, beyond it the view is clamped at grazing)."""
    theta = np.asarray(angles_deg, dtype=np.float64)
    view_air = np.clip(ILLUMINATION_DEG - theta, -89.0, 89.0)  # signed: −15° views at 60°, +15° at 30°
    phi_i = np.full(theta.shape, np.arcsin(np.sin(np.radians(ILLUMINATION_DEG)) / n))
    phi_v = np.arcsin(np.sin(np.radians(view_air)) / n)
    t_in = 1.0 - fresnel_unpolarised(ILLUMINATION_DEG, n)
    t_out = 1.0 - fresnel_unpolarised(view_air, n)
    return FlakeGeometry(
        phi_i=phi_i,
        phi_v=phi_v,
        tilt=0.5 * (phi_i - phi_v),
        incidence=0.5 * np.abs(phi_i + phi_v),
        transfer=t_in * t_out / n**2,
        path=1.0 / np.cos(phi_i) + 1.0 / np.cos(phi_v),
    )


def beckmann(tilt_rad: ArrayLike, m: float) -> NDArray[np.float64]:
    """Beckmann flake-tilt density D(α) = exp(−tan²α / m²) / (π m² cos⁴α) (normalised: ∫ D cos α dω = 1)."""
    a = np.asarray(tilt_rad, dtype=np.float64)
    t2 = np.tan(a) ** 2
    return np.asarray(np.exp(-t2 / (m * m)) / (np.pi * m * m * np.cos(a) ** 4), dtype=np.float64)


@dataclass(frozen=True)
class ThinFilm:
    """A TiO2 interference layer on a mica platelet: Cauchy index n(λ) = a + b / λ², thickness (nm),
    *faces* reflecting faces per platelet (added incoherently)."""

    cauchy_a: float
    cauchy_b_nm2: float
    thickness_nm: float
    faces: int = 2

    def __post_init__(self) -> None:
        if not (self.cauchy_a > 1.0 and self.cauchy_b_nm2 >= 0 and self.thickness_nm > 0 and self.faces >= 1):
            raise FormulateInputError("thin_film", "cauchy_a > 1, cauchy_b_nm2 >= 0, thickness_nm > 0", self)

    def reflectance(self, incidence_rad: ArrayLike, n_medium: float = N_BINDER) -> NDArray[np.float64]:
        """Unpolarised platelet reflectance at incidence angles (radians, in the binder), shape (A, 31),
        by the transfer-matrix method (``colour.phenomena.thin_film_tmm``)."""
        from colour.phenomena import thin_film_tmm

        n_film = self.cauchy_a + self.cauchy_b_nm2 / WAVELENGTHS_NM**2
        beta = np.degrees(np.atleast_1d(np.asarray(incidence_rad, dtype=np.float64)))
        # one wavelength per call: given a dispersive index for all 31 bands at once, thin_film_tmm
        # (colour-science 0.4.7) returns oblique-incidence reflectances up to 0.02 off the Airy formula,
        # while one band at a time agrees with it to round-off (tests/formulate/test_effect_pigments.py)
        one = np.empty((beta.size, WAVELENGTHS_NM.size))
        for k, lam in enumerate(WAVELENGTHS_NM):
            stack = np.array([[n_medium], [n_film[k]], [n_medium]])
            r, _t = thin_film_tmm(stack, self.thickness_nm, np.array([lam]), beta)
            one[:, k] = np.asarray(r, dtype=np.float64)[0, :, 0, :].mean(-1)  # mean of s and p
        f = self.faces
        # f faces of equal reflectance, incoherent multiple reflection: R_f = f R / (1 + (f − 1) R)
        return np.asarray(f * one / (1.0 + (f - 1) * one), dtype=np.float64)

    def diffuse_reflectance(self) -> NDArray[np.float64]:
        """r̄(λ): the platelet reflectance for diffuse light in the binder, shape (31,).

        The cosine-weighted (Lambertian flux) mean over internal incidence β of :meth:`reflectance`,
        r̄ = ∫ r(β) sin 2β dβ over 0–90° (∫ sin 2β dβ = 1), by Gauss–Legendre quadrature (cached).
        """
        return _hemispherical_film(self)


#: Gauss–Legendre nodes of the diffuse-light average over a platelet (the Fresnel rise towards grazing needs
#: more than a midpoint rule).
_DIFFUSE_NODES = 48


@functools.lru_cache(maxsize=64)
def _hemispherical_film(film: ThinFilm) -> NDArray[np.float64]:
    """:meth:`ThinFilm.diffuse_reflectance` (cached per film: the transfer matrix is the slow part)."""
    x, wx = np.polynomial.legendre.leggauss(_DIFFUSE_NODES)
    beta = np.pi / 4.0 * (x + 1.0)  # [−1, 1] → [0, π/2]
    w = np.pi / 4.0 * wx * np.sin(2.0 * beta)  # ∫ sin 2β dβ over [0, π/2] = 1
    out = np.asarray(w @ film.reflectance(beta), dtype=np.float64)
    out.setflags(write=False)
    return out
