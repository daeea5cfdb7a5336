"""Repeat readings of one panel: mean, per-geometry standard deviation, outliers; instrument bias.

:func:`summarise` averages N readings of one panel (the geometries all of them share):

* ``mean`` — the arithmetic mean of L*, a*, b* per geometry (a :class:`~station.qc.readings.Reading`,
  which :func:`station.qc.check.check_pair` judges like any other);
* ``sd`` — the sample standard deviation (N − 1 in the denominator) of L*, a*, b* per geometry, and
  ``sd_de``, the root-mean-square ΔE*ab of the readings to the mean per geometry (None for N = 1);
* outliers — for each reading, d_i = the mean over geometries of ΔE*ab(reading_i, centre), where the
  centre is the per-geometry, per-channel **median** Lab (robust to the outlier itself). Its robust z is
  z_i = (d_i − median(d)) / s with s = max(1.4826 · MAD(d), QC_OUTLIER_SCALE_FLOOR), MAD the median
  absolute deviation (1.4826 · MAD estimates σ for normal data). A reading is an outlier when
  z_i > QC_OUTLIER_Z (3.5, Iglewicz & Hoaglin's modified z-score threshold). Only large d count (a
  reading closer than typical is never an outlier); with N < 3 nothing is flagged. ``mean_kept`` is
  the mean without the outliers.

:func:`correlate` compares two instruments on one shared panel: per common geometry the bias
mean(B) − mean(A) of L*, a*, b*, ΔE*ab between the two means, and the spread of one B − A reading
difference, sd = √(s_A² + s_B²) (readings independent; None unless each instrument has N >= 2).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from typing_extensions import TypedDict

from station.model.domain import QC_OUTLIER_SCALE_FLOOR, QC_OUTLIER_Z, aspecular_name
from station.qc.errors import QcInputError
from station.qc.readings import Reading, common_angles, lab_at
from station.qc.texture import mean_texture
from station.wire import wire_form

__all__ = [
    "GeometryBias",
    "InstrumentCorrelation",
    "RepeatGeometryWire",
    "RepeatReadingWire",
    "RepeatSummary",
    "RepeatSummaryWire",
    "correlate",
    "summarise",
]

#: 1.4826 · MAD estimates the standard deviation of normally distributed data (1 / Φ⁻¹(3/4)).
MAD_TO_SIGMA = 1.4826


def _round(x: float | None) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


class RepeatGeometryWire(TypedDict):
    """Mean L*, a*, b* at one geometry, their sample sd and the RMS ΔE*ab to the mean (None for N = 1)."""

    geometry: str
    aspecular_deg: float
    mean: list[float]
    sd: list[float] | None
    sd_de: float | None


class RepeatReadingWire(TypedDict):
    """One repeat reading (by its index among the N): mean ΔE*ab to the median centre, robust z, flag."""

    index: int
    de_to_centre: float
    robust_z: float | None
    outlier: bool


class RepeatSummaryWire(TypedDict):
    """N repeat readings: per-geometry mean and sd, each reading's robust z, the outliers and the rule."""

    n: int
    per_geometry: list[RepeatGeometryWire]
    readings: list[RepeatReadingWire]
    outliers: list[int]
    mean_without_outliers: list[list[float]]
    rule: str


@dataclass(frozen=True)
class RepeatSummary:
    """The result of :func:`summarise` (module docstring for each quantity)."""

    aspecular_deg: tuple[float, ...]
    n: int
    mean: Reading
    mean_kept: Reading
    sd: tuple[tuple[float, float, float], ...] | None
    sd_de: tuple[float, ...] | None
    reading_de: tuple[float, ...]
    robust_z: tuple[float, ...]
    outliers: tuple[bool, ...]

    @property
    def geometries(self) -> tuple[str, ...]:
        return tuple(aspecular_name(a) for a in self.aspecular_deg)

    def to_dict(self) -> RepeatSummaryWire:
        per: list[RepeatGeometryWire] = []
        for i, g in enumerate(self.geometries):
            per.append(
                {
                    "geometry": g,
                    "aspecular_deg": self.aspecular_deg[i],
                    "mean": list(self.mean.lab[i]),
                    "sd": None if self.sd is None else list(self.sd[i]),
                    "sd_de": None if self.sd_de is None else self.sd_de[i],
                }
            )
        return {
            "n": self.n,
            "per_geometry": per,
            "readings": [
                {"index": i, "de_to_centre": d, "robust_z": _round(z), "outlier": o}
                for i, (d, z, o) in enumerate(zip(self.reading_de, self.robust_z, self.outliers, strict=True))
            ],
            "outliers": [i for i, o in enumerate(self.outliers) if o],
            "mean_without_outliers": [list(r) for r in self.mean_kept.lab],
            "rule": f"robust z of mean ΔE*ab to the median reading > {QC_OUTLIER_Z:g}",
        }


def _stack(readings: Sequence[Reading], field: str) -> tuple[tuple[float, ...], NDArray[np.float64]]:
    if not readings:
        raise QcInputError(field, "at least one reading", 0)
    angles = common_angles(readings)
    if not angles:
        raise QcInputError(f"{field}.geometries", "at least one geometry shared by every reading", None)
    return angles, np.stack([lab_at(r, angles) for r in readings])


