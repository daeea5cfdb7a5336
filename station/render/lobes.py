"""Cosine-lobe basis and the (light, view) geometries at which designed BRDFs are sampled (thesis §2.3–§2.4).

A basis is a tuple of Phong exponents E_i shared by every design (eq 2.3.4 chooses them). The lobe
(R·V)^E_i is a function of the aspecular angle α only: R is the mirror direction of the light, so
R·V = cos α (eq 2.4.2 samples it at angles Θ_1..Θ_n).

Sample geometries (documented in docs/render-fit.md). The surface normal is +z. The light comes from
incidence θ_i in the x–z plane, L = (sin θ_i, 0, cos θ_i), with mirror direction R = (−sin θ_i, 0, cos θ_i).
The view is R turned by the aspecular angle α towards azimuth φ about R:

    V = cos α · R + sin α · (cos φ · e1 + sin φ · e2),   e1 = (cos θ_i, 0, sin θ_i),  e2 = (0, 1, 0),

so φ = 0° is in plane towards the light (the instrument's positive aspecular angles, 45as15 … 45as110),
φ = 180° in plane away from it (45as−15), and φ = 90°, 270° out of plane. Views below 3° elevation are
dropped. Two sets:

* colour rows: θ_i ∈ {15, 45, 65}°, α ∈ COLOUR_ALPHAS_DEG (0–120°), φ ∈ {0, 60, 120, 180, 240, 300}°;
* gloss rows:  θ_i ∈ {20, 45, 60}°,  α ∈ GLOSS_ALPHAS_DEG (0–40°, dense near 0), φ ∈ {0, 90, 180, 270}°.

Each row carries a weight √(ΔΩ), ΔΩ the solid angle of its (α, φ) cell about R, so a weighted least-
squares fit approximates the L2 norm of the BRDF error over the sphere of views.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.errors import InputError

#: Aspecular angles (degrees) of the colour rows (the clamped quadratic spans 0–110°+).
COLOUR_ALPHAS_DEG = (
    0.0,
    5.0,
    10.0,
    15.0,
    20.0,
    25.0,
    30.0,
    35.0,
    40.0,
    45.0,
    50.0,
    55.0,
    60.0,
    65.0,
    70.0,
    75.0,
    80.0,
    90.0,
    100.0,
    110.0,
    120.0,
)
COLOUR_INCIDENCES_DEG = (15.0, 45.0, 65.0)
COLOUR_AZIMUTHS_DEG = (0.0, 60.0, 120.0, 180.0, 240.0, 300.0)
#: Aspecular angles (degrees) of the gloss rows: dense near specular to resolve lobes up to E ~ 10⁴.
GLOSS_ALPHAS_DEG = (
    0.0,
    0.25,
    0.5,
    0.75,
    1.0,
    1.25,
    1.5,
    2.0,
    2.5,
    3.0,
    3.5,
    4.0,
    5.0,
    6.0,
    7.0,
    8.0,
    10.0,
    12.0,
    14.0,
    17.0,
    20.0,
    25.0,
    30.0,
    40.0,
)
GLOSS_INCIDENCES_DEG = (20.0, 45.0, 60.0)
GLOSS_AZIMUTHS_DEG = (0.0, 90.0, 180.0, 270.0)
#: Lowest view elevation kept (degrees above the tangent plane).
MIN_VIEW_ELEVATION_DEG = 3.0
#: Accepted exponent range of a basis lobe.
EXPONENT_RANGE = (0.5, 1.0e5)
#: Most lobes a basis may hold (thesis Fig. 2.4 stops at eleven).
MAX_LOBES = 11


@dataclass(frozen=True)
class LobeBasis:
    """A shared set of Phong exponents E_1..E_m (eq 2.3.2), in increasing order.

    Parameters
    ----------
    exponents
        Phong exponents (dimensionless), EXPONENT_RANGE[0] <= E <= EXPONENT_RANGE[1], 1 to MAX_LOBES of
        them. Near-duplicates are accepted (the fitters stay stable); they are sorted.
    """

    exponents: tuple[float, ...]

    def __post_init__(self) -> None:
        try:
            e = np.asarray(self.exponents, dtype=float).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise InputError("exponents", "a sequence of numbers", self.exponents) from exc
        lo, hi = EXPONENT_RANGE
        if not 1 <= e.size <= MAX_LOBES:
            raise InputError("exponents", f"1 to {MAX_LOBES} Phong exponents", e.size)
        if not np.all(np.isfinite(e)) or np.any(e < lo) or np.any(e > hi):
            raise InputError("exponents", f"finite {lo:g} <= E <= {hi:g}", tuple(e.tolist()))
        object.__setattr__(self, "exponents", tuple(float(x) for x in np.sort(e)))

    @property
    def size(self) -> int:
        """Number m of lobes."""
        return len(self.exponents)

    def lobes(self, cos_alpha: ArrayLike) -> NDArray[np.float64]:
        """Return max(cos α, 0)^E_i, shape (..., m) (eq 2.4.2)."""
        c = np.clip(np.asarray(cos_alpha, dtype=float), 0.0, 1.0)[..., None]
        return c ** np.asarray(self.exponents)


@dataclass(frozen=True)
class SampleGeometries:
    """Light/view geometries (N = +z) at which a designed BRDF is sampled for fitting.

    Attributes (all arrays of one length n)
    ----------------------------------------
    light, view
        (n, 3) unit vectors L and V.
    n_dot_l, n_dot_v
        Cosines of incidence and of view.
    cos_alpha, alpha_deg
        R·V and the aspecular angle α in degrees.
    weight
        √(solid angle of the row's cell), sr^½.
    gloss
        True for a gloss row, False for a colour row.
    """

    light: NDArray[np.float64]
    view: NDArray[np.float64]
    n_dot_l: NDArray[np.float64]
    n_dot_v: NDArray[np.float64]
    cos_alpha: NDArray[np.float64]
    alpha_deg: NDArray[np.float64]
    weight: NDArray[np.float64]
    gloss: NDArray[np.bool_]

    def __len__(self) -> int:
        return int(self.n_dot_l.size)


def _cell_solid_angles(alphas_deg: tuple[float, ...], n_azimuths: int) -> NDArray[np.float64]:
    """Solid angle (sr) of the cell of each α ring divided among *n_azimuths* azimuths."""
    a = np.radians(np.asarray(alphas_deg))
    edges = np.concatenate([[0.0], 0.5 * (a[1:] + a[:-1]), [a[-1] + 0.5 * (a[-1] - a[-2])]])
    ring = 2.0 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:]))
    return ring / n_azimuths


def _geometry_block(
    incidences: tuple[float, ...], alphas: tuple[float, ...], azimuths: tuple[float, ...], gloss: bool
) -> dict[str, NDArray[np.float64]]:
    grid = np.meshgrid(np.radians(incidences), np.radians(alphas), np.radians(azimuths), indexing="ij")
    cell_grid = np.broadcast_to(_cell_solid_angles(alphas, len(azimuths))[None, :, None], grid[0].shape)
    ti, al, ph, cell = (x.reshape(-1) for x in (*grid, cell_grid))
    light = np.stack([np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=-1)
    mirror = np.stack([-np.sin(ti), np.zeros_like(ti), np.cos(ti)], axis=-1)
    e1 = np.stack([np.cos(ti), np.zeros_like(ti), np.sin(ti)], axis=-1)
    e2 = np.stack([np.zeros_like(ti), np.ones_like(ti), np.zeros_like(ti)], axis=-1)
    view = np.cos(al)[:, None] * mirror + np.sin(al)[:, None] * (
        np.cos(ph)[:, None] * e1 + np.sin(ph)[:, None] * e2
    )
    keep = view[:, 2] >= np.sin(np.radians(MIN_VIEW_ELEVATION_DEG))
    # α = 0 rows repeat for every azimuth: keep one, with the whole polar cap.
    first_az = np.isclose(ph, ph.min())
    cap = al == 0.0
    keep &= ~cap | first_az
    cell = np.where(cap, cell * len(azimuths), cell)
    return {
        "light": light[keep],
        "view": view[keep],
        "alpha": al[keep],
        "cell": cell[keep],
        "gloss": np.full(int(keep.sum()), gloss),
    }


@lru_cache(maxsize=1)
def sample_geometries() -> SampleGeometries:
    """Return the documented colour + gloss sample geometries (see module docstring)."""
    blocks = [
        _geometry_block(COLOUR_INCIDENCES_DEG, COLOUR_ALPHAS_DEG, COLOUR_AZIMUTHS_DEG, gloss=False),
        _geometry_block(GLOSS_INCIDENCES_DEG, GLOSS_ALPHAS_DEG, GLOSS_AZIMUTHS_DEG, gloss=True),
    ]
    cat = {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}
    light, view = cat["light"], cat["view"]
    mirror = light * np.array([-1.0, -1.0, 1.0])
    cos_alpha = np.clip(np.einsum("ij,ij->i", mirror, view), -1.0, 1.0)
    geo = SampleGeometries(
        light=light,
        view=view,
        n_dot_l=light[:, 2].copy(),
        n_dot_v=view[:, 2].copy(),
        cos_alpha=cos_alpha,
        alpha_deg=np.degrees(np.arccos(cos_alpha)),
        weight=np.sqrt(cat["cell"]),
        gloss=cat["gloss"].astype(bool),
    )
    for arr in (
        geo.light,
        geo.view,
        geo.n_dot_l,
        geo.n_dot_v,
        geo.cos_alpha,
        geo.alpha_deg,
        geo.weight,
        geo.gloss,
    ):
        arr.setflags(write=False)
    return geo


class BasisRow(TypedDict):
    """One row of the shipped basis table: the optimal exponents for a lobe count and their ΔE errors."""

    lobes: int
    exponents: list[float]
    max_error_de: float
    mean_error_de: float
    objective: float


class BasisTable(TypedDict):
    """The shipped basis-selection result (``data/lobe_basis.json``)."""

    schema: str
    default_lobes: int
    objective: str
    note: str
    bases: list[BasisRow]


def basis_table() -> BasisTable:
    """Return the shipped basis-selection result (station/render/data/lobe_basis.json) as a dict."""
    return json.loads(_basis_text())


@lru_cache(maxsize=1)
def _basis_text() -> str:
    return resources.files("station.render").joinpath("data/lobe_basis.json").read_text()


def basis_for_count(m: int) -> LobeBasis:
    """Return the shipped optimal basis with *m* lobes (1 <= m <= MAX_LOBES), eq 2.3.4."""
    table = basis_table()
    rows = {int(r["lobes"]): r for r in table["bases"]}
    if m not in rows:
        raise InputError("lobes", f"one of {sorted(rows)}", m)
    return LobeBasis(tuple(rows[m]["exponents"]))


#: The default basis calibrated on the demo library (``python -m bench.library_basis --write``).
LIBRARY_BASIS = Path(__file__).parent / "data" / "lobe_basis_library.json"


@lru_cache(maxsize=1)
def default_basis() -> LobeBasis:
    """Return the shipped default basis: the table's ``default_lobes`` row (eq 2.3.4 over the design
    database) with the lobes its calibration on a training split of the demo library moved added
    (LIBRARY_BASIS, ``bench.library_basis``: 7 lobes), or the row alone where no calibration is shipped."""
    if LIBRARY_BASIS.is_file():
        return LobeBasis(tuple(float(e) for e in json.loads(LIBRARY_BASIS.read_text())["exponents"]))
    return basis_for_count(int(basis_table()["default_lobes"]))


def horizon_factors(
    exponent: float, r_dot_n: ArrayLike, nodes: int = 1024
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Cosine and horizon factors of a normalised lobe about R at angle β from N (cos β = R·N).

    Returns (g, h), each shaped like *r_dot_n*, with p(ω) = (E+1)/(2π) max(R·ω, 0)^E:

        g = ∫ p(ω) max(N·ω, 0) dω     (what the directionally diffuse term needs, eq 2.3.3)
        h = ∫ p(ω) 1[N·ω > 0] dω       (the part of a gloss lobe above the horizon, eq 2.3.2)

    A renderer that looks up one prefiltered map C_E(R) per lobe (eqs 2.5.1–2.5.2) is exact in a
    constant environment when it weights K_DD by g instead of R·N and K_G by h. For E → ∞, g → R·N and
    h → 1. The azimuthal integral about R is closed-form; the polar one uses *nodes* midpoints in
    u = cos^(E+1) ψ (equal lobe mass each).
    """
    c = np.clip(np.asarray(r_dot_n, dtype=float), -1.0, 1.0)
    u = (np.arange(nodes) + 0.5) / nodes
    cos_psi = u ** (1.0 / (exponent + 1.0))
    sin_psi = np.sqrt(np.maximum(0.0, 1.0 - cos_psi**2))
    sin_b = np.sqrt(np.maximum(0.0, 1.0 - c**2))[..., None]
    a = c[..., None] * cos_psi  # N·ω = a + b cos φ
    b = sin_b * sin_psi
    with np.errstate(divide="ignore", invalid="ignore"):
        phi0 = np.where(
            b > 1e-15,
            np.arccos(np.clip(-a / np.where(b > 1e-15, b, 1.0), -1.0, 1.0)),
            np.where(a > 0, np.pi, 0.0),
        )
    g = (2.0 * (a * phi0 + b * np.sin(phi0)) / (2.0 * np.pi)).mean(axis=-1)
    h = (phi0 / np.pi).mean(axis=-1)
    return g, h


#: Sharpness of the spherical Gaussian that best matches the clamped cosine (N·ω)₊ (amplitude 1.17):
#: the product rule of spherical Gaussians bends a lobe cos^E(R·ω) times (N·ω) towards N.
COSINE_SG_SHARPNESS = 2.133


def bent_direction(exponent: float, reflect: ArrayLike, normal: ArrayLike) -> NDArray[np.float64]:
    """Lookup direction B = normalize(E·R + 2.133·N) for a directionally diffuse lobe (eq 2.5.1).

    (N·ω)(R·ω)^E is, as a product of spherical Gaussians, a lobe about B; looking the prefiltered map up
    at B (weighted by g of :func:`horizon_factors`) instead of at R fixes most of eq 2.5.1's error for
    wide lobes under uneven light (docs/render-fit.md §7). Shapes (..., 3) → (..., 3).
    """
    b = exponent * np.asarray(reflect, dtype=float) + COSINE_SG_SHARPNESS * np.asarray(normal, dtype=float)
    return b / np.linalg.norm(b, axis=-1, keepdims=True)
