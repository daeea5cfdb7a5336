"""Goniogeometric index (thesis eq 4.3.1) and the seam colour difference it is built on.

``β_min = min β | ΔE(c(f, Ω, Ψ), c(f, Ω_β, Ψ_β)) ≥ ε`` — the smallest misalignment, in degrees, at
which two panels painted with the same paint differ by ε (default 2.3 ΔE*ab, one JND as in the thesis).
Colours ``c`` are defined in :mod:`station.analysis.shading`, the geometry in
:mod:`station.analysis.geometry`.

Root finding (first crossing, so a non-monotone ΔE(β) never yields a later root):

1. Bracket: ΔE − ε on a uniform grid ``0 … β_max`` (step ``grid_step_deg``, default 0.25°), all
   geometries and both rotation directions in one vectorised evaluation.
2. Guard against a crossing hidden between grid points: with ``K_j`` twice the largest second
   difference next to interval j (a local curvature bound), an interval whose bound
   ``max(F_j, F_{j+1}) + K_j h²/8`` reaches 0 is subdivided (16 points, recursively, down to 1e-3°)
   before the first bracketed crossing is accepted.
3. Two vectorised 32-fold subdivisions of the bracket, then Brent's method (:func:`scipy.optimize.brentq`,
   ``xtol = 1e-7°``) inside the first bracket of the row(s) that can hold the minimum. Stated
   resolution: 1e-6° on β_min. Steps 2 and 3: :mod:`station.analysis.bracket`; the seam ΔE itself:
   :class:`station.analysis.seam_model.SeamModel`.

When ΔE stays below ε up to β_max (or up to the angle at which panel B turns away from the viewer),
the result says so: ``reached = False``, ``beta_min_deg = None`` and the largest ΔE seen.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from station.analysis.bracket import brent, first_bracket, shrink
from station.analysis.errors import AnalysisInputError
from station.analysis.geometry import (
    Direction,
    Hinge,
    SeamGeometry,
    check_polar,
)
from station.analysis.seam_model import SeamModel
from station.analysis.shading import Environment, Exposure
from station.model.domain import BETA_MAX_RANGE_DEG, GRID_STEP_RANGE_DEG, INDEX_RESOLUTION_DEG
from station.model.domain import JND_CIE76 as DOMAIN_JND_CIE76

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: ε of the thesis: one JND, in ΔE*ab.
JND_CIE76 = DOMAIN_JND_CIE76
#: The stated resolution of β_min (degrees; Brent's tolerance is ``station.analysis.bracket.BRENT_XTOL_DEG``).
RESOLUTION_DEG = INDEX_RESOLUTION_DEG
#: Aspecular angles (degrees) scanned when no view is given for an effect paint: the measured range.
DEFAULT_ASPECULAR_SCAN = tuple(float(a) for a in range(15, 111, 5))

Light = float | Sequence[float] | Environment


@dataclass(frozen=True)
class GeometryIndex:
    """β_min of one geometry and rotation direction (approximate unless it is the overall minimum)."""

    light_deg: float | None
    view_deg: float
    direction: str
    beta_min_deg: float | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form: the fields as they are."""
        return asdict(self)


@dataclass(frozen=True)
class IndexResult:
    """Goniogeometric index over the requested geometries (eq 4.3.1).

    Attributes
    ----------
    beta_min_deg
        Smallest misalignment in degrees giving ΔE ≥ ε, or ``None`` when ε is never reached.
    reached
        Whether ε was reached within the search range.
    direction
        ``"+"`` or ``"-"``: the rotation direction attaining β_min (``None`` when not reached).
    geometry
        The lighting / viewing geometry attaining β_min (JSON-able dict; for an environment the light
        is ``"environment"``).
    epsilon, method
        Threshold and ΔE formula.
    beta_max_deg
        Upper end of the search.
    max_delta_e
        Largest ΔE seen on the grid (over all geometries and directions) up to β_max.
    resolution_deg
        Stated resolution of β_min.
    message
        One human-readable sentence.
    per_geometry
        β_min for each geometry and direction; values other than the overall minimum are linear
        interpolations inside the grid bracket (accurate to about the grid step squared).
    """

    beta_min_deg: float | None
    reached: bool
    direction: str | None
    geometry: dict[str, Any]
    epsilon: float
    method: str
    beta_max_deg: float
    max_delta_e: float
    resolution_deg: float = RESOLUTION_DEG
    message: str = ""
    per_geometry: tuple[GeometryIndex, ...] = field(default=(), repr=False)

    def to_dict(self, per_geometry: bool = False) -> dict[str, Any]:
        """JSON-able form (the CLI's ``--json`` output): the fields, ``per_geometry`` only when asked."""
        out = asdict(self)
        rows = out.pop("per_geometry")
        if per_geometry:
            out["per_geometry"] = list(rows)
        return out


