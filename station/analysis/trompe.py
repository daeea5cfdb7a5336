"""Inverse trompe l'oeil (thesis §4.4): a second paint that hides a misaligned seam.

Panel A keeps paint A; panel B, rotated by β about the hinge, gets paint B chosen to minimise the seam
colour difference ``ΔE_g = ΔE(c(A, panel A, g), c(B, panel B, g))`` over a set of lighting / viewing
geometries g (colours as in :mod:`station.analysis.shading`). Objectives (thesis §4.4.1):

* ``"single"``: one geometry (the thesis's "optimised at 45°" column), ``min ΔE_g²``;
* ``"rms"``: ``min mean_g ΔE_g²`` (the thesis's RMS column);
* ``"minimax"``: ``min max_g ΔE_g`` in epigraph form, ``min t  s.t.  t ≥ ΔE_g²`` (SLSQP);
* ``"per_geometry"``: one paint per geometry (the thesis's last column).

Free parameters: a named subset of ``face_L, face_a, face_b, flop_L, flop_a, flop_b, travel_deg``
(:data:`SUBSETS`; the others stay at paint A's values); for a solid, ``"solid"`` = its L*, a*, b*.
A tiny Tikhonov term ``1e-8 Σ (x − x_A)²`` picks the solution nearest paint A when several fit equally.

Constraints: the paintable bound of :mod:`station.analysis.gamut` (sRGB chromaticity, reflectance
bound, face not darker than flop unless ``allow_face_darker``), model ranges as box bounds
(0 ≤ L* ≤ 200, |a*|, |b*| ≤ 150, 15° < travel ≤ 180°). When the best paint leaves some seam above ε the
result says so (``meets_epsilon = False``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

from station.analysis.errors import AnalysisError, AnalysisInputError
from station.analysis.gamut import GamutReport, check_paintable, rgb_bounds
from station.analysis.geometry import Hinge, SeamGeometry, check_polar
from station.analysis.index import JND_CIE76
from station.analysis.options import OBJECTIVES, Objective
from station.analysis.seam_model import SeamModel
from station.analysis.shading import Environment, Exposure
from station.model.colorimetry import lab_to_linear_srgb
from station.model.domain import FACE_ANGLE_DEG, LAB_RANGES, TRAVEL_MAX_DEG
from station.wire import wire_form

PARAMS = ("face_L", "face_a", "face_b", "flop_L", "flop_a", "flop_b", "travel_deg")
#: Named parameter subsets.
SUBSETS: dict[str, tuple[str, ...]] = {
    "solid": ("L", "a", "b"),
    "face_L": ("face_L",),
    "face_L+travel": ("face_L", "travel_deg"),
    "lightness": ("face_L", "flop_L"),
    "lightness+travel": ("face_L", "flop_L", "travel_deg"),
    "face": ("face_L", "face_a", "face_b"),
    "face+travel": ("face_L", "face_a", "face_b", "travel_deg"),
    "full": PARAMS,
}
#: Search bounds: the domain's Lab bound and travel range (station.model.domain).
_BOUNDS = {**LAB_RANGES, "travel_deg": (FACE_ANGLE_DEG + 1e-3, TRAVEL_MAX_DEG)}
_REG = 1e-8


def _bound(name: str) -> tuple[float, float]:
    return _BOUNDS["travel_deg"] if name == "travel_deg" else _BOUNDS[name[-1]]


@dataclass(frozen=True)
class TrompeResult:
    """Result of an inverse trompe l'oeil solve.

    Attributes
    ----------
    objective, subset
        What was minimised and over which parameters.
    paint
        Paint B (``FaceFlopTravelGloss``); for ``per_geometry`` the one of the first geometry.
    paints
        One paint per geometry for ``per_geometry``, else ``(paint,)``.
    geometries
        The geometries, in order.
    beta_deg
        Signed misalignment in degrees.
    seam_de_before, seam_de_after
        Seam ΔE per geometry with paint A on both panels, and with the solution.
    meets_epsilon
        Whether every seam ΔE after the solve is ≤ ε.
    gamut
        Paintability of the solution (every paint for ``per_geometry``).
    changes
        Paint B − paint A per free parameter (Lab units, degrees for travel).
    solve_ms
        Wall time of the solve.
    message
        One sentence.
    """

    objective: str
    subset: str
    paint: Any
    paints: tuple[Any, ...]
    geometries: tuple[SeamGeometry | EnvironmentGeometry, ...]
    beta_deg: float
    method: str
    epsilon: float
    seam_de_before: tuple[float, ...]
    seam_de_after: tuple[float, ...]
    meets_epsilon: bool
    gamut: GamutReport
    changes: dict[str, float]
    solve_ms: float
    message: str
    converged: bool = True
    per_geometry_changes: tuple[dict[str, float], ...] = field(default=(), repr=False)

    @property
    def rms_before(self) -> float:
        """RMS seam ΔE with paint A on both panels."""
        return float(np.sqrt(np.mean(np.square(self.seam_de_before))))

    @property
    def rms_after(self) -> float:
        """RMS seam ΔE with the solution."""
        return float(np.sqrt(np.mean(np.square(self.seam_de_after))))

    @property
    def max_before(self) -> float:
        """Worst seam ΔE with paint A on both panels."""
        return float(np.max(self.seam_de_before))

    @property
    def max_after(self) -> float:
        """Worst seam ΔE with the solution."""
        return float(np.max(self.seam_de_after))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form; paints as ``cacad.design/1``-like dicts."""
        per_geometry = self.objective == "per_geometry"
        return wire_form(
            self,
            omit={"paint", "paints", "geometries", "converged", "per_geometry_changes"},
            after={
                "epsilon": {
                    "paint": paint_to_dict(self.paint),
                    "paints": [paint_to_dict(p) for p in self.paints] if per_geometry else None,
                    "geometries": self.geometries,
                },
                "seam_de_after": {
                    "rms_before": self.rms_before,
                    "rms_after": self.rms_after,
                    "max_before": self.max_before,
                    "max_after": self.max_after,
                },
                "changes": {"converged": self.converged},
            },
        )


