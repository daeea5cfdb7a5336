"""Synthetic colorant database and the per-geometry Kubelka–Munk paint model (SYNTHETIC DATA).

Nothing here is measured: the colorants are invented, with spectra shaped like their real
counterparts (TiO2 white, carbon black, organic tints, aluminium flakes, mica pearls, interference
pigments), so that the formulation pipeline can be built and tested end to end. Every library made
from it is labelled synthetic.

Model (documented in docs/formulate.md, "Colorant model"). For aspecular angle θ (degrees,
illumination at 45°) and wavelength λ (400–700 nm, 10 nm):

* absorption  K(λ)    = K_binder + Σ_i c_i K_i(λ)
* scattering  S(θ, λ) = S_binder + Σ_i c_i S_i(λ) g_i(θ, λ)

  where c_i is the mass fraction of colorant i in the basecoat and g_i is the colorant's angular lobe:
  1 for diffuse pigments, ``floor + exp(-(|θ|/w)^p)`` for flakes and pearls (bright near the specular
  direction, dark at flop). Interference pigments also move their reflection band with angle:
  λ_peak(θ) = λ₀ √(1 − sin²(θ′)/n²), θ′ = min(|θ|, 90°), n = 1.6 (thin-film blue shift).
* Kubelka–Munk reflectance of an opaque layer: R∞ = 1 + K/S − √((K/S)² + 2 K/S)  (Kubelka & Munk 1931)
* Saunderson correction, specular component excluded (aspecular geometry):
  R = (1 − k₁)(1 − k₂) R∞ / (1 − k₂ R∞), k₁ = 0.04, k₂ = 0.6  (Saunderson 1942).

Lab per angle is CIE L*a*b* D65 / CIE 1964 10° of R through the same tristimulus weights as
:func:`station.model.spectra.reflectance_to_lab` (a linear map, extracted once; see :func:`lab_from_reflectance`).

Gloss (60°, GU) is a clear-coat property: G = 90 − 650 c_matting (matting silica), 6.5 ≤ G ≤ 90 GU
over the allowed matting range.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.errors import FormulateInputError

WAVELENGTHS_NM: NDArray[np.float64] = np.arange(400.0, 701.0, 10.0)
K1_SAUNDERSON = 0.04
K2_SAUNDERSON = 0.6
K_BINDER = 0.02
S_BINDER = 0.01
GLOSS_CLEAR_GU = 90.0
GLOSS_PER_MATTING = 650.0
#: Total pigment mass fraction allowed in a basecoat.
MAX_TOTAL = 0.6

_L = WAVELENGTHS_NM


def _sig(x: NDArray[np.float64]) -> NDArray[np.float64]:
    return 1.0 / (1.0 + np.exp(-x))


def _gauss(mu: float, sd: float) -> NDArray[np.float64]:
    return np.exp(-0.5 * ((_L - mu) / sd) ** 2)


@dataclass(frozen=True)
class Colorant:
    """One synthetic colorant.

    Attributes
    ----------
    name
        Identifier used in recipes.
    family
        ``"white" | "black" | "tint" | "aluminium" | "pearl" | "interference" | "matting"``.
    k, s
        Absorption and scattering per unit mass fraction, shape (31,) on :data:`WAVELENGTHS_NM`.
    lobe_width_deg, lobe_power, lobe_floor
        Angular lobe g(θ) = floor + exp(-(|θ|/w)^p) for effect pigments (``None`` width: diffuse, g = 1).
    peak_nm, band_nm
        Interference band centre at normal observation and its width (``None``: no interference).
    max_fraction
        Upper bound of its mass fraction in a recipe.
    """

    name: str
    family: str
    k: NDArray[np.float64]
    s: NDArray[np.float64]
    lobe_width_deg: float | None = None
    lobe_power: float = 1.0
    lobe_floor: float = 0.0
    peak_nm: float | None = None
    band_nm: float = 40.0
    max_fraction: float = 0.5

    def lobe(self, angles_deg: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return g(θ) of shape (A,) for aspecular *angles_deg* (degrees)."""
        a = np.abs(np.asarray(angles_deg, dtype=np.float64))
        if self.lobe_width_deg is None:
            return np.ones_like(a)
        return self.lobe_floor + np.exp(-((a / self.lobe_width_deg) ** self.lobe_power))

    def scattering(self, angles_deg: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return S_i(λ) g_i(θ, λ), shape (A, 31), per unit mass fraction."""
        g = self.lobe(angles_deg)[:, None]
        if self.peak_nm is None:
            return g * self.s[None, :]
        theta = np.radians(np.minimum(np.abs(np.asarray(angles_deg, dtype=np.float64)), 90.0))
        peak = self.peak_nm * np.sqrt(1.0 - (np.sin(theta) / 1.6) ** 2)
        band = np.exp(-0.5 * ((_L[None, :] - peak[:, None]) / self.band_nm) ** 2)
        return g * self.s[None, :] * (0.15 + band)


def _tint(name: str, k: NDArray[np.float64], s: float = 0.08, max_fraction: float = 0.3) -> Colorant:
    return Colorant(name, "tint", k, np.full(31, s), max_fraction=max_fraction)


def _build() -> tuple[Colorant, ...]:
    flat = np.ones(31)
    return (
        Colorant(
            "white_tio2",
            "white",
            0.03 + 0.4 * _sig((410.0 - _L) / 8.0),
            6.0 * (550.0 / _L) ** 1.5,
            max_fraction=0.45,
        ),
        Colorant("black_carbon", "black", 25.0 * flat * (550.0 / _L) ** 0.3, 0.3 * flat, max_fraction=0.1),
        _tint("yellow_py", 14.0 * _sig((495.0 - _L) / 12.0)),
        _tint("orange_po", 14.0 * _sig((560.0 - _L) / 12.0)),
        _tint("red_pr", 16.0 * _sig((595.0 - _L) / 12.0) + 2.0 * _gauss(420.0, 30.0)),
        _tint("magenta_pv", 12.0 * _gauss(545.0, 38.0)),
        _tint("blue_pb", 14.0 * _gauss(615.0, 55.0) + 3.0 * _sig((_L - 560.0) / 20.0) + 0.5),
        _tint("green_pg", 12.0 * _sig((450.0 - _L) / 15.0) + 14.0 * _sig((_L - 575.0) / 15.0)),
        Colorant(
            "alu_coarse",
            "aluminium",
            1.6 * flat,
            80.0 * flat,
            lobe_width_deg=18.0,
            lobe_power=1.6,
            lobe_floor=0.001,
            max_fraction=0.2,
        ),
        Colorant(
            "alu_fine",
            "aluminium",
            1.0 * flat,
            60.0 * flat,
            lobe_width_deg=28.0,
            lobe_power=1.5,
            lobe_floor=0.003,
            max_fraction=0.2,
        ),
        Colorant(
            "pearl_white",
            "pearl",
            0.04 * flat,
            5.0 * flat,
            lobe_width_deg=45.0,
            lobe_power=1.5,
            lobe_floor=0.08,
            max_fraction=0.2,
        ),
        Colorant(
            "interference_blue",
            "interference",
            0.05 * flat,
            8.0 * flat,
            lobe_width_deg=40.0,
            lobe_power=1.5,
            lobe_floor=0.03,
            peak_nm=470.0,
            band_nm=35.0,
            max_fraction=0.15,
        ),
        Colorant(
            "interference_green",
            "interference",
            0.05 * flat,
            8.0 * flat,
            lobe_width_deg=40.0,
            lobe_power=1.5,
            lobe_floor=0.03,
            peak_nm=540.0,
            band_nm=35.0,
            max_fraction=0.15,
        ),
        Colorant(
            "interference_gold",
            "interference",
            0.05 * flat,
            8.0 * flat,
            lobe_width_deg=40.0,
            lobe_power=1.5,
            lobe_floor=0.03,
            peak_nm=600.0,
            band_nm=45.0,
            max_fraction=0.15,
        ),
        Colorant("matting_silica", "matting", 0.0 * flat, 0.0 * flat, max_fraction=0.13),
    )


@dataclass(frozen=True)
class ColorantDatabase:
    """An ordered set of colorants with the recipe constraints.

    Constraints on a recipe c (mass fractions): 0 ≤ c_i ≤ max_fraction_i, Σ c_i ≤ :data:`MAX_TOTAL`
    (the rest is binder), aluminium + pearl + interference ≤ ``max_effect`` (flake limit).
    """

    colorants: tuple[Colorant, ...]
    max_total: float = MAX_TOTAL
    max_effect: float = 0.25
    synthetic: bool = True

    @property
    def names(self) -> tuple[str, ...]:
        """Colorant names, in recipe-vector order."""
        return tuple(c.name for c in self.colorants)

    @functools.cached_property
    def _k(self) -> NDArray[np.float64]:
        return np.stack([c.k for c in self.colorants])

    @property
    def upper_bounds(self) -> NDArray[np.float64]:
        """Per-colorant upper bound of the mass fraction, shape (n,)."""
        return np.array([c.max_fraction for c in self.colorants])

    @property
    def effect_mask(self) -> NDArray[np.bool_]:
        """True for flake / pearl / interference colorants (the flake limit applies to their sum)."""
        return np.array([c.family in ("aluminium", "pearl", "interference") for c in self.colorants])

    @property
    def matting_index(self) -> int:
        """Row of the matting agent (gloss control)."""
        return [c.family for c in self.colorants].index("matting")

    def scattering_table(self, angles_deg: tuple[float, ...]) -> NDArray[np.float64]:
        """Return S_i(θ, λ) per unit fraction, shape (n, A, 31)."""
        return _scattering_table(self, tuple(float(a) for a in angles_deg))

    def vector(self, recipe: dict[str, float]) -> NDArray[np.float64]:
        """Return the recipe as a concentration vector; unknown colorant names are refused."""
        c = np.zeros(len(self.colorants))
        names = self.names
        for key, val in recipe.items():
            if key not in names:
                raise FormulateInputError("recipe", f"colorants from {names}", key)
            c[names.index(key)] = float(val)
        return c

    def recipe(self, c: ArrayLike, threshold: float = 1e-6) -> dict[str, float]:
        """Return concentration vector *c* as ``{name: fraction}`` (fractions below *threshold* omitted)."""
        return {n: float(v) for n, v in zip(self.names, np.asarray(c), strict=True) if v > threshold}

    def check(self, c: ArrayLike, field: str = "recipe") -> NDArray[np.float64]:
        """Validate recipe vector(s) *c* against the constraints; return it as an array."""
        c = np.asarray(c, dtype=np.float64)
        tol = 1e-9
        if c.shape[-1] != len(self.colorants) or not np.all(np.isfinite(c)):
            raise FormulateInputError(field, f"{len(self.colorants)} finite fractions", c.shape)
        if np.any(c < -tol) or np.any(c > self.upper_bounds + tol):
            raise FormulateInputError(field, "0 <= c_i <= max_fraction_i", self.recipe(np.clip(c, 0, None)))
        if np.any(c.sum(-1) > self.max_total + tol):
            raise FormulateInputError(field, f"total fraction <= {self.max_total}", float(c.sum(-1).max()))
        if np.any((c * self.effect_mask).sum(-1) > self.max_effect + tol):
            raise FormulateInputError(field, f"flake + pearl fraction <= {self.max_effect}", None)
        return c

    def __hash__(self) -> int:
        return id(self)

    def __eq__(self, other: object) -> bool:
        return self is other


@functools.lru_cache(maxsize=16)
def _scattering_table(db: ColorantDatabase, angles: tuple[float, ...]) -> NDArray[np.float64]:
    a = np.asarray(angles)
    return np.stack([c.scattering(a) for c in db.colorants])


@functools.lru_cache(maxsize=1)
def default_database() -> ColorantDatabase:
    """Return the built-in SYNTHETIC colorant database (15 colorants)."""
    return ColorantDatabase(_build())


def predict_reflectance(
    c: ArrayLike, angles_deg: tuple[float, ...], db: ColorantDatabase | None = None
) -> NDArray[np.float64]:
    """Predict reflectance factors per angle (Kubelka–Munk + Saunderson, see module docstring).

    Parameters
    ----------
    c
        Mass fractions, shape (..., n_colorants).
    angles_deg
        Aspecular angles in degrees.

    Returns
    -------
    ndarray
        R in [0, 1), shape (..., len(angles_deg), 31) on 400–700 nm / 10 nm.
    """
    db = db or default_database()
    c = np.asarray(c, dtype=np.float64)
    k = K_BINDER + c @ db._k  # (..., 31)
    s = S_BINDER + np.einsum("...i,iaw->...aw", c, db.scattering_table(angles_deg))  # (..., A, 31)
    ks = k[..., None, :] / s
    r_inf = 1.0 + ks - np.sqrt(ks * ks + 2.0 * ks)
    return (1.0 - K1_SAUNDERSON) * (1.0 - K2_SAUNDERSON) * r_inf / (1.0 - K2_SAUNDERSON * r_inf)


@functools.lru_cache(maxsize=1)
def _tristimulus() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return (offset, W) with XYZ(R) = offset + R @ W, extracted from the product's own conversion.

    XYZ of a reflectance is linear in R for every tabulation method (integration or ASTM E308), so
    probing reflectance_to_lab with 32 spectra recovers its weights exactly (to round-off).
    """
    from station.model.colorimetry import lab_to_xyz
    from station.model.spectra import reflectance_to_lab as _to_lab

    base = np.full(31, 0.5)
    probes = np.vstack([base, base + 0.25 * np.eye(31)])
    xyz = lab_to_xyz(_to_lab(probes))
    w = (xyz[1:] - xyz[0]) / 0.25
    offset = xyz[0] - base @ w
    return offset, w


def lab_from_reflectance(r: ArrayLike) -> NDArray[np.float64]:
    """CIE L*a*b* (D65, 10°) of reflectance *r* (..., 31), identical in value to
    :func:`station.model.spectra.reflectance_to_lab` (same tristimulus weights), vectorised for speed."""
    from station.model.colorimetry import xyz_to_lab

    offset, w = _tristimulus()
    return xyz_to_lab(offset + np.asarray(r, dtype=np.float64) @ w)


def predict_lab(
    c: ArrayLike, angles_deg: tuple[float, ...], db: ColorantDatabase | None = None
) -> NDArray[np.float64]:
    """Predict L*a*b* per angle for recipe(s) *c*: shape (..., len(angles_deg), 3)."""
    return lab_from_reflectance(predict_reflectance(c, angles_deg, db))


def predict_gloss(c: ArrayLike, db: ColorantDatabase | None = None) -> NDArray[np.float64]:
    """Predict 60° gloss in GU from the matting fraction: G = 90 − 650 c_matting."""
    db = db or default_database()
    c = np.asarray(c, dtype=np.float64)
    return GLOSS_CLEAR_GU - GLOSS_PER_MATTING * c[..., db.matting_index]