def _check_positive(value: float, field_name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise AnalysisInputError(field_name, "a positive number", value) from exc
    if not math.isfinite(v) or v <= 0:
        raise AnalysisInputError(field_name, f"{field_name} > 0", value)
    return v


def _check_range(value: float, field_name: str, bounds: tuple[float, float]) -> float:
    lo, hi = bounds
    accepted = f"{lo:g} <= {field_name} <= {hi:g}"
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise AnalysisInputError(field_name, accepted, value) from exc
    if not lo <= v <= hi:  # NaN fails too
        raise AnalysisInputError(field_name, accepted, value)
    return v


def _as_list(values: float | Sequence[float], field_name: str) -> list[float]:
    if isinstance(values, (int, float, np.floating, np.integer)):
        values = [float(values)]
    vals = list(values)
    if not vals:
        raise AnalysisInputError(field_name, "at least one angle in degrees", vals)
    return [check_polar(v, f"{field_name}[{i}]") for i, v in enumerate(vals)]


def default_views(paint: FaceFlopTravelGloss, lights: list[float]) -> tuple[list[float], list[float]]:
    """Geometries scanned when no view is given: one view for a solid, aspecular 15–110° otherwise.

    Returns parallel lists (lights, views) in degrees; views whose polar angle exceeds 89° are dropped.
    """
    if getattr(paint, "is_solid", False):
        return list(lights), [0.0 if abs(lt) > 1e-9 else 1.0 for lt in lights]
    ls, vs = [], []
    for lt in lights:
        for asp in DEFAULT_ASPECULAR_SCAN:
            v = asp - lt
            if abs(v) <= 89.0:
                ls.append(lt)
                vs.append(v)
    return ls, vs


def goniogeometric_index(
    paint: FaceFlopTravelGloss,
    light: Light,
    view: float | Sequence[float] | None = None,
    *,
    epsilon: float = JND_CIE76,
    method: str = "cie76",
    hinge: Hinge = "in-plane",
    direction: Direction = "either",
    beta_max_deg: float = 30.0,
    grid_step_deg: float = 0.25,
    exposure: Exposure = "reference",
    gloss: bool = False,
) -> IndexResult:
    """Goniogeometric index β_min (eq 4.3.1) of *paint* over the given lights and views.

    Parameters
    ----------
    paint
        The paint (``FaceFlopTravelGloss``; a solid has face = flop), identical on both panels.
    light
        A point light's signed polar angle in degrees, a sequence of them, or an :class:`Environment`.
    view
        Viewer polar angle(s) in degrees (signed, same convention). With several lights and several
        views every pair is used. ``None``: one view for a solid (the index does not depend on it),
        views at aspecular 15°–110° (step 5°) for an effect paint.
    epsilon
        Threshold ε in units of *method* (default 2.3, one JND in ΔE*ab).
    method
        ΔE formula: ``cie76`` | ``cie94`` | ``cie2000`` | ``din6175``.
    hinge
        ``"in-plane"`` | ``"out-of-plane"`` | hinge azimuth in degrees.
    direction
        ``"+"``, ``"-"`` or ``"either"`` (the smaller of the two).
    beta_max_deg
        Largest misalignment searched, degrees (``BETA_MAX_RANGE_DEG``: 1e-6 ≤ β_max ≤ 89).
    grid_step_deg
        Bracketing grid step in degrees (``GRID_STEP_RANGE_DEG``: 0.001 ≤ step ≤ 1).
    exposure, gloss
        See :mod:`station.analysis.shading`.

    Returns
    -------
    IndexResult
        β_min (degrees, resolution 1e-6°), the direction and geometry attaining it, or ``reached=False``.
    """
    eps = _check_positive(epsilon, "epsilon")
    bmax = _check_range(beta_max_deg, "beta_max_deg", BETA_MAX_RANGE_DEG)
    step = _check_range(grid_step_deg, "grid_step_deg", GRID_STEP_RANGE_DEG)
    if direction not in ("+", "-", "either"):
        raise AnalysisInputError("direction", '"+", "-" or "either"', direction)
    if isinstance(light, Environment):
        views = [0.0] if view is None else _as_list(view, "view_deg")
        model = SeamModel(light, views, hinge=hinge, method=method, exposure=exposure, gloss=gloss)
    else:
        lights = _as_list(light, "light_deg")
        if view is None:
            ls, vs = default_views(paint, lights)
        else:
            views = _as_list(view, "view_deg")
            ls = [lt for lt in lights for _ in views]
            vs = [v for _ in lights for v in views]
        model = SeamModel(ls, vs, hinge=hinge, method=method, exposure=exposure, gloss=gloss)
    signs = {"+": (1.0,), "-": (-1.0,), "either": (1.0, -1.0)}[direction]
    return _search(model, paint, eps, bmax, step, signs)


#: Orientations of panel A for :func:`environment_index`: its normal in the world (+Y up).
PANEL_FRAMES: dict[str, NDArray[np.float64]] = {
    # rows: the panel's x, y, z (normal) axes in world coordinates (right-handed)
    "up": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),  # a bonnet or roof
    "front": np.eye(3),  # a door facing +Z
}


