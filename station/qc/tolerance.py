"""QC tolerance sets and pass / warn / fail verdicts of a sample against a standard, per geometry.

A :class:`ToleranceSet` holds, per geometry (an aspecular angle under the standard 45° illumination,
named like ``45as15``), a limit on ΔE for the set's formula and optional limits on the components,
either ΔL*, Δa*, Δb* or ΔL*, ΔC*, ΔH* (never both in one geometry); an aggregation rule over the
geometries; and a warn band. Limits are symmetric: a component passes while |ΔX| <= its limit.

Formulas: ``cie76`` (ΔE*ab), ``cie94``, ``cie2000`` with the parametric ratio l:c (k_L:k_C, 1:1 by
default, 2:1 for textiles; :func:`station.model.difference.delta_e_cie2000_lc`) and ``din6175``
(DIN 6175-2 ΔE_eff, weighted by the aspecular angle; :func:`station.model.difference.delta_e_din6175`).

Verdict of one geometry (:func:`judge`):

* ``fail`` when ΔE or any limited component exceeds its limit;
* ``warn`` when none fails but one exceeds ``warn_fraction`` × its limit (the warn band);
* ``pass`` otherwise. The reasons name each quantity outside its band, e.g. ``"ΔE 1.23 > 1 (din6175)"``.

Overall verdict, by the aggregation rule:

* ``max``: the worst geometry's verdict (every geometry must pass); the aggregate reported is the
  largest ΔE with its geometry (DIN 6175-2's maxdE);
* ``mean``: the mean ΔE over the geometries (DIN 6175-2's mdE) against ``mean_limit`` with the same warn
  band; the per-geometry ΔE limits are then informational, while component limits still count (a
  component failing at any geometry fails the sample).

Components: ΔL* = L*₂ − L*₁, Δa*, Δb*, ΔC* = C*₂ − C*₁ and the signed ΔH* = 2√(C*₁C*₂) sin(Δh/2)
(CIE 15), sample minus standard. Defaults (limit, warn band, rule, formula) come from
:mod:`station.model.domain`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from typing_extensions import TypedDict

from station.model.difference import (
    DIN_DEFAULT_FACTORS,
    DinFactors,
    audi2000_unavailable,
    delta_e,
    delta_e_cie2000_lc,
    validate_method,
)
from station.model.domain import (
    ANGLE_MAX_DEG,
    ANGLE_MIN_DEG,
    DELTA_E_COMPUTED,
    ILLUMINATION_DEG,
    QC_AGGREGATION,
    QC_DE_LIMIT,
    QC_FORMULA,
    QC_WARN_FRACTION,
    QC_WARN_FRACTION_RANGE,
    TOLERANCE_AGGREGATIONS,
    aspecular_name,
    check_lab,
    parse_geometry,
)
from station.model.errors import ModelInputError

__all__ = [
    "AGGREGATIONS",
    "FORMULAS",
    "GeometryLimits",
    "GeometryVerdict",
    "GeometryVerdictWire",
    "QcVerdict",
    "QcVerdictWire",
    "ToleranceSet",
    "Verdict",
    "judge",
    "lab_components",
    "worst_verdict",
]

Verdict = Literal["pass", "warn", "fail"]
#: Formulas a tolerance set may name.
FORMULAS = DELTA_E_COMPUTED
#: Aggregation rules over the geometries.
AGGREGATIONS = TOLERANCE_AGGREGATIONS
_RANK: Mapping[str, int] = MappingProxyType({"pass": 0, "warn": 1, "fail": 2})
_COMPONENTS = ("dl", "da", "db", "dc", "dh")
_SYMBOL: Mapping[str, str] = MappingProxyType(
    {"dl": "ΔL*", "da": "Δa*", "db": "Δb*", "dc": "ΔC*", "dh": "ΔH*"}
)


def _positive(value: Any, name: str, allow_none: bool = False) -> float | None:
    if value is None and allow_none:
        return None
    ok = (
        isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0
    )
    if not ok:
        raise ModelInputError(name, "a finite number > 0" + (" (or absent)" if allow_none else ""), value)
    return float(value)


def worst_verdict(verdicts: Iterable[str]) -> Verdict:
    """The worst of *verdicts* in the order pass < warn < fail (``pass`` when there is none)."""
    w = max(verdicts, key=lambda v: _RANK[v], default="pass")
    return "fail" if w == "fail" else "warn" if w == "warn" else "pass"


@dataclass(frozen=True)
class GeometryLimits:
    """Limits at one geometry: ΔE (required) and optional |ΔL*|, |Δa*|, |Δb*| or |ΔL*|, |ΔC*|, |ΔH*|.

    *aspecular_deg* in degrees (ANGLE_MIN_DEG … ANGLE_MAX_DEG, under 45° illumination); every limit a
    finite number > 0, in CIELAB units (ΔE in the set's formula).
    """

    aspecular_deg: float
    de: float = QC_DE_LIMIT
    dl: float | None = None
    da: float | None = None
    db: float | None = None
    dc: float | None = None
    dh: float | None = None
    where: str = field(default="geometry", compare=False, repr=False)

    def __post_init__(self) -> None:
        a = self.aspecular_deg
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not ANGLE_MIN_DEG <= a <= ANGLE_MAX_DEG:
            raise ModelInputError(
                f"{self.where}.aspecular_deg",
                f"an angle in [{ANGLE_MIN_DEG:g}, {ANGLE_MAX_DEG:g}] degrees",
                a,
            )
        object.__setattr__(self, "aspecular_deg", float(a))
        object.__setattr__(self, "de", _positive(self.de, f"{self.where}.de"))
        for c in _COMPONENTS:
            object.__setattr__(self, c, _positive(getattr(self, c), f"{self.where}.{c}", allow_none=True))
        if (self.da is not None or self.db is not None) and (self.dc is not None or self.dh is not None):
            raise ModelInputError(
                f"{self.where}.components", "limits on ΔL*, Δa*, Δb* or on ΔL*, ΔC*, ΔH*, not both", "both"
            )

    @property
    def geometry(self) -> str:
        """Name of the geometry, e.g. ``"45as15"``."""
        return aspecular_name(self.aspecular_deg)

    def component_limits(self) -> dict[str, float]:
        """The limited components and their limits, e.g. ``{"dl": 0.5, "dc": 0.8}``."""
        out: dict[str, float] = {}
        for c in _COMPONENTS:
            v = getattr(self, c)
            if v is not None:
                out[c] = float(v)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "geometry": self.geometry,
            "aspecular_deg": self.aspecular_deg,
            "de": self.de,
            **self.component_limits(),
        }


@dataclass(frozen=True)
class ToleranceSet:
    """Per-geometry limits, the ΔE formula, the aggregation rule and the warn band (module docstring).

    Parameters
    ----------
    geometries
        One :class:`GeometryLimits` per geometry, distinct angles.
    formula
        ``cie76`` | ``cie94`` | ``cie2000`` | ``din6175``.
    aggregation
        ``max`` (every geometry must pass) or ``mean`` (mean ΔE against *mean_limit*).
    mean_limit
        Limit on the mean ΔE under ``mean`` (default :data:`~station.model.domain.QC_DE_LIMIT`).
    warn_fraction
        Warn once a value exceeds this fraction of its limit, 0 < f <= 1 (1: no warn band).
    l_c
        CIEDE2000 (k_L, k_C), each > 0 (k_H = 1); only read by ``cie2000``.
    din_factors
        DIN 6175-2 parametric factors g; only read by ``din6175``.
    name
        Free text naming the set (customer, part).
    """

    geometries: tuple[GeometryLimits, ...]
    formula: str = QC_FORMULA
    aggregation: str = QC_AGGREGATION
    mean_limit: float = QC_DE_LIMIT
    warn_fraction: float = QC_WARN_FRACTION
    l_c: tuple[float, float] = (1.0, 1.0)
    din_factors: DinFactors = DIN_DEFAULT_FACTORS
    name: str = ""

    def __post_init__(self) -> None:
        geoms = tuple(self.geometries)
        if not geoms or not all(isinstance(g, GeometryLimits) for g in geoms):
            raise ModelInputError("tolerance.geometries", "at least one GeometryLimits", self.geometries)
        angles = [g.aspecular_deg for g in geoms]
        if len(set(angles)) != len(angles):
            raise ModelInputError("tolerance.geometries", "distinct geometries", [g.geometry for g in geoms])
        object.__setattr__(self, "geometries", geoms)
        formula = validate_method(self.formula)
        if formula == "audi2000":
            raise audi2000_unavailable()
        if formula not in FORMULAS:
            raise ModelInputError("tolerance.formula", " | ".join(FORMULAS), self.formula)
        object.__setattr__(self, "formula", formula)
        if self.aggregation not in AGGREGATIONS:
            raise ModelInputError("tolerance.aggregation", " | ".join(AGGREGATIONS), self.aggregation)
        object.__setattr__(self, "mean_limit", _positive(self.mean_limit, "tolerance.mean_limit"))
        lo, hi = QC_WARN_FRACTION_RANGE
        f = self.warn_fraction
        if isinstance(f, bool) or not isinstance(f, (int, float)) or not (lo < f <= hi):
            raise ModelInputError("tolerance.warn_fraction", f"a number, {lo:g} < warn_fraction <= {hi:g}", f)
        object.__setattr__(self, "warn_fraction", float(f))
        lc = tuple(self.l_c)
        if len(lc) != 2:
            raise ModelInputError("tolerance.l_c", "two numbers k_L:k_C, each > 0", self.l_c)
        object.__setattr__(
            self, "l_c", (_positive(lc[0], "tolerance.l_c.l"), _positive(lc[1], "tolerance.l_c.c"))
        )
        if not isinstance(self.din_factors, DinFactors):
            raise ModelInputError("tolerance.din_factors", "a DinFactors", self.din_factors)

    @classmethod
    def uniform(
        cls,
        angles_deg: Sequence[float],
        de: float = QC_DE_LIMIT,
        components: Mapping[str, float] | None = None,
        **kwargs: Any,
    ) -> ToleranceSet:
        """The same limits at every angle of *angles_deg* (degrees); *kwargs* as the constructor."""
        comp = dict(components or {})
        bad = set(comp) - set(_COMPONENTS)
        if bad:
            raise ModelInputError("tolerance.components", " | ".join(_COMPONENTS), sorted(bad))
        geoms = tuple(
            GeometryLimits(float(a), de, where=f"tolerance.geometries[{i}]", **comp)
            for i, a in enumerate(angles_deg)
        )
        return cls(geoms, **kwargs)

    def limits_for(self, aspecular_deg: float) -> GeometryLimits:
        """The limits of one geometry; :class:`ModelInputError` when the set has none for it."""
        for g in self.geometries:
            if g.aspecular_deg == float(aspecular_deg):
                return g
        raise ModelInputError(
            "angles",
            f"geometries of the tolerance set ({', '.join(g.geometry for g in self.geometries)})",
            aspecular_name(float(aspecular_deg)),
        )

    def delta_e(self, lab_std: NDArray[np.float64], lab_smp: NDArray[np.float64], angles: NDArray) -> NDArray:
        """ΔE per geometry with this set's formula (and l:c or g), shape (n,)."""
        if self.formula == "cie2000":
            return delta_e_cie2000_lc(lab_std, lab_smp, self.l_c[0], self.l_c[1])
        return delta_e(lab_std, lab_smp, self.formula, aspecular_deg=angles, din_factors=self.din_factors)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (:meth:`from_dict` reads it back)."""
        out: dict[str, Any] = {
            "name": self.name,
            "formula": self.formula,
            "aggregation": self.aggregation,
            "mean_limit": self.mean_limit,
            "warn_fraction": self.warn_fraction,
            "geometries": [g.to_dict() for g in self.geometries],
        }
        if self.formula == "cie2000":
            out["l_c"] = list(self.l_c)
        if self.formula == "din6175":
            d = self.din_factors
            out["din_g"] = {"l": d.g_l, "c": d.g_c, "h": d.g_h, "a": d.g_a, "b": d.g_b}
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ToleranceSet:
        """Build from :meth:`to_dict` output; a geometry is ``"geometry": "45as15"`` or ``"aspecular_deg"``.

        Unknown keys are refused (typed error naming the key), so a misspelt limit is never ignored.
        """
        if not isinstance(data, Mapping):
            raise ModelInputError("tolerance", "a JSON object", type(data).__name__)
        known = {
            "name",
            "formula",
            "aggregation",
            "mean_limit",
            "warn_fraction",
            "geometries",
            "l_c",
            "din_g",
        }
        extra = sorted(set(data) - known)
        if extra:
            raise ModelInputError(f"tolerance.{extra[0]}", "one of " + ", ".join(sorted(known)), extra[0])
        rows = data.get("geometries")
        if not isinstance(rows, list) or not rows:
            raise ModelInputError("tolerance.geometries", "a non-empty list of geometry limits", rows)
        geoms = []
        for i, row in enumerate(rows):
            where = f"tolerance.geometries[{i}]"
            if not isinstance(row, Mapping):
                raise ModelInputError(where, "an object with geometry and de", row)
            row = dict(row)
            name = row.pop("geometry", None)
            angle = row.pop("aspecular_deg", None)
            if name is not None:
                illum, asp = parse_geometry(name, f"{where}.geometry")
                if illum != ILLUMINATION_DEG:
                    raise ModelInputError(
                        f"{where}.geometry", f"a {ILLUMINATION_DEG:g}° illumination geometry", name
                    )
                if angle is not None and float(angle) != asp:
                    raise ModelInputError(
                        f"{where}.aspecular_deg", f"{asp:g} (as its geometry {name})", angle
                    )
                angle = asp
            if angle is None:
                raise ModelInputError(f"{where}.geometry", 'a name like "45as15" (or aspecular_deg)', None)
            bad = sorted(set(row) - {"de", *_COMPONENTS})
            if bad:
                raise ModelInputError(f"{where}.{bad[0]}", "de, dl, da, db, dc, dh", bad[0])
            geoms.append(GeometryLimits(angle, where=where, **row))
        g = data.get("din_g") or {}
        if not isinstance(g, Mapping) or set(g) - set("lchab"):
            raise ModelInputError("tolerance.din_g", "an object with keys l, c, h, a, b", g)
        factors = DinFactors(**{f"g_{k}": v for k, v in g.items()})
        kwargs = {
            k: data[k] for k in ("name", "formula", "aggregation", "mean_limit", "warn_fraction") if k in data
        }
        if "l_c" in data:
            lc = data["l_c"]
            if not isinstance(lc, (list, tuple)) or len(lc) != 2:
                raise ModelInputError("tolerance.l_c", "two numbers [k_L, k_C]", lc)
            kwargs["l_c"] = (lc[0], lc[1])
        return cls(tuple(geoms), din_factors=factors, **kwargs)


class GeometryVerdictWire(TypedDict):
    """One geometry's differences (sample − standard, CIELAB units), the ΔE limit used there (in the
    formula's units; ``None`` under ``mean`` aggregation without a per-geometry limit) and the verdict."""

    geometry: str
    aspecular_deg: float
    dL: float
    da: float
    db: float
    dC: float
    dH: float
    dE: float
    limit: float | None
    verdict: Verdict
    reasons: list[str]


class QcVerdictWire(TypedDict):
    """Overall verdict with the reason, per-geometry verdicts, mean and max ΔE and the worst geometry."""

    verdict: Verdict
    reason: str
    formula: str
    aggregation: str
    per_geometry: list[GeometryVerdictWire]
    mean_de: float
    max_de: float
    worst_geometry: str


@dataclass(frozen=True)
class GeometryVerdict:
    """Differences and verdict at one geometry (sample minus standard, CIELAB units)."""

    geometry: str
    aspecular_deg: float
    dl: float
    da: float
    db: float
    dc: float
    dh: float
    de: float
    verdict: Verdict
    reasons: tuple[str, ...]
    limit: float | None = None

    def to_dict(self) -> GeometryVerdictWire:
        return {
            "geometry": self.geometry,
            "aspecular_deg": self.aspecular_deg,
            "dL": self.dl,
            "da": self.da,
            "db": self.db,
            "dC": self.dc,
            "dH": self.dh,
            "dE": self.de,
            "limit": self.limit,
            "verdict": self.verdict,
            "reasons": list(self.reasons),
        }


@dataclass(frozen=True)
class QcVerdict:
    """Overall verdict with the per-geometry ones, mean and max ΔE and the worst geometry."""

    verdict: Verdict
    reason: str
    formula: str
    aggregation: str
    per_geometry: tuple[GeometryVerdict, ...]
    mean_de: float
    max_de: float
    worst_geometry: str

    def to_dict(self) -> QcVerdictWire:
        return {
            "verdict": self.verdict,
            "reason": self.reason,
            "formula": self.formula,
            "aggregation": self.aggregation,
            "per_geometry": [g.to_dict() for g in self.per_geometry],
            "mean_de": self.mean_de,
            "max_de": self.max_de,
            "worst_geometry": self.worst_geometry,
        }


def lab_components(lab_std: ArrayLike, lab_smp: ArrayLike) -> NDArray[np.float64]:
    """ΔL*, Δa*, Δb*, ΔC*, ΔH* (sample − standard), shape (..., 5); ΔH* = 2√(C*₁C*₂) sin(Δh/2), signed."""
    s = np.asarray(lab_std, dtype=float)
    p = np.asarray(lab_smp, dtype=float)
    c1, c2 = np.hypot(s[..., 1], s[..., 2]), np.hypot(p[..., 1], p[..., 2])
    dh_angle = np.arctan2(p[..., 2], p[..., 1]) - np.arctan2(s[..., 2], s[..., 1])
    dh_angle = (dh_angle + np.pi) % (2 * np.pi) - np.pi
    dh = 2.0 * np.sqrt(c1 * c2) * np.sin(dh_angle / 2.0)
    d = p - s
    return np.stack([d[..., 0], d[..., 1], d[..., 2], c2 - c1, dh], axis=-1)


def _band(
    value: float, limit: float, label: str, fraction: float, note: str = ""
) -> tuple[Verdict, str | None]:
    """Verdict of |value| against *limit* with the warn band, and the reason when it is not a pass."""
    mag = abs(value)
    bound = f"{limit:g}" if label == "ΔE" else f"±{limit:g}"
    if mag > limit:
        return "fail", f"{label} {value:.3g} beyond {bound}{note}"
    if fraction < 1.0 and mag > fraction * limit:
        return (
            "warn",
            f"{label} {value:.3g} in the warn band (over {fraction * limit:.3g}, limit {bound}){note}",
        )
    return "pass", None


def _parse_lab(lab: ArrayLike, field_name: str) -> NDArray[np.float64]:
    arr = np.asarray(lab, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0:
        raise ModelInputError(field_name, "one L*, a*, b* triple per geometry, shape (n >= 1, 3)", arr.shape)
    return np.array([check_lab(row, f"{field_name}[{i}]") for i, row in enumerate(arr)], dtype=float)


def _geometry_verdict(
    lim: GeometryLimits, comps: NDArray[np.float64], de: float, tolerance: ToleranceSet
) -> tuple[GeometryVerdict, list[str]]:
    """The verdict at one geometry (components then ΔE against their limits), and its component verdicts."""
    f = tolerance.warn_fraction
    verdicts: list[str] = []
    reasons: list[str] = []
    component_verdicts: list[str] = []
    for j, c in enumerate(_COMPONENTS):
        limit = getattr(lim, c)
        if limit is not None:
            v, why = _band(float(comps[j]), limit, _SYMBOL[c], f)
            verdicts.append(v)
            component_verdicts.append(v)
            if why:
                reasons.append(why)
    v, why = _band(de, lim.de, "ΔE", f, f" ({tolerance.formula})")
    verdicts.append(v)
    if why:
        reasons.append(why)
    dl, da, db, dc, dh = (float(x) for x in comps)
    g = GeometryVerdict(
        lim.geometry,
        lim.aspecular_deg,
        dl,
        da,
        db,
        dc,
        dh,
        de,
        worst_verdict(verdicts),
        tuple(reasons),
        lim.de,
    )
    return g, component_verdicts


def _overall(
    per: Sequence[GeometryVerdict],
    component_verdicts: Sequence[str],
    mean_de: float,
    max_de: float,
    worst_i: int,
    tolerance: ToleranceSet,
) -> tuple[Verdict, str]:
    """The overall verdict and its reason under the set's aggregation rule (module docstring)."""
    if tolerance.aggregation == "max":
        overall = worst_verdict([g.verdict for g in per])
        bad = [g for g in per if g.verdict == overall and overall != "pass"]
        reason = (
            "; ".join(f"{g.geometry}: {', '.join(g.reasons)}" for g in bad)
            if bad
            else f"every geometry within its limits (max ΔE {max_de:.3g} at {per[worst_i].geometry})"
        )
        return overall, reason
    v_mean, why = _band(
        mean_de, tolerance.mean_limit, "ΔE", tolerance.warn_fraction, f" ({tolerance.formula})"
    )
    overall = worst_verdict([v_mean, *component_verdicts])
    parts = [f"mean {why}"] if why else []
    parts += [f"{g.geometry}: {r}" for g in per for r in g.reasons if not r.startswith("ΔE")]
    reason = "; ".join(parts) if parts else f"mean ΔE {mean_de:.3g} within {tolerance.mean_limit:g}"
    return overall, reason


def judge(
    lab_standard: ArrayLike, lab_sample: ArrayLike, aspecular_deg: Sequence[float], tolerance: ToleranceSet
) -> QcVerdict:
    """Verdict of a sample against its standard (module docstring for the rules).

    Parameters
    ----------
    lab_standard, lab_sample
        L*, a*, b* per geometry, shape (n, 3), each inside the domain's Lab bound.
    aspecular_deg
        The n aspecular angles (degrees) of the rows; each must have limits in *tolerance*.
    tolerance
        The tolerance set.
    """
    std = _parse_lab(lab_standard, "standard")
    smp = _parse_lab(lab_sample, "sample")
    if smp.shape != std.shape:
        raise ModelInputError("sample", f"{std.shape[0]} triples (as many as the standard)", smp.shape[0])
    angles = np.asarray(aspecular_deg, dtype=float).reshape(-1)
    if angles.shape != (std.shape[0],):
        raise ModelInputError("angles", f"{std.shape[0]} aspecular angles (one per Lab triple)", angles.size)
    if len(set(angles.tolist())) != angles.size:
        raise ModelInputError("angles", "distinct geometries", angles.tolist())
    limits = [tolerance.limits_for(a) for a in angles]
    de = tolerance.delta_e(std, smp, angles)
    comps = lab_components(std, smp)
    per: list[GeometryVerdict] = []
    component_verdicts: list[str] = []
    for i, lim in enumerate(limits):
        g, verdicts = _geometry_verdict(lim, comps[i], float(de[i]), tolerance)
        per.append(g)
        component_verdicts += verdicts
    worst_i = int(np.argmax(de))
    mean_de, max_de = float(de.mean()), float(de[worst_i])
    overall, reason = _overall(per, component_verdicts, mean_de, max_de, worst_i, tolerance)
    return QcVerdict(
        overall,
        reason,
        tolerance.formula,
        tolerance.aggregation,
        tuple(per),
        mean_de,
        max_de,
        per[worst_i].geometry,
    )
