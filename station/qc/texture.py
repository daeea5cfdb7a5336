"""Texture QC within one vendor: sparkle and graininess of a sample against its standard.

Texture values (sparkle intensity, sparkle area, sparkle grade per geometry; graininess per sample,
under diffuse light) are what the instrument vendor's software computes from its images; they are
unitless and device-dependent (PTB; BYK-mac i and smart-chart, X-Rite MA-T12), so a sample is judged
only against a standard measured through the same vendor's procedure. Values are the import's and the
database's ``texture`` entries: ``{"vendor", "name", "geometry", "value"}`` (``geometry`` ``""`` for a
per-sample value).

Rules (:func:`judge_texture`): each value of the sample is paired with the standard's of the same name
and geometry; the difference Δ = sample − standard is judged against its own tolerance: **ΔS** for every
sparkle quantity (a name starting with "sparkle"), **ΔG** for graininess (a name starting with "grain").
Limits are symmetric; ``fail`` beyond the limit, ``warn`` beyond ``warn_fraction`` of it (the colour
warn band, :data:`station.model.domain.QC_WARN_FRACTION`), ``pass`` otherwise. A value of another
vendor raises :class:`TextureVendorError` (never compared); values without a counterpart, or of a
quantity without a limit, are listed unjudged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from typing_extensions import TypedDict

from station.model.domain import QC_WARN_FRACTION
from station.qc.errors import QcInputError
from station.qc.tolerance import Verdict

__all__ = [
    "TextureRow",
    "TextureRowWire",
    "TextureTolerance",
    "TextureValue",
    "TextureVendorError",
    "TextureVerdict",
    "TextureVerdictWire",
    "judge_texture",
    "mean_texture",
    "parse_texture_limits",
    "texture_values",
]


class TextureVendorError(QcInputError):
    """Texture values of two vendors compared: they are device-dependent and never compare."""


@dataclass(frozen=True)
class TextureValue:
    """One vendor texture value (unitless) at a geometry (``""``: the whole sample)."""

    vendor: str
    name: str
    geometry: str
    value: float


def texture_values(entries: Any, where: str) -> tuple[TextureValue, ...]:
    """Texture values from JSON entries ``{"vendor", "name", "geometry", "value"}`` (None: none)."""
    if entries is None:
        return ()
    if not isinstance(entries, Sequence) or isinstance(entries, str):
        raise QcInputError(f"{where}.texture", "a list of {vendor, name, geometry, value} objects", entries)
    out = []
    for i, e in enumerate(entries):
        accepted = "{vendor, name, geometry, value} with a finite value"
        if not isinstance(e, Mapping):
            raise QcInputError(f"{where}.texture[{i}]", accepted, e)
        value = e.get("value")
        ok = isinstance(e.get("vendor"), str) and isinstance(e.get("name"), str)
        if (
            not ok
            or not isinstance(value, (int, float))
            or isinstance(value, bool)
            or not math.isfinite(value)
        ):
            raise QcInputError(f"{where}.texture[{i}]", accepted, e)
        out.append(TextureValue(e["vendor"], e["name"], str(e.get("geometry") or ""), float(value)))
    return tuple(out)


def mean_texture(sets: Sequence[Sequence[TextureValue]]) -> tuple[TextureValue, ...]:
    """The mean of each (vendor, name, geometry) over the readings that have it (repeat readings)."""
    acc: dict[tuple[str, str, str], list[float]] = {}
    for values in sets:
        for v in values:
            acc.setdefault((v.vendor, v.name, v.geometry), []).append(v.value)
    return tuple(TextureValue(k[0], k[1], k[2], sum(x) / len(x)) for k, x in acc.items())


@dataclass(frozen=True)
class TextureTolerance:
    """Limits on |ΔS| (every sparkle quantity) and |ΔG| (graininess), in the vendor's units; None: not judged."""

    ds: float | None = None
    dg: float | None = None
    warn_fraction: float = QC_WARN_FRACTION

    def __post_init__(self) -> None:
        for name in ("ds", "dg"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise QcInputError(f"texture_limits.{name}", "a finite number > 0", v)
        if not 0 < self.warn_fraction <= 1:
            raise QcInputError("texture_limits.warn_fraction", "0 < fraction <= 1", self.warn_fraction)

    def limit_for(self, name: str) -> tuple[str, float | None]:
        """The tolerance (``"ΔS"``/``"ΔG"``) and its limit for a quantity *name*; ("", None) if none."""
        low = name.lower()
        if low.startswith("sparkle"):
            return "ΔS", self.ds
        if low.startswith("grain"):
            return "ΔG", self.dg
        return "", None


def parse_texture_limits(text: str) -> TextureTolerance:
    """``"ds=1.0,dg=0.5"`` (either may be left out) → :class:`TextureTolerance`."""
    limits: dict[str, float] = {}
    for part in (p.strip() for p in text.split(",") if p.strip()):
        key, _, val = part.partition("=")
        key = key.strip().lower()
        if key not in ("ds", "dg") or key in limits:
            raise QcInputError("texture_limits", 'ds=LIMIT and/or dg=LIMIT, e.g. "ds=1,dg=0.5"', text)
        try:
            limits[key] = float(val)
        except ValueError as exc:
            raise QcInputError(f"texture_limits.{key}", "a finite number > 0", val) from exc
    if not limits:
        raise QcInputError("texture_limits", 'ds=LIMIT and/or dg=LIMIT, e.g. "ds=1,dg=0.5"', text)
    return TextureTolerance(limits.get("ds"), limits.get("dg"))


class TextureRowWire(TypedDict):
    """One texture quantity (vendor units): standard, sample, Δ, the tolerance (``ΔS``/``ΔG``, ``""``
    none) and its limit used, and the verdict (``None``: unjudged)."""

    name: str
    geometry: str
    tolerance: str
    limit: float | None
    verdict: Verdict | None
    standard: float | None
    sample: float | None
    delta: float | None


class TextureVerdictWire(TypedDict):
    """The texture verdict within one vendor: the worst judged row and every row."""

    verdict: Verdict
    vendor: str
    rows: list[TextureRowWire]


@dataclass(frozen=True)
class TextureRow:
    """One texture quantity: standard, sample, Δ, the tolerance used and the verdict (None: unjudged)."""

    name: str
    geometry: str
    standard: float | None
    sample: float | None
    delta: float | None
    tolerance: str
    limit: float | None
    verdict: Verdict | None

    def to_dict(self) -> TextureRowWire:
        return {
            "name": self.name,
            "geometry": self.geometry,
            "standard": self.standard,
            "sample": self.sample,
            "delta": self.delta,
            "tolerance": self.tolerance,
            "limit": self.limit,
            "verdict": self.verdict,
        }


@dataclass(frozen=True)
class TextureVerdict:
    """The texture verdict: the worst judged row (``pass`` with none judged), its vendor and its rows."""

    verdict: Verdict
    vendor: str
    rows: tuple[TextureRow, ...]

    def to_dict(self) -> TextureVerdictWire:
        return {"verdict": self.verdict, "vendor": self.vendor, "rows": [r.to_dict() for r in self.rows]}


def _vendor(std: Sequence[TextureValue], smp: Sequence[TextureValue]) -> str:
    vendors = {v.vendor for v in (*std, *smp)}
    if len(vendors) > 1:
        raise TextureVendorError(
            "texture",
            "texture values of one vendor (device-dependent, never compared across vendors)",
            sorted(vendors),
        )
    return next(iter(vendors), "")


def _band(delta: float, limit: float, fraction: float) -> Verdict:
    mag = abs(delta)
    return "fail" if mag > limit else "warn" if mag > fraction * limit else "pass"


def judge_texture(
    standard: Sequence[TextureValue], sample: Sequence[TextureValue], tolerance: TextureTolerance
) -> TextureVerdict:
    """Sample texture against the standard's, within one vendor (module docstring for the rules)."""
    vendor = _vendor(standard, sample)
    std = {(v.name, v.geometry): v.value for v in standard}
    smp = {(v.name, v.geometry): v.value for v in sample}
    rows = []
    rank = {"pass": 0, "warn": 1, "fail": 2}
    worst: Verdict = "pass"
    for key in sorted(set(std) | set(smp), key=lambda k: (k[0].lower(), k[1])):
        a, b = std.get(key), smp.get(key)
        label, limit = tolerance.limit_for(key[0])
        delta = None if a is None or b is None else b - a
        verdict: Verdict | None = None
        if delta is not None and limit is not None:
            verdict = _band(delta, limit, tolerance.warn_fraction)
            worst = verdict if rank[verdict] > rank[worst] else worst
        rows.append(TextureRow(key[0], key[1], a, b, delta, label, limit, verdict))
    return TextureVerdict(worst, vendor, tuple(rows))