def environment_index(
    paint: FaceFlopTravelGloss,
    directions: NDArray[np.float64],
    radiance: NDArray[np.float64],
    view: float | Sequence[float] | None = None,
    *,
    panel: str = "up",
    **options: Any,
) -> IndexResult:
    """Environment-lit goniogeometric index (eq 4.3.1 with c of an environment, thesis §4.3): the
    environment given as world samples — unit *directions* (n, 3) (+Y up) and radiance × solid angle
    *radiance* (n, 3) — is turned into the frame of panel A (``panel``: ``"up"`` a horizontal panel,
    ``"front"`` a vertical one facing +Z; PANEL_FRAMES) and :func:`goniogeometric_index` searched over
    the views (signed polar angles in the panel's x–z plane; None: normal view) with *options* (epsilon,
    method, hinge, direction, beta_max_deg, grid_step_deg, gloss)."""
    if panel not in PANEL_FRAMES:
        raise AnalysisInputError("panel", " | ".join(PANEL_FRAMES), panel)
    d = np.asarray(directions, dtype=float)
    if d.ndim != 2 or d.shape[-1:] != (3,):
        raise AnalysisInputError("environment.directions", "an (n, 3) array of unit vectors", d.shape)
    env = Environment(d @ PANEL_FRAMES[panel].T, np.asarray(radiance, dtype=float))
    return goniogeometric_index(paint, env, view, **options)


Bracket = tuple[float, float, int, int]  # (lo, hi, geometry row, direction index), F(lo) < 0 <= F(hi)