@dataclass(frozen=True)
class EnvironmentGeometry:
    """A view under environment lighting (the light is the whole environment)."""

    view_deg: float
    hinge: Hinge = "in-plane"

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return {
            "light": "environment",
            "view_deg": self.view_deg,
            "hinge": self.hinge if isinstance(self.hinge, str) else float(self.hinge),
        }


def paint_to_dict(paint: Any) -> dict[str, Any]:
    """A paint as a ``cacad.design/1`` dict (via the model's design_io when present)."""
    try:
        from station.model.design_io import design_to_dict

        return dict(design_to_dict(paint))
    except ImportError:  # pragma: no cover - design_io is part of the model API
        return {
            "schema": "cacad.design/1",
            "name": paint.name,
            "face": list(paint.face),
            "flop": list(paint.flop),
            "travel_deg": paint.travel_deg,
            "gloss_gu": paint.gloss_gu,
        }


class _Problem:
    """Parameter vector ⇄ paint B, seam ΔE per geometry, constraints."""

    def __init__(
        self, paint_a: Any, model: SeamModel, beta: float, names: tuple[str, ...], allow_face_darker: bool
    ) -> None:
        self.a = paint_a
        self.model = model
        self.beta = np.array([beta])
        self.names = names
        self.solid = names == SUBSETS["solid"]
        base = {
            "face_L": paint_a.face[0],
            "face_a": paint_a.face[1],
            "face_b": paint_a.face[2],
            "flop_L": paint_a.flop[0],
            "flop_a": paint_a.flop[1],
            "flop_b": paint_a.flop[2],
            "travel_deg": paint_a.travel_deg,
            "L": paint_a.face[0],
            "a": paint_a.face[1],
            "b": paint_a.face[2],
        }
        self.base = base
        self.x0 = np.array([float(base[n]) for n in names])
        self.bounds = [_bound(n) for n in names]
        self.x0 = np.clip(self.x0, [b[0] for b in self.bounds], [b[1] for b in self.bounds])
        self.allow_face_darker = allow_face_darker
        face_free = any(n.startswith("face") for n in names) or self.solid
        flop_free = any(n.startswith("flop") for n in names)
        self.face_free, self.flop_free = face_free, flop_free
        ra = lab_to_linear_srgb(np.stack([np.asarray(paint_a.face), np.asarray(paint_a.flop)]))
        lo, hi = rgb_bounds(paint_a.face, paint_a.flop, self.solid or paint_a.is_solid)
        self.lo, self.hi = np.minimum(lo, ra), np.maximum(hi, ra)
        self.face_darker_a = paint_a.face[0] < paint_a.flop[0]

    def values(self, x: NDArray[np.float64]) -> dict[str, float]:
        v = dict(self.base)
        v.update(zip(self.names, (float(t) for t in x), strict=True))
        return v

    def paint(self, x: NDArray[np.float64]) -> Any:
        v = self.values(x)
        if self.solid:
            lab = (v["L"], v["a"], v["b"])
            return self.a.replace(face=lab, flop=lab, travel_deg=None)
        face = (v["face_L"], v["face_a"], v["face_b"])
        flop = (v["flop_L"], v["flop_a"], v["flop_b"])
        return self.a.replace(
            face=face,
            flop=flop,
            travel_deg=v["travel_deg"] if face != flop or self.a.travel_deg is not None else None,
        )

    def de(self, x: NDArray[np.float64], rows: NDArray[np.intp] | None = None) -> NDArray[np.float64]:
        return self.model.delta_e(self.a, self.paint(x), self.beta, rows=rows)[:, 0]

    def reg(self, x: NDArray[np.float64]) -> float:
        return _REG * float(np.sum((x - self.x0) ** 2))

    def constraints(self) -> list[dict[str, Any]]:
        cons: list[dict[str, Any]] = []
        k = len(self.names)

        def gam(z: NDArray[np.float64]) -> NDArray[np.float64]:
            v = self.values(z[:k])
            if self.solid:
                rgb = lab_to_linear_srgb(np.array([v["L"], v["a"], v["b"]]))
                return np.concatenate([rgb - self.lo[0], self.hi[0] - rgb])
            labs = np.array(
                [[v["face_L"], v["face_a"], v["face_b"]], [v["flop_L"], v["flop_a"], v["flop_b"]]]
            )
            rgb = lab_to_linear_srgb(labs)
            parts = []
            for i, free in enumerate((self.face_free, self.flop_free)):
                if free:
                    parts += [rgb[i] - self.lo[i], self.hi[i] - rgb[i]]
            return np.concatenate(parts)

        if self.face_free or self.flop_free:
            cons.append({"type": "ineq", "fun": gam})
        if (
            not self.solid
            and not self.allow_face_darker
            and not self.face_darker_a
            and ("face_L" in self.names or "flop_L" in self.names)
        ):
            cons.append(
                {
                    "type": "ineq",
                    "fun": lambda z: np.array([self.values(z[:k])["face_L"] - self.values(z[:k])["flop_L"]]),
                }
            )
        return cons


