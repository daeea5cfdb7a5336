"""Fresnel reflectance of dielectrics and the physical clear coat (shared by the gloss meter and renderers).

:func:`fresnel_unpolarised` (scalar, exact), :func:`fresnel_dielectric` (vectorised, exact) and Schlick's
approximation (:func:`fresnel_schlick`, kept for comparison); :class:`ClearCoat` the coat layer the
renderers draw. The gloss meter's standard (black glass, :data:`STANDARD_INDEX`) lives here because the
coat's factor is normalised to the lobe albedo it defines (:mod:`station.model.gloss`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from station.model.errors import ModelInputError

#: Refractive index of the primary gloss standard (black glass at 587.6 nm).
STANDARD_INDEX = 1.567


def fresnel_unpolarised(theta_deg: float, n: float) -> float:
    """Fresnel reflectance of a dielectric (index *n*, from air) at incidence *theta_deg*, unpolarised.

    Examples
    --------
    Normal incidence gives ((n − 1)/(n + 1))²; the black-glass standard (n = 1.567) reflects 10.0 % at 60°:

    >>> round(fresnel_unpolarised(0.0, 1.5), 12), round(fresnel_unpolarised(60.0, 1.567), 6)
    (0.04, 0.100056)
    """
    ti = math.radians(theta_deg)
    st = math.sin(ti) / n
    tt = math.asin(st)
    ci, ct = math.cos(ti), math.cos(tt)
    rs = ((ci - n * ct) / (ci + n * ct)) ** 2
    rp = ((n * ci - ct) / (n * ci + ct)) ** 2
    return 0.5 * (rs + rp)


#: Refractive index of an automotive clear coat (acrylic / polyurethane binders, about 1.5).
CLEAR_COAT_INDEX = 1.5
#: Incidence (degrees) at which a design's specular albedo is defined: the 60° gloss geometry (above).
COAT_REFERENCE_DEG = 60.0


def schlick_f0(n: float) -> float:
    """Normal-incidence reflectance F0 = ((n − 1)/(n + 1))² of a dielectric of index *n* from air.

    Examples
    --------
    >>> round(schlick_f0(1.5), 12)
    0.04
    """
    return ((n - 1.0) / (n + 1.0)) ** 2


def fresnel_schlick(cos_theta: NDArray | float, n: float) -> NDArray[np.float64]:
    """Schlick's approximation F(θ) = F0 + (1 − F0)(1 − cos θ)⁵ of the dielectric Fresnel reflectance.

    *cos_theta* is clipped to [0, 1] (grazing beyond 90° reads as 90°); *n* the coat's index.
    """
    c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
    f0 = schlick_f0(n)
    return f0 + (1.0 - f0) * (1.0 - c) ** 5


def fresnel_dielectric(cos_theta: NDArray | float, n: float) -> NDArray[np.float64]:
    """Exact unpolarised Fresnel reflectance of a dielectric of index *n* from air, vectorised.

    *cos_theta* (cosine of the incidence angle) is clipped to [0, 1]; the result lies in [F0, 1]: F0 =
    ((n − 1)/(n + 1))² head-on, 1 at grazing (the same value as :func:`fresnel_unpolarised`).
    """
    c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
    ct = np.sqrt(np.maximum(1.0 - (1.0 - c * c) / (n * n), 0.0))
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return np.asarray(0.5 * (rs * rs + rp * rp), dtype=float)


@lru_cache(maxsize=64)
def fresnel_diffuse_reflectance(n: float, steps: int = 128) -> float:
    """F_dr,ext(n) = 2 ∫₀¹ F(μ; n) μ dμ: the cosine-weighted hemispherical mean of the Fresnel reflectance
    of a dielectric of index *n* from air (dimensionless; what it reflects of a uniform, diffuse light).

    Gauss–Legendre quadrature in μ = cos θ (*steps* nodes; 128 agree with 4096 to 1e-15). 1 − F_dr,ext is what a
    uniform environment delivers through the coat, and equals η²(1 − F_dr,int) (the internal diffuse
    reflectance at the same interface, Mitsuba's ``plastic``).

    Examples
    --------
    >>> round(fresnel_diffuse_reflectance(1.5), 4)
    0.0918
    """
    x, w = np.polynomial.legendre.leggauss(int(steps))
    mu = 0.5 * (x + 1.0)
    return float(np.sum(w * 0.5 * 2.0 * fresnel_dielectric(mu, n) * mu))


@dataclass(frozen=True)
class ClearCoat:
    """A physical clear coat over the paint (the thesis's §2.5.2 Fresnel remark, made energy conserving).

    A dielectric layer of index n reflects the exact unpolarised Fresnel fraction F(N·V; n) ≤ 1
    (:func:`fresnel_dielectric`, evaluated at the view angle: the split-sum assumption of one Fresnel
    factor per pixel for the lobes about R) and passes 1 − F(N·V) to the paint below, so per pixel

        radiance = s(N·V) · gloss terms + (1 − F(N·V)) · base terms,    s = F(N·V)/ρ_ref

    with ρ_ref = F(60°; 1.567) = 0.100 the albedo of a design's gloss lobe at full strength (the black
    glass of the gloss scale, ``station.model.gloss.lobe_from_gloss``; the lobe fit conserves it,
    ``station.render.lobe_fit.conserve_gloss_energy``): a full-gloss design's coat reflects exactly F,
    0.04 head-on and 1 at grazing for n = 1.5, and a lower-gloss one (ρ_s scaled down) proportionally
    less. The base terms (diffuse, directionally diffuse, fall-off, flakes) are what the coat lets
    through. Under a uniform environment a white Lambertian base then returns F + (1 − F) = 1 of the
    light and no base returns more (the white-furnace test). ``None`` in place of a ClearCoat is the
    thesis's model (no Fresnel: the measured colours already hold the coat's transmission).

    Light entering the coat (:meth:`entry_scale`): the diffuse base sees each incoming direction l through
    the coat as well, weighted by (1 − F(N·l))/(1 − F_dr,ext), F_dr,ext the cosine-weighted hemispherical
    mean of F (:func:`fresnel_diffuse_reflectance`). This is Mitsuba 3's ``plastic`` (``nonlinear``
    false): (1 − F_i)(1 − F_o) ρ/(π η²(1 − F_dr,int)), with η²(1 − F_dr,int) = 1 − F_dr,ext, the light the
    base's internal reflections under the coat return. In a uniform environment the entry weight
    averages to exactly 1 (the white furnace is unchanged: F + (1 − F)·ρ ≤ 1); under a directional light
    at N·l the diffuse base scales by (1 − F(N·l))(1 − F(N·V))/(1 − F_dr,ext). The renderers apply it
    to the diffuse term (K_D) only, through a coat-transmitted diffuse map
    (``station.render.prefilter.coat_diffuse_map``); the effect terms (directionally diffuse lobes,
    fall-off, flakes) keep 1 − F(N·V) alone: they are fitted to measured colours that already hold
    the coat's entry at the measured geometries, and the plastic model has no such lobes.

    Attributes
    ----------
    index
        Refractive index n of the coat, 1.0 < n <= 3.0 (default CLEAR_COAT_INDEX = 1.5).
    """

    index: float = CLEAR_COAT_INDEX

    def __post_init__(self) -> None:
        n = self.index
        if (
            isinstance(n, bool)
            or not isinstance(n, (int, float))
            or not (math.isfinite(n) and 1.0 < n <= 3.0)
        ):
            raise ModelInputError("coat_index", "1.0 < n <= 3.0", n)
        object.__setattr__(self, "index", float(n))

    @property
    def f0(self) -> float:
        """Normal-incidence reflectance F0 of the coat (the renderers recover n from it)."""
        return schlick_f0(self.index)

    @property
    def reference(self) -> float:
        """ρ_ref = F(60°; 1.567): the lobe albedo of a full-gloss design, which s(N·V) divides by."""
        return fresnel_unpolarised(COAT_REFERENCE_DEG, STANDARD_INDEX)

    def fresnel(self, n_dot_v: NDArray | float) -> NDArray[np.float64]:
        """F(N·V; n), the share of the light the coat reflects (dimensionless, ≤ 1)."""
        return fresnel_dielectric(n_dot_v, self.index)

    def gloss_scale(self, n_dot_v: NDArray | float) -> NDArray[np.float64]:
        """s(N·V) = F(N·V; n)/ρ_ref, the factor on the gloss terms (dimensionless, class docstring)."""
        return self.fresnel(n_dot_v) / self.reference

    def base_scale(self, n_dot_v: NDArray | float) -> NDArray[np.float64]:
        """1 − F(N·V; n), the factor on the base (colour) terms: what the coat transmits."""
        return 1.0 - self.fresnel(n_dot_v)

    @property
    def diffuse_transmission(self) -> float:
        """1 − F_dr,ext(n): the share of a uniform, diffuse light the coat lets in (dimensionless)."""
        return 1.0 - fresnel_diffuse_reflectance(self.index)

    def entry_scale(self, n_dot_l: NDArray | float) -> NDArray[np.float64]:
        """(1 − F(N·l; n))/(1 − F_dr,ext(n)): the weight of light arriving at N·l on the diffuse base
        (dimensionless; its cosine-weighted hemispherical mean is 1, class docstring)."""
        return (1.0 - self.fresnel(n_dot_l)) / self.diffuse_transmission