def _search(
    model: SeamModel,
    paint: FaceFlopTravelGloss,
    eps: float,
    bmax: float,
    step: float,
    signs: tuple[float, ...],
) -> IndexResult:
    """β_min over every geometry row and direction: grid brackets, then the first crossing (eq 4.3.1)."""
    n = max(3, math.ceil(bmax / step) + 1)
    grid = np.linspace(0.0, bmax, n)
    signed = np.concatenate([s * grid for s in signs])  # (S·n,)
    G, S = model.size, len(signs)
    de = model.delta_e(paint, paint, signed).reshape(G, S, n)  # (G, S, n)
    # Beyond the first invisible β the row ends.
    vis = np.cumprod(model.visible(signed).reshape(G, S, n), axis=-1).astype(bool)
    F = np.where(vis, de - eps, -np.inf)
    max_de = float(np.max(np.where(vis, de, 0.0)))

    brackets: list[Bracket] = []
    for g in range(G):
        for si in range(S):
            br = first_bracket(model, paint, eps, signs[si], g, grid, F[g, si])
            if br is not None:
                brackets.append((br[0], br[1], g, si))
    if not brackets:
        per = tuple(
            GeometryIndex(_light(model, g), float(model.view_deg[g]), "+" if s > 0 else "-", None)
            for g in range(G)
            for s in signs
        )
        return IndexResult(
            None,
            False,
            None,
            _geometry_dict(model, 0),
            eps,
            model.method,
            bmax,
            max_de,
            message=(f"ε = {eps:g} is never reached up to β = {bmax:g}° (largest ΔE seen {max_de:.3g})"),
            per_geometry=per,
        )
    (beta, g, si), approx = _roots(model, paint, eps, signs, brackets)
    per = tuple(
        GeometryIndex(
            _light(model, gg), float(model.view_deg[gg]), "+" if signs[ss] > 0 else "-", approx.get((gg, ss))
        )
        for gg in range(G)
        for ss in range(S)
    )
    d = "+" if signs[si] > 0 else "-"
    return IndexResult(
        beta,
        True,
        d,
        _geometry_dict(model, g),
        eps,
        model.method,
        bmax,
        max_de,
        message=f"ΔE reaches {eps:g} at β = {beta:.4f}° (direction {d})",
        per_geometry=per,
    )


def _roots(
    model: SeamModel,
    paint: FaceFlopTravelGloss,
    eps: float,
    signs: tuple[float, ...],
    brackets: list[Bracket],
) -> tuple[tuple[float, int, int], dict[tuple[int, int], float]]:
    """The overall first crossing ``(β, row, direction index)`` from non-empty *brackets*, and β of
    every (row, direction): Brent's root where the bracket can hold the minimum, else linear
    interpolation inside the bracket."""
    best_hi = min(b[1] for b in brackets)
    known: dict[tuple[int, int], dict[float, float]] = {}
    # Shrink the brackets that can hold the minimum (vectorised, 32-fold per pass, two passes), then
    # run Brent only where the shrunken bracket still can.
    for _ in range(2):
        cand = [i for i, b in enumerate(brackets) if b[0] <= best_hi]
        shrunk = shrink(model, paint, eps, signs, [brackets[i] for i in cand], known)
        for i, lohi in zip(cand, shrunk, strict=True):
            brackets[i] = (*lohi, brackets[i][2], brackets[i][3])
        best_hi = min(b[1] for b in brackets)
    best: tuple[float, int, int] | None = None
    approx: dict[tuple[int, int], float] = {}
    rest = []
    for lo, hi, g, si in brackets:
        if lo <= best_hi:
            root = brent(model, paint, eps, signs[si], g, lo, hi, known.get((g, si)))
            approx[(g, si)] = root
            if best is None or root < best[0]:
                best = (root, g, si)
        else:
            rest.append((lo, hi, g, si))
    if rest:  # the other rows: linear interpolation inside their bracket, one vectorised evaluation
        ends = np.array([[signs[si] * lo, signs[si] * hi] for lo, hi, _, si in rest])
        F = model.delta_e_rows(paint, paint, ends, np.array([g for _, _, g, _ in rest])) - eps
        for (lo, hi, g, si), (flo, fhi) in zip(rest, F, strict=True):
            approx[(g, si)] = float(lo + (hi - lo) * (-flo) / (fhi - flo)) if fhi > flo else hi
    assert best is not None  # noqa: S101 - brackets is non-empty
    return best, approx


def _light(model: SeamModel, g: int) -> float | None:
    return None if model.env is not None else float(model.light_deg[g])


def _geometry_dict(model: SeamModel, g: int) -> dict[str, Any]:
    if model.env is not None:
        return {
            "light": "environment",
            "view_deg": float(model.view_deg[g]),
            "hinge": model.hinge if isinstance(model.hinge, str) else float(model.hinge),
        }
    return SeamGeometry(float(model.light_deg[g]), float(model.view_deg[g]), model.hinge).to_dict()