def _geometries(lights: Sequence[float], views: Sequence[float] | None) -> tuple[list[float], list[float]]:
    ls = [check_polar(v, f"lights_deg[{i}]") for i, v in enumerate(lights)]
    if not ls:
        raise AnalysisInputError("lights_deg", "at least one light angle in degrees", list(lights))
    if views is None:
        vs = [0.0 if abs(lt) > 1e-9 else 1.0 for lt in ls]
    else:
        vs = [check_polar(v, f"views_deg[{i}]") for i, v in enumerate(views)]
        if len(vs) != len(ls):
            raise AnalysisInputError("views_deg", f"{len(ls)} view angles (one per light) or none", len(vs))
    return ls, vs


def inverse_trompe_loeil(
    paint_a: Any,
    lights_deg: Sequence[float] | Environment,
    views_deg: Sequence[float] | None = None,
    *,
    beta_deg: float,
    objective: Objective = "rms",
    at: int = 0,
    subset: str | None = None,
    hinge: Hinge = "in-plane",
    method: str = "cie76",
    epsilon: float = JND_CIE76,
    allow_face_darker: bool = False,
    exposure: Exposure = "reference",
    gloss: bool = False,
) -> TrompeResult:
    """Choose paint B for the misaligned panel (thesis §4.4).

    Parameters
    ----------
    paint_a
        Paint of the reference panel (``FaceFlopTravelGloss``).
    lights_deg, views_deg
        Geometries as parallel lists of signed polar angles in degrees (one view per light; ``None``
        views the panels from the normal, enough for solids). *lights_deg* may instead be an
        :class:`~station.analysis.shading.Environment`; the geometries are then the views under it.
    beta_deg
        Signed misalignment of panel B in degrees (sign = rotation direction, see
        :mod:`station.analysis.geometry`), ``0 < |β| ≤ 45``.
    objective
        ``"single"`` (geometry *at*), ``"rms"``, ``"minimax"`` or ``"per_geometry"``.
    subset
        Name in :data:`SUBSETS` or a ``"+"``-joined list of parameter names; default ``"solid"`` for a
        solid paint A, ``"full"`` otherwise.
    method, epsilon
        ΔE formula and the threshold the seams are judged against.
    allow_face_darker
        Accept L*face < L*flop in the solution.

    Returns
    -------
    TrompeResult
    """
    t0 = time.perf_counter()
    beta = _check_request(beta_deg, objective, epsilon)
    names = _subset(paint_a, subset)
    env, ls, vs = _request_geometries(lights_deg, views_deg)
    if objective == "single" and not (0 <= at < len(ls)):
        raise AnalysisInputError("at", f"0 <= at < {len(ls)}", at)
    model = SeamModel(
        env if env is not None else ls, vs, hinge=hinge, method=method, exposure=exposure, gloss=gloss
    )
    prob = _Problem(paint_a, model, beta, names, allow_face_darker)
    before = prob.de(prob.x0)
    sol = _solve_for(prob, objective, at, len(ls), paint_a, allow_face_darker)
    judged = sol.after if objective != "single" else sol.after[[at]]
    meets = bool(np.all(judged <= epsilon))
    msg = _message(meets, judged, before, epsilon, objective, _subset_name(subset, paint_a), sol)
    return TrompeResult(
        objective=objective,
        subset=_subset_name(subset, paint_a),
        paint=sol.paints[0],
        paints=sol.paints,
        geometries=tuple(
            EnvironmentGeometry(v, hinge) if env is not None else SeamGeometry(lt, v, hinge)
            for lt, v in zip(ls, vs, strict=True)
        ),
        beta_deg=beta,
        method=method,
        epsilon=float(epsilon),
        seam_de_before=tuple(float(v) for v in before),
        seam_de_after=tuple(float(v) for v in sol.after),
        meets_epsilon=meets,
        gamut=sol.gamut,
        changes=_changes(prob, sol.x_main),
        solve_ms=(time.perf_counter() - t0) * 1e3,
        message=msg,
        converged=sol.converged,
        per_geometry_changes=sol.per_changes,
    )