def _mean_reading(
    lab: NDArray[np.float64], angles: tuple[float, ...], like: Reading, where: str, of: Sequence[Reading]
) -> Reading:
    """The mean Lab as a reading, with the mean texture values of the readings *of*."""
    return Reading(
        angles,
        tuple((float(r[0]), float(r[1]), float(r[2])) for r in lab),
        instrument=like.instrument,
        sample=like.sample,
        measured_at=like.measured_at,
        where=where,
        texture=mean_texture([r.texture for r in of]),
    )


def summarise(readings: Sequence[Reading]) -> RepeatSummary:
    """Mean, per-geometry sd and outlier flags of N >= 1 readings of one panel (module docstring).

    The readings are judged at the geometries they all share; their spectra are not averaged.
    """
    angles, lab = _stack(readings, "readings")  # (N, G, 3)
    n = lab.shape[0]
    mean = lab.mean(axis=0)
    if n >= 2:
        sd_arr = lab.std(axis=0, ddof=1)
        de_mean = np.linalg.norm(lab - mean, axis=-1)  # (N, G)
        sd_de: tuple[float, ...] | None = tuple(float(v) for v in np.sqrt((de_mean**2).sum(axis=0) / (n - 1)))
        sd: tuple[tuple[float, float, float], ...] | None = tuple(
            (float(r[0]), float(r[1]), float(r[2])) for r in sd_arr
        )
    else:
        sd, sd_de = None, None
    centre = np.median(lab, axis=0)
    d = np.linalg.norm(lab - centre, axis=-1).mean(axis=1)  # (N,)
    med = float(np.median(d))
    scale = max(MAD_TO_SIGMA * float(np.median(np.abs(d - med))), QC_OUTLIER_SCALE_FLOOR)
    z = (d - med) / scale
    flags = tuple(bool(n >= 3 and zi > QC_OUTLIER_Z) for zi in z)
    kept = lab[[not f for f in flags]]
    first = readings[0]
    return RepeatSummary(
        angles,
        n,
        _mean_reading(mean, angles, first, "mean", readings),
        _mean_reading(
            kept.mean(axis=0),
            angles,
            first,
            "mean_kept",
            [r for r, f in zip(readings, flags, strict=True) if not f],
        ),
        sd,
        sd_de,
        tuple(float(v) for v in d),
        tuple(float(v) for v in z),
        flags,
    )


@dataclass(frozen=True)
class GeometryBias:
    """Bias of instrument B against A at one geometry: B − A of the means, and the spread of one difference."""

    geometry: str
    aspecular_deg: float
    dl: float
    da: float
    db: float
    de: float
    sd_l: float | None
    sd_a: float | None
    sd_b: float | None

    def to_dict(self) -> dict[str, Any]:
        sd = None if self.sd_l is None else [self.sd_l, self.sd_a, self.sd_b]
        return wire_form(
            self, rename={"dl": "dL", "de": "dE"}, omit={"sd_l", "sd_a", "sd_b"}, after={"sd_b": {"sd": sd}}
        )


@dataclass(frozen=True)
class InstrumentCorrelation:
    """Instrument-to-instrument comparison on a shared panel (:func:`correlate`)."""

    instrument_a: str
    instrument_b: str
    n_a: int
    n_b: int
    per_geometry: tuple[GeometryBias, ...]
    mean_de: float
    max_de: float
    worst_geometry: str

    def to_dict(self) -> dict[str, Any]:
        return wire_form(self)


def correlate(readings_a: Sequence[Reading], readings_b: Sequence[Reading]) -> InstrumentCorrelation:
    """Bias of instrument B against instrument A on one panel, per geometry (module docstring).

    ΔE is ΔE*ab between the two instruments' means (an instrument comparison, not a colour tolerance).
    """
    ang_a, lab_a = _stack(readings_a, "instrument_a")
    ang_b, lab_b = _stack(readings_b, "instrument_b")
    angles = tuple(a for a in ang_a if a in ang_b)
    if not angles:
        raise QcInputError("instrument_b.geometries", f"a geometry of instrument A ({ang_a})", ang_b)
    ia = [ang_a.index(a) for a in angles]
    ib = [ang_b.index(a) for a in angles]
    ma, mb = lab_a[:, ia].mean(axis=0), lab_b[:, ib].mean(axis=0)
    both = lab_a.shape[0] >= 2 and lab_b.shape[0] >= 2
    if both:
        spread = np.sqrt(lab_a[:, ia].var(axis=0, ddof=1) + lab_b[:, ib].var(axis=0, ddof=1))
    diff = mb - ma
    de = np.linalg.norm(diff, axis=-1)
    per = tuple(
        GeometryBias(
            aspecular_name(a),
            a,
            float(diff[i, 0]),
            float(diff[i, 1]),
            float(diff[i, 2]),
            float(de[i]),
            float(spread[i, 0]) if both else None,
            float(spread[i, 1]) if both else None,
            float(spread[i, 2]) if both else None,
        )
        for i, a in enumerate(angles)
    )
    worst = int(np.argmax(de))
    return InstrumentCorrelation(
        readings_a[0].instrument,
        readings_b[0].instrument,
        lab_a.shape[0],
        lab_b.shape[0],
        per,
        float(de.mean()),
        float(de[worst]),
        per[worst].geometry,
    )
