"""QC under the booth's illuminants: illuminant rows with their own limits beside the D65 verdict.

A lab checks a match under two or three illuminants, because a batch that matches in daylight can fail
under shop or street light. :func:`check_illuminants` adds, per chosen test illuminant and per
geometry, a row "A 45as15: MI 0.80 ≤ 1.00 pass": the CIE special metamerism index of the sample
against the standard (:func:`station.qc.metamerism.metamerism`, the one implementation — the sample
corrected additively in Lab for its mismatch under D65, then the colour difference under the test
illuminant, in the QC formula's units) judged against the user's limit for that illuminant. A row
passes when the index is at or below its limit and fails above it.

:class:`PairVerdict` joins the D65 verdict (:func:`station.qc.check.check_pair`) with the rows: its
verdict is the worse of the two. Both readings need spectra (400–700 nm, 10 nm).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NotRequired, cast

from typing_extensions import TypedDict

from station.model.domain import aspecular_name
from station.model.errors import ModelInputError
from station.model.illuminants import REFERENCE_ILLUMINANT, illuminant_name
from station.qc.errors import QcInputError
from station.qc.metamerism import metamerism
from station.qc.readings import Reading
from station.qc.tolerance import QcVerdict, QcVerdictWire, Verdict

__all__ = [
    "IlluminantCheck",
    "IlluminantCheckWire",
    "IlluminantRow",
    "IlluminantRowWire",
    "PairVerdict",
    "PairVerdictWire",
    "check_illuminants",
    "illuminant_limits",
    "parse_illuminant_limits",
]

#: Largest metamerism-index limit accepted (ΔE units of the QC formula).
MAX_LIMIT = 100.0
_FIELD = "illuminant_limits"


def illuminant_limits(limits: Mapping[str, float], field: str = _FIELD) -> dict[str, float]:
    """Validated ``{illuminant: MI limit}``: catalogue names (the reference D65 refused: its index is 0
    by construction), each once, limits finite with 0 < limit <= :data:`MAX_LIMIT`.

    Raises
    ------
    QcInputError
        Naming ``illuminant_limits.NAME`` for a bad name or limit, or *field* for an empty mapping.
    """
    out: dict[str, float] = {}
    for raw, limit in limits.items():
        try:
            name = illuminant_name(raw)
        except ModelInputError as exc:
            raise QcInputError(f"{field}.{raw}", exc.accepted, raw) from exc
        if name == REFERENCE_ILLUMINANT:
            raise QcInputError(
                f"{field}.{raw}", f"a test illuminant other than the reference {REFERENCE_ILLUMINANT}", raw
            )
        if name in out:
            raise QcInputError(f"{field}.{raw}", "each illuminant once", raw)
        if isinstance(limit, bool) or not isinstance(limit, (int, float)):
            raise QcInputError(f"{field}.{name}", f"a number 0 < limit <= {MAX_LIMIT:g}", limit)
        if not (math.isfinite(limit) and 0.0 < limit <= MAX_LIMIT):
            raise QcInputError(f"{field}.{name}", f"0 < limit <= {MAX_LIMIT:g}", limit)
        out[name] = float(limit)
    if not out:
        raise QcInputError(field, "at least one illuminant with its limit, e.g. A=1.0", dict(limits))
    return out


def parse_illuminant_limits(text: str, field: str = _FIELD) -> dict[str, float]:
    """``"A=1.0,F11=1.5"`` (``:`` also accepted) → validated ``{illuminant: limit}``."""
    pairs: dict[str, float] = {}
    for item in (t.strip() for t in text.split(",")):
        if not item:
            continue
        name, sep, value = item.replace(":", "=").partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or not math.isfinite(number):
            raise QcInputError(field, 'ILLUMINANT=LIMIT pairs, e.g. "A=1.0,F11=1.5"', text)
        if name.strip() in pairs:
            raise QcInputError(f"{field}.{name.strip()}", "each illuminant once", text)
        pairs[name.strip()] = number
    return illuminant_limits(pairs, field)


class IlluminantRowWire(TypedDict):
    """The metamerism index under one test illuminant at one geometry against its limit."""

    illuminant: str
    geometry: str
    aspecular_deg: float
    metamerism_index: float
    limit: float
    verdict: Verdict
    text: str


class IlluminantCheckWire(TypedDict):
    """Illuminant rows of a sample: ``fail`` when any row is above its limit."""

    reference_illuminant: str
    formula: str
    index: str
    limits: dict[str, float]
    verdict: Verdict
    reason: str
    rows: list[IlluminantRowWire]


class PairVerdictWire(QcVerdictWire):
    """The D65 verdict; with illuminant rows, ``verdict`` is the worse of ``d65_verdict`` and theirs."""

    d65_verdict: NotRequired[Verdict]
    illuminants: NotRequired[IlluminantCheckWire]


@dataclass(frozen=True)
class IlluminantRow:
    """The metamerism index under one test illuminant at one geometry, judged against its limit."""

    illuminant: str
    geometry: str
    aspecular_deg: float
    index: float
    limit: float

    @property
    def verdict(self) -> Verdict:
        """``pass`` when the index is at or below the limit, else ``fail``."""
        return "pass" if self.index <= self.limit else "fail"

    @property
    def text(self) -> str:
        """The row as a person reads it: ``A 45as15: MI 0.80 <= 1.00 pass``."""
        op = "<=" if self.verdict == "pass" else ">"
        return f"{self.illuminant} {self.geometry}: MI {self.index:.2f} {op} {self.limit:.2f} {self.verdict}"

    def to_dict(self) -> IlluminantRowWire:
        return {
            "illuminant": self.illuminant,
            "geometry": self.geometry,
            "aspecular_deg": self.aspecular_deg,
            "metamerism_index": self.index,
            "limit": self.limit,
            "verdict": self.verdict,
            "text": self.text,
        }


@dataclass(frozen=True)
class IlluminantCheck:
    """Every illuminant row of a sample, the limits and the verdict over them (``fail`` if any row fails)."""

    formula: str
    limits: dict[str, float]
    rows: tuple[IlluminantRow, ...]

    @property
    def verdict(self) -> Verdict:
        return "fail" if any(r.verdict == "fail" for r in self.rows) else "pass"

    @property
    def reason(self) -> str:
        failed = [r for r in self.rows if r.verdict == "fail"]
        if not failed:
            return "every illuminant row within its limit"
        return "; ".join(r.text for r in failed)

    def to_dict(self) -> IlluminantCheckWire:
        return {
            "reference_illuminant": REFERENCE_ILLUMINANT,
            "formula": self.formula,
            "index": "CIE special metamerism index (change in illuminant), additive correction from D65",
            "limits": dict(self.limits),
            "verdict": self.verdict,
            "reason": self.reason,
            "rows": [r.to_dict() for r in self.rows],
        }


def check_illuminants(
    standard: Reading, sample: Reading, limits: Mapping[str, float], formula: str
) -> IlluminantCheck:
    """Illuminant rows of *sample* against *standard* (module docstring), at the standard's geometries.

    Parameters
    ----------
    standard, sample
        Readings with spectra on 400–700 nm / 10 nm; the sample must have every geometry of the standard.
    limits
        ``{illuminant: MI limit}`` in *formula*'s ΔE units (:func:`illuminant_limits` validates it).
    formula
        The QC formula (``din6175-2`` | ``cie2000`` | ``cie94`` | ``cie76``).

    Raises
    ------
    QcInputError
        A reading without spectra, a geometry of the standard missing from the sample, a bad limit.
    """
    lims = illuminant_limits(limits)
    missing = [aspecular_name(a) for a in standard.aspecular_deg if a not in sample.aspecular_deg]
    if missing:
        raise QcInputError(
            "sample.geometries",
            f"every geometry of the standard ({', '.join(standard.geometries)})",
            list(sample.geometries),
            detail=f"missing {', '.join(missing)}",
        )
    result = metamerism(standard, sample, formula, tuple(lims))
    rows = tuple(
        IlluminantRow(ill, aspecular_name(a), a, result.index[ill][i], lims[ill])
        for ill in lims
        for i, a in enumerate(result.aspecular_deg)
    )
    return IlluminantCheck(result.formula, lims, rows)


_ORDER: dict[str, int] = {"pass": 0, "warn": 1, "fail": 2}


@dataclass(frozen=True)
class PairVerdict:
    """The D65 verdict of a sample with its illuminant rows (``None`` when none were asked for)."""

    colour: QcVerdict
    illuminants: IlluminantCheck | None = None

    @property
    def verdict(self) -> Verdict:
        """The worse of the D65 verdict and the illuminant rows' verdict."""
        if self.illuminants is None:
            return self.colour.verdict
        return max(self.colour.verdict, self.illuminants.verdict, key=_ORDER.__getitem__)

    def to_dict(self) -> PairVerdictWire:
        out = cast(PairVerdictWire, {**self.colour.to_dict()})  # the optional keys follow
        if self.illuminants is None:
            return out
        out["d65_verdict"] = self.colour.verdict
        out["verdict"] = self.verdict
        if self.illuminants.verdict == "fail":
            out["reason"] = f"{self.colour.reason}; under the booth's illuminants: {self.illuminants.reason}"
        out["illuminants"] = self.illuminants.to_dict()
        return out