def _check_request(beta_deg: float, objective: str, epsilon: float) -> float:
    """β in degrees, once β (0 < |β| <= 45), the objective and ε (> 0) are known to be valid."""
    try:
        beta = float(beta_deg)
    except (TypeError, ValueError) as exc:
        raise AnalysisInputError("beta_deg", "a number of degrees, 0 < |β| <= 45", beta_deg) from exc
    if not np.isfinite(beta) or not (0.0 < abs(beta) <= 45.0):
        raise AnalysisInputError("beta_deg", "a number of degrees, 0 < |β| <= 45", beta_deg)
    if objective not in OBJECTIVES:
        raise AnalysisInputError("objective", " | ".join(OBJECTIVES), objective)
    if not (np.isfinite(epsilon) and epsilon > 0):
        raise AnalysisInputError("epsilon", "epsilon > 0", epsilon)
    return beta


def _request_geometries(
    lights_deg: Sequence[float] | Environment, views_deg: Sequence[float] | None
) -> tuple[Environment | None, list[float], list[float]]:
    """The environment (or ``None``) and parallel lists (lights, views) in degrees; lights are NaN
    under an environment, whose geometries are the views (default: the normal view)."""
    if not isinstance(lights_deg, Environment):
        ls, vs = _geometries(lights_deg, views_deg)
        return None, ls, vs
    vs = [0.0] if views_deg is None else [check_polar(v, f"views_deg[{i}]") for i, v in enumerate(views_deg)]
    if not vs:
        raise AnalysisInputError("views_deg", "at least one view angle in degrees", list(views_deg or []))
    return lights_deg, [float("nan")] * len(vs), vs


class _Solution(NamedTuple):
    """What :func:`_solve_for` found: the paints, seam ΔE after, the main solution and its checks."""

    paints: tuple[Any, ...]
    after: NDArray[np.float64]
    x_main: NDArray[np.float64]
    converged: bool
    gamut: GamutReport
    per_changes: tuple[dict[str, float], ...]


def _solve_for(
    prob: _Problem, objective: Objective, at: int, count: int, paint_a: Any, allow_face_darker: bool
) -> _Solution:
    """Solve *objective* over the *count* geometries: one paint per geometry for ``per_geometry``,
    else one paint (for geometry *at* alone with ``single``)."""
    if objective != "per_geometry":
        rows = np.array([at]) if objective == "single" else None
        x_main, converged = _solve(prob, objective, rows)
        paint = prob.paint(x_main)
        gamut = check_paintable(paint, allow_face_darker=allow_face_darker, relax_to=paint_a)
        return _Solution((paint,), prob.de(x_main), x_main, converged, gamut, ())
    converged = True
    xs, after = [], []
    for g in range(count):
        x, ok = _solve(prob, "single", np.array([g]))
        converged &= ok
        xs.append(x)
        after.append(float(prob.de(x, rows=np.array([g]))[0]))
    paints = tuple(prob.paint(x) for x in xs)
    reports = [check_paintable(p, allow_face_darker=allow_face_darker, relax_to=paint_a) for p in paints]
    gamut = GamutReport(
        all(r.paintable for r in reports),
        tuple(q for r in reports for q in r.problems),
        None if any(r.pointer_gamut is None for r in reports) else all(r.pointer_gamut for r in reports),
    )
    return _Solution(paints, np.array(after), xs[0], converged, gamut, tuple(_changes(prob, x) for x in xs))


