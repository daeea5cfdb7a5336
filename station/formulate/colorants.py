"""Synthetic colorant database and the effect-paint colorant model (SYNTHETIC DATA).

Nothing here is measured: the colorants are invented, with spectra shaped like their real counterparts
(TiO2 white, carbon black, organic tints, three aluminium flake grades, a mica pearl and three
interference pigments), so that the formulation pipeline can be built and tested end to end. Every
parameter is in one data file, ``station/formulate/data/colorants.json``; every library made from it
is labelled synthetic. The effect pigments are documented one by one in docs/effect-pigments.md.

Model, for aspecular angle θ (degrees, illumination at 45°, signed: positive towards the illumination, so
−15° views at 60° from the normal and +15° at 30°, and the two differ as on a real multi-angle
instrument) and wavelength λ
(400–700 nm, 10 nm), recipe c (mass fractions in the basecoat):

1. **Diffuse body** (every colorant, flakes included): two-constant Kubelka–Munk of an opaque layer,
   K(λ) = K_binder + Σ c_i K_i(λ), S(λ) = S_binder + Σ c_i S_i(λ),
   R∞ = 1 + K/S − √((K/S)² + 2 K/S) (Kubelka & Munk 1931), through the clear coat by Saunderson
   (1942) with the specular component excluded: R_d = (1 − k₁)(1 − k₂) R∞ / (1 − k₂ R∞), k₁ the
   Fresnel reflectance of the binder (n) at the 45° illumination, k₂ = 0.6 (diffuse internal).
   R_d < 1 always: a diffuse body never reflects more than a white diffuser.
2. **Flake reflection** (aluminium, pearl, interference), in the manner of the flake radiance-factor
   models (Mobil, US 3,916,168: diffuse flux + angular flux; PPG, US 5,231,472: flake reflection
   attenuated by the film on the way in and out). Inside the film the light travels at
   φ_i′ = asin(sin 45° / n) and the viewing direction at φ_v′ = asin(sin(45° − θ) / n); a flake
   mirrors one into the other when tilted by α = (φ_i′ − φ_v′)/2, the light meeting it at
   β = (φ_i′ + φ_v′)/2. With a Beckmann distribution of flake tilts of r.m.s. slope m,
   D(α) = exp(−tan²α / m²) / (π m² cos⁴α), the flake term is the microfacet radiance factor
   carried out through the coat (radiance n² law):

       R_f(θ, λ) = Σ_j A_j(c) · r_j(β, λ) · π D_j(α) / (4 cos φ_i′ cos φ_v′) · T(45°) T(φ_v) / n²
                   · exp(−(K′ + f S′) h (1/cos φ_i′ + 1/cos φ_v′))
                 + Σ_j A_j ρ_d,j T(45°) T(φ_v) / n² · exp(−(K′ + f S′) h (1/cos φ_i′ + 2)),

   where A_j is the area fraction covered by flakes of grade j (Beer–Lambert stacking:
   A = 1 − exp(−Σ σ_j c_j), shared in proportion to σ_j c_j), r_j the flake's reflectance
   (aluminium: a measured-like metal spectrum; pearl and interference: the thin-film reflectance of a
   TiO2 layer in the binder at incidence β by the transfer-matrix method of colour-science,
   ``colour.phenomena.thin_film_tmm``, both faces of the platelet added incoherently), T the Fresnel
   transmittance of the coat, and the exponential the attenuation by the non-flake pigments above the
   flakes (K′, S′; depth h and the scattering share f are model constants). The second sum is the
   flakes' diffuse flux (albedo ρ_d: edges, roughness, flake-to-flake reflection), seen through the
   same pigments on a diffuse way out (mean path 2 = ∫ μ⁻¹ 2μ dμ): it gives a metallic its flop colour
   (tint over aluminium). R_f exceeds 1 near
   specular: bright silvers read L*15 of 110–140 and fall to a dark flop as D(α) does.

3. **Through the platelets** (pearl, interference): a non-absorbing thin film transmits 1 − r̄(λ), the
   complement of its reflection colour (r̄ the platelet reflectance for diffuse light), so the body is
   seen filtered by F(λ) = 1 − Σ_j A_j r̄_j (2 − r̄_j) (down and up through the platelets); the diffuse
   flux of a rough platelet keeps its interference colour, ρ_d,j(λ) = ρ_d,j r̄_j(λ) / ⟨r̄_j⟩. Over a light
   base the flop shows the complementary colour, over a dark one a weak interference colour
   (docs/effect-pigments.md).

R = R_d F + R_f. Lab per angle is CIE L*a*b* D65 / CIE 1964 10° of R through the same tristimulus weights
as :func:`station.model.spectra.reflectance_to_lab` (a linear map, extracted once; see
:func:`lab_from_reflectance`).

Gloss (60°, GU) is a clear-coat property: G = G_clear − g c_matting (matting silica), 6.5 ≤ G ≤ 90 GU
over the allowed matting range.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.formulate.effect_optics import (
    DATA_FILE,
    GLOSS_CLEAR_GU,
    GLOSS_PER_MATTING,
    K1_SAUNDERSON,
    K2_SAUNDERSON,
    K_BINDER,
    MAX_TOTAL,
    N_BINDER,
    S_BINDER,
    WAVELENGTHS_NM,
    FlakeGeometry,
    ThinFilm,
    beckmann,
    colorant_data,
    flake_geometry,
    fresnel_unpolarised,
)
from station.formulate.errors import FormulateError, FormulateInputError

#: The model's public names; the optics of :mod:`station.formulate.effect_optics` are re-exported.
__all__ = [
    "DATA_FILE",
    "EFFECT_FAMILIES",
    "FAMILIES",
    "GLOSS_CLEAR_GU",
    "GLOSS_PER_MATTING",
    "K1_SAUNDERSON",
    "K2_SAUNDERSON",
    "K_BINDER",
    "MAX_TOTAL",
    "MODEL_REVISION",
    "N_BINDER",
    "S_BINDER",
    "WAVELENGTHS_NM",
    "Colorant",
    "ColorantDatabase",
    "Flake",
    "FlakeGeometry",
    "ThinFilm",
    "beckmann",
    "body_filter",
    "colorant_data",
    "default_database",
    "diffuse_reflectance",
    "flake_area",
    "flake_geometry",
    "flake_reflectance",
    "fresnel_unpolarised",
    "lab_from_reflectance",
    "predict_gloss",
    "predict_lab",
    "predict_reflectance",
]

#: Revision of the model's equations (the data file holds every parameter): a cached library made with
#: another revision is stale. 2: spectral platelet albedo, the body seen through the platelets, signed θ.
MODEL_REVISION = 2
#: Families of colorants the model knows; the effect families carry a :class:`Flake`.
FAMILIES = ("white", "black", "tint", "aluminium", "pearl", "interference", "matting")
EFFECT_FAMILIES = ("aluminium", "pearl", "interference")


@dataclass(frozen=True)
class Flake:
    """Flake optics of an effect pigment (module docstring, step 2).

    Attributes
    ----------
    coverage_per_fraction
        σ: flake area per unit film area per unit mass fraction (A = 1 − exp(−σ c)).
    orientation_m
        r.m.s. slope m of the Beckmann tilt distribution (small: well-oriented, bright face, dark flop).
    diffuse_albedo
        ρ_d: the share of light a flake returns diffusely (edges, roughness, multiple reflection between
        flakes: the "diffuse flux" of the Mobil model), seen through the pigments above it.
    reflectance
        Metal flake reflectance r(λ), shape (31,) (aluminium), or ``None`` for a thin-film platelet.
    thin_film
        The interference layer of a pearl / interference pigment, or ``None`` for a metal flake.
    """

    coverage_per_fraction: float
    orientation_m: float
    diffuse_albedo: float = 0.0
    reflectance: NDArray[np.float64] | None = None
    thin_film: ThinFilm | None = None

    def __post_init__(self) -> None:
        if not (
            self.coverage_per_fraction > 0 and 0 < self.orientation_m < 1.5 and 0 <= self.diffuse_albedo <= 1
        ):
            raise FormulateInputError(
                "flake", "coverage_per_fraction > 0, 0 < orientation_m < 1.5, 0 <= diffuse_albedo <= 1", self
            )
        if (self.reflectance is None) == (self.thin_film is None):
            raise FormulateInputError("flake", "exactly one of reflectance / thin_film", self)
        if self.reflectance is not None and (
            self.reflectance.shape != (31,) or np.any(self.reflectance < 0) or np.any(self.reflectance > 1)
        ):
            raise FormulateInputError("flake.reflectance", "31 values in [0, 1]", self.reflectance.shape)

    def facet_reflectance(self, incidence_rad: NDArray[np.float64]) -> NDArray[np.float64]:
        """r(β, λ), shape (A, 31)."""
        if self.reflectance is not None:
            return np.broadcast_to(self.reflectance, (incidence_rad.size, 31)).copy()
        assert self.thin_film is not None  # noqa: S101 - __post_init__ guarantees one of the two
        return self.thin_film.reflectance(incidence_rad)

    def diffuse_albedo_spectrum(self) -> NDArray[np.float64]:
        """ρ_d(λ), shape (31,): neutral ρ_d for a metal flake; for a thin-film platelet the diffuse flux keeps
        the interference colour, ρ_d(λ) = min(1, ρ_d r̄(λ) / ⟨r̄⟩) (its spectral mean is ρ_d; r̄ from
        :meth:`ThinFilm.diffuse_reflectance`, ⟨·⟩ the mean over the 31 bands)."""
        if self.thin_film is None:
            return np.full(31, self.diffuse_albedo)
        r = self.thin_film.diffuse_reflectance()
        return np.asarray(np.minimum(1.0, self.diffuse_albedo * r / r.mean()), dtype=np.float64)

    def body_loss(self) -> NDArray[np.float64]:
        """L(λ), shape (31,): the share of the body's light a platelet removes on the way down and up.

        A non-absorbing thin film transmits 1 − r̄(λ), the complement of its reflection colour, so the
        body seen through it is filtered by (1 − r̄)² and L = 1 − (1 − r̄)² = r̄ (2 − r̄): over a light
        base the flop shows the complementary colour. A metal flake (opaque; its hiding is already in
        the body's K and S) removes nothing here: L = 0.
        """
        if self.thin_film is None:
            return np.zeros(31)
        r = self.thin_film.diffuse_reflectance()
        return np.asarray(r * (2.0 - r), dtype=np.float64)

    def radiance_factor(self, angles_deg: ArrayLike) -> NDArray[np.float64]:
        """Specular flake radiance factor at full coverage and no attenuation, shape (A, 31):
        r(β, λ) π D(α) / (4 cos φ_i′ cos φ_v′) · T T / n²."""
        g = flake_geometry(angles_deg)
        d = beckmann(g.tilt, self.orientation_m)
        geo = np.pi * d / (4.0 * np.cos(g.phi_i) * np.cos(g.phi_v)) * g.transfer
        return geo[:, None] * self.facet_reflectance(g.incidence)


@dataclass(frozen=True)
class Colorant:
    """One synthetic colorant (a record of the data file).

    Attributes
    ----------
    name
        Identifier used in recipes.
    family
        One of :data:`FAMILIES`.
    k, s
        Kubelka–Munk absorption and scattering per unit mass fraction, shape (31,) on
        :data:`WAVELENGTHS_NM` (the diffuse body; flakes too have one).
    flake
        Flake optics (effect families only).
    max_fraction
        Upper bound of its mass fraction in a recipe.
    doc
        One line saying what it stands for.
    """

    name: str
    family: str
    k: NDArray[np.float64]
    s: NDArray[np.float64]
    flake: Flake | None = None
    max_fraction: float = 0.5
    doc: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if self.family not in FAMILIES:
            raise FormulateInputError("colorant.family", f"one of {FAMILIES}", self.family)
        if (self.flake is not None) != (self.family in EFFECT_FAMILIES):
            raise FormulateInputError("colorant.flake", "flake optics exactly for effect families", self.name)
        for nm, arr in (("k", self.k), ("s", self.s)):
            if arr.shape != (31,) or not np.all(np.isfinite(arr)) or np.any(arr < 0):
                raise FormulateInputError(f"colorant.{nm}", "31 finite values >= 0", self.name)
        if not 0 < self.max_fraction <= 1:
            raise FormulateInputError("colorant.max_fraction", "0 < max_fraction <= 1", self.max_fraction)


def _colorant_from_record(rec: dict[str, Any]) -> Colorant:
    fl = rec.get("flake")
    flake = None
    if fl is not None:
        tf = fl.get("thin_film")
        flake = Flake(
            coverage_per_fraction=float(fl["coverage_per_fraction"]),
            orientation_m=float(fl["orientation_m"]),
            diffuse_albedo=float(fl.get("diffuse_albedo", 0.0)),
            reflectance=None if fl.get("reflectance") is None else np.asarray(fl["reflectance"], float),
            thin_film=None if tf is None else ThinFilm(**tf),
        )
    return Colorant(
        name=str(rec["name"]),
        family=str(rec["family"]),
        k=np.asarray(rec["k"], dtype=np.float64),
        s=np.asarray(rec["s"], dtype=np.float64),
        flake=flake,
        max_fraction=float(rec["max_fraction"]),
        doc=str(rec.get("doc", "")),
    )


@dataclass(frozen=True)
class ColorantDatabase:
    """An ordered set of colorants with the recipe constraints.

    Constraints on a recipe c (mass fractions): 0 ≤ c_i ≤ max_fraction_i, Σ c_i ≤ :data:`MAX_TOTAL`
    (the rest is binder), aluminium + pearl + interference ≤ ``max_effect`` (flake limit).
    ``flake_depth`` (h) and ``scatter_extinction`` (f) set the attenuation of the flake term by the
    pigments above the flakes (module docstring).
    """

    colorants: tuple[Colorant, ...]
    max_total: float = MAX_TOTAL
    max_effect: float = 0.25
    synthetic: bool = True
    flake_depth: float = 0.35
    scatter_extinction: float = 0.5

    def __post_init__(self) -> None:
        names = [c.name for c in self.colorants]
        if (
            len(set(names)) != len(names)
            or names.count("")
            or "matting" not in [c.family for c in self.colorants]
        ):
            raise FormulateInputError("colorants", "unique names and one matting agent", names)

    @property
    def names(self) -> tuple[str, ...]:
        """Colorant names, in recipe-vector order."""
        return tuple(c.name for c in self.colorants)

    @functools.cached_property
    def _k(self) -> NDArray[np.float64]:
        return np.stack([c.k for c in self.colorants])

    @functools.cached_property
    def _s(self) -> NDArray[np.float64]:
        return np.stack([c.s for c in self.colorants])

    @functools.cached_property
    def _k_above(self) -> NDArray[np.float64]:
        """K and S of the non-flake colorants only (what lies above the flakes), (n, 31) each."""
        return np.where(self.effect_mask[:, None], 0.0, self._k)

    @functools.cached_property
    def _s_above(self) -> NDArray[np.float64]:
        return np.where(self.effect_mask[:, None], 0.0, self._s)

    @functools.cached_property
    def effect_index(self) -> NDArray[np.intp]:
        """Rows of the effect pigments (those with flake optics)."""
        return np.flatnonzero(self.effect_mask)

    @functools.cached_property
    def flakes(self) -> tuple[Flake, ...]:
        """Flake optics of the effect pigments, in :attr:`effect_index` order."""
        return tuple(c.flake for c in self.colorants if c.flake is not None)

    @functools.cached_property
    def coverage(self) -> NDArray[np.float64]:
        """σ_j of the effect pigments, shape (E,)."""
        return np.array([f.coverage_per_fraction for f in self.flakes])

    @functools.cached_property
    def diffuse_albedo(self) -> NDArray[np.float64]:
        """ρ_d(λ) of the effect pigments, shape (E, 31) (:meth:`Flake.diffuse_albedo_spectrum`)."""
        return (
            np.stack([f.diffuse_albedo_spectrum() for f in self.flakes]) if self.flakes else np.zeros((0, 31))
        )

    @functools.cached_property
    def body_loss(self) -> NDArray[np.float64]:
        """L_j(λ) of the effect pigments, shape (E, 31) (:meth:`Flake.body_loss`)."""
        return np.stack([f.body_loss() for f in self.flakes]) if self.flakes else np.zeros((0, 31))

    @property
    def upper_bounds(self) -> NDArray[np.float64]:
        """Per-colorant upper bound of the mass fraction, shape (n,)."""
        return np.array([c.max_fraction for c in self.colorants])

    @property
    def effect_mask(self) -> NDArray[np.bool_]:
        """True for flake / pearl / interference colorants (the flake limit applies to their sum)."""
        return np.array([c.family in EFFECT_FAMILIES for c in self.colorants])

    @property
    def matting_index(self) -> int:
        """Row of the matting agent (gloss control)."""
        return [c.family for c in self.colorants].index("matting")

    def flake_table(self, angles_deg: tuple[float, ...]) -> NDArray[np.float64]:
        """Flake radiance factors at full coverage, shape (E, A, 31) (cached per angle set)."""
        return _flake_table(self, tuple(float(a) for a in angles_deg))

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


@functools.lru_cache(maxsize=32)
def _flake_table(db: ColorantDatabase, angles: tuple[float, ...]) -> NDArray[np.float64]:
    a = np.asarray(angles)
    rows = [f.radiance_factor(a) for f in db.flakes]
    return np.stack(rows) if rows else np.zeros((0, len(angles), 31))


@functools.lru_cache(maxsize=1)
def default_database() -> ColorantDatabase:
    """Return the built-in SYNTHETIC colorant database, read from the data file."""
    data = colorant_data()
    if data.get("synthetic") is not True:
        raise FormulateError("the colorant data file must be labelled synthetic")
    m = data["model"]
    return ColorantDatabase(
        tuple(_colorant_from_record(r) for r in data["colorants"]),
        max_total=float(m["max_total"]),
        max_effect=float(m["max_effect"]),
        synthetic=True,
        flake_depth=float(m["flake_depth"]),
        scatter_extinction=float(m["scatter_extinction"]),
    )


def diffuse_reflectance(c: ArrayLike, db: ColorantDatabase | None = None) -> NDArray[np.float64]:
    """The diffuse body R_d (Kubelka–Munk + Saunderson, module docstring step 1), shape (..., 31)."""
    db = db or default_database()
    c = np.asarray(c, dtype=np.float64)
    ks = (K_BINDER + c @ db._k) / (S_BINDER + c @ db._s)
    r_inf = 1.0 + ks - np.sqrt(ks * ks + 2.0 * ks)
    return np.asarray(
        (1.0 - K1_SAUNDERSON) * (1.0 - K2_SAUNDERSON) * r_inf / (1.0 - K2_SAUNDERSON * r_inf),
        dtype=np.float64,
    )


def flake_area(c: ArrayLike, db: ColorantDatabase) -> NDArray[np.float64]:
    """Area fraction A_j covered by each effect pigment, shape (..., E): A = 1 − exp(−Σ σ_j c_j) shared in
    proportion to σ_j c_j (Beer–Lambert stacking, module docstring step 2)."""
    sc = np.asarray(c, dtype=np.float64)[..., db.effect_index] * db.coverage
    tot = sc.sum(-1, keepdims=True)
    share = np.where(tot > 1e-12, -np.expm1(-tot) / np.maximum(tot, 1e-12), 1.0)  # A/Σσc, → 1 at 0
    return np.asarray(sc * share, dtype=np.float64)


def body_filter(c: ArrayLike, db: ColorantDatabase | None = None) -> NDArray[np.float64]:
    """F(λ) = 1 − Σ_j A_j L_j(λ), shape (..., 31): the body seen through the thin-film platelets
    (:meth:`Flake.body_loss`); 1 without interference or pearl pigments."""
    db = db or default_database()
    return np.asarray(1.0 - flake_area(c, db) @ db.body_loss, dtype=np.float64)


def flake_reflectance(
    c: ArrayLike, angles_deg: tuple[float, ...], db: ColorantDatabase | None = None
) -> NDArray[np.float64]:
    """The flake term R_f (module docstring step 2), shape (..., A, 31); zero without effect pigments."""
    db = db or default_database()
    c = np.asarray(c, dtype=np.float64)
    table = db.flake_table(angles_deg)  # (E, A, 31)
    area = flake_area(c, db)  # (..., E)
    ext = (c @ db._k_above + db.scatter_extinction * (c @ db._s_above)) * db.flake_depth  # (..., 31)
    g = flake_geometry(angles_deg)
    atten = np.exp(-ext[..., None, :] * g.path[:, None])  # (..., A, 31)
    atten_d = np.exp(-ext * (1.0 / np.cos(g.phi_i[0]) + 2.0)) if g.phi_i.size else ext  # (..., 31)
    diffuse = (area @ db.diffuse_albedo)[..., None, :] * g.transfer[:, None] * atten_d[..., None, :]
    return np.asarray(np.einsum("...e,eaw->...aw", area, table) * atten + diffuse, dtype=np.float64)


def predict_reflectance(
    c: ArrayLike, angles_deg: tuple[float, ...], db: ColorantDatabase | None = None
) -> NDArray[np.float64]:
    """Predict reflectance factors per angle: R = R_d F + R_f (module docstring).

    Parameters
    ----------
    c
        Mass fractions, shape (..., n_colorants).
    angles_deg
        Aspecular angles in degrees.

    Returns
    -------
    ndarray
        Radiance factors ≥ 0, shape (..., len(angles_deg), 31) on 400–700 nm / 10 nm; the diffuse part
        is below 1, the flake part may exceed 1 near specular.
    """
    db = db or default_database()
    r_d = diffuse_reflectance(c, db) * body_filter(c, db)
    return np.asarray(r_d[..., None, :] + flake_reflectance(c, angles_deg, db), dtype=np.float64)


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
    """Predict 60° gloss in GU from the matting fraction: G = G_clear − g c_matting."""
    db = db or default_database()
    c = np.asarray(c, dtype=np.float64)
    return GLOSS_CLEAR_GU - GLOSS_PER_MATTING * c[..., db.matting_index]