def _message(
    meets: bool,
    judged: NDArray[np.float64],
    before: NDArray[np.float64],
    epsilon: float,
    objective: str,
    subset: str,
    sol: _Solution,
) -> str:
    """One sentence on the solution: ε met or not (worst seam ΔE), out of gamut, not converged."""
    worst = float(np.max(judged))
    if meets:
        msg = f"seam ΔE ≤ {epsilon:g} on every {'target ' if objective == 'single' else ''}geometry (worst {worst:.3g})"
    else:
        msg = (
            f"no paint in subset '{subset}' brings every seam under ε = {epsilon:g}: "
            f"worst ΔE {worst:.3g} after, {float(np.max(before)):.3g} before"
        )
    if not sol.gamut.paintable:
        msg += "; solution outside the paintable bound: " + "; ".join(sol.gamut.problems)
    if not sol.converged:
        msg += "; the optimiser stopped before convergence (best point returned)"
    return msg


def _subset_name(subset: str | None, paint_a: Any) -> str:
    if subset is None:
        return "solid" if paint_a.is_solid else "full"
    return subset


def _subset(paint_a: Any, subset: str | None) -> tuple[str, ...]:
    name = _subset_name(subset, paint_a)
    if name in SUBSETS:
        names = SUBSETS[name]
    else:
        names = tuple(p.strip() for p in name.split("+") if p.strip())
        bad = [n for n in names if n not in PARAMS]
        if bad or not names or len(set(names)) != len(names):
            raise AnalysisInputError(
                "subset", f"one of {sorted(SUBSETS)} or '+'-joined names from {PARAMS}", subset
            )
    if paint_a.is_solid and names != SUBSETS["solid"]:
        raise AnalysisInputError("subset", '"solid" for a solid paint A (it has no travel)', subset)
    if not paint_a.is_solid and names == SUBSETS["solid"]:
        raise AnalysisInputError("subset", "an effect-paint subset (paint A has travel)", subset)
    return names


def _changes(prob: _Problem, x: NDArray[np.float64]) -> dict[str, float]:
    return {n: float(v - prob.base[n]) for n, v in zip(prob.names, x, strict=True)}


def _solve(prob: _Problem, objective: str, rows: NDArray[np.intp] | None) -> tuple[NDArray[np.float64], bool]:
    """Run SLSQP for one objective; returns (x, converged)."""
    k = len(prob.names)
    opts = {"maxiter": 200, "ftol": 1e-9}
    if objective in ("single", "rms"):

        def fun(x: NDArray[np.float64]) -> float:
            return float(np.mean(prob.de(x, rows) ** 2)) + prob.reg(x)

        # scipy-stubs type a dict constraint's "fun" as scalar-valued; SLSQP also takes vector-valued ones
        res = minimize(  # type: ignore[call-overload]
            fun, prob.x0, method="SLSQP", bounds=prob.bounds, constraints=prob.constraints(), options=opts
        )
        x = np.asarray(res.x, dtype=float)
    elif objective == "minimax":
        d0 = prob.de(prob.x0) ** 2
        z0 = np.concatenate([prob.x0, [float(np.max(d0))]])
        cons = [*prob.constraints(), {"type": "ineq", "fun": lambda z: z[k] - prob.de(z[:k]) ** 2}]
        res = minimize(  # type: ignore[call-overload]  # as above: vector-valued constraint functions
            lambda z: float(z[k]) + prob.reg(z[:k]),
            z0,
            method="SLSQP",
            bounds=[*prob.bounds, (0.0, None)],
            constraints=cons,
            options=opts,
        )
        x = np.asarray(res.x[:k], dtype=float)
    else:  # pragma: no cover - validated by the caller
        raise AnalysisError(f"unknown objective {objective!r}")
    x = np.clip(x, [b[0] for b in prob.bounds], [b[1] for b in prob.bounds])
    # Never return something worse than paint A itself on the objective.
    if _objective_value(prob, objective, x, rows) > _objective_value(prob, objective, prob.x0, rows):
        return prob.x0.copy(), False
    return x, bool(res.success)


def _objective_value(
    prob: _Problem, objective: str, x: NDArray[np.float64], rows: NDArray[np.intp] | None
) -> float:
    de = prob.de(x, rows)
    return float(np.max(de)) if objective == "minimax" else float(np.mean(de**2))
