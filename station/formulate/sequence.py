"""Metallic colour sequences (thesis §5.4.4): steps between principal colours, evenly spaced by eye.

The thesis's architectural wall needed "metallic color sequences … that blended into the surrounding
environment but were also harmonious", made by interpolating between the principal metallic colours the
architect chose. Here the path runs through the designs' face/flop/travel/gloss parameters, piecewise
linearly from one principal colour to the next: face and flop Lab, travel θ_clamp (degrees) and gloss (GU)
each linear in a parameter u ∈ [0, 1] per segment. A solid (no travel) takes the travel of its neighbour,
which leaves its colour unchanged (face = flop at every angle).

Even spacing is perceptual, not parametric: the path is sampled densely (:data:`DENSE_PER_SEGMENT` points per
segment), its length measured as the sum of

    d(P, Q) = mean over θ ∈ {15°, 45°, 110°} of ΔE00(P(θ), Q(θ))

between consecutive samples (CIEDE2000, :func:`station.model.difference.delta_e`), the steps placed at
equal arc length by linear interpolation of the cumulative length, then moved along the path until
consecutive steps are equally far apart by d itself (the chords; a bending path's chords are shorter
than its arcs). Every principal colour is a step: the
steps of each segment are in proportion to its perceptual length (at least one interval each), so the
spacing is even within a segment and as even as whole steps allow across segments.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from station.model.difference import delta_e
from station.model.domain import ANGLES_3
from station.model.errors import ModelInputError
from station.model.representations import FaceFlopTravelGloss

#: Dense samples per segment for the arc length (error of the step spacing well under 1 %).
DENSE_PER_SEGMENT = 256
MAX_STEPS = 200
#: Steps of one segment are equal in d to this relative tolerance (or after CHORD_ITERATIONS passes).
CHORD_RTOL = 1e-3
CHORD_ITERATIONS = 30


@dataclass(frozen=True)
class ColourSequence:
    """Steps of a sequence, best read in order; ``step_de`` the distance d between consecutive steps."""

    designs: tuple[FaceFlopTravelGloss, ...]
    step_de: tuple[float, ...]
    principal_steps: tuple[int, ...]

    def to_dict(self) -> dict[str, object]:
        """JSON-able summary (the designs as face/flop/travel/gloss)."""
        return {
            "steps": [
                {
                    "name": d.name,
                    "face": list(d.face),
                    "flop": list(d.flop),
                    "travel_deg": d.travel_deg,
                    "gloss_gu": d.gloss_gu,
                }
                for d in self.designs
            ],
            "step_de": list(self.step_de),
            "principal_steps": list(self.principal_steps),
            "metric": "mean CIEDE2000 over 15/45/110 degrees",
        }


def _between(a: FaceFlopTravelGloss, b: FaceFlopTravelGloss, u: float, name: str) -> FaceFlopTravelGloss:
    """The design a fraction *u* of the way from *a* to *b* in face/flop/travel/gloss."""
    ta = a.travel_deg if a.travel_deg is not None else b.travel_deg
    tb = b.travel_deg if b.travel_deg is not None else a.travel_deg
    fa, fb = np.asarray(a.face), np.asarray(b.face)
    pa, pb = np.asarray(a.flop), np.asarray(b.flop)
    f, p = (1 - u) * fa + u * fb, (1 - u) * pa + u * pb
    face = (float(f[0]), float(f[1]), float(f[2]))
    flop = (float(p[0]), float(p[1]), float(p[2]))
    travel = None if ta is None or tb is None else (1 - u) * ta + u * tb
    gloss = (1 - u) * a.gloss_gu + u * b.gloss_gu
    return FaceFlopTravelGloss(face, face if travel is None else flop, travel, gloss, name=name)


def _lab(design: FaceFlopTravelGloss) -> NDArray[np.float64]:
    return np.asarray(design.lab_at(np.asarray(ANGLES_3)), dtype=np.float64)


def colour_sequence(principals: Sequence[FaceFlopTravelGloss], steps: int) -> ColourSequence:
    """*steps* designs from the first principal colour to the last through the others (module docstring).

    Raises :class:`ModelInputError` for fewer than two principal colours or a step count under their
    number or over :data:`MAX_STEPS`."""
    k = len(principals)
    if k < 2:
        raise ModelInputError("principals", "at least 2 principal colours", k)
    if not k <= steps <= MAX_STEPS:
        raise ModelInputError("steps", f"{k} (the principal colours) to {MAX_STEPS}", steps)
    u = np.linspace(0.0, 1.0, DENSE_PER_SEGMENT + 1)
    seg_len = []
    for a, b in itertools.pairwise(principals):
        labs = np.array([_lab(_between(a, b, float(x), "")) for x in u])
        d = delta_e(labs[:-1], labs[1:], "cie2000").mean(axis=1)
        seg_len.append(np.concatenate([[0.0], np.cumsum(d)]))
    lengths = np.array([s[-1] for s in seg_len])
    intervals = _apportion(lengths, steps - 1)
    designs: list[FaceFlopTravelGloss] = []
    principal_steps = [0]
    for i, (a, b) in enumerate(itertools.pairwise(principals)):
        us = _even_chords(a, b, u, seg_len[i], int(intervals[i]))
        for x in us[1:] if i else us:  # a segment's first step is the previous segment's last
            designs.append(_between(a, b, float(x), f"step {len(designs) + 1}"))
        principal_steps.append(len(designs) - 1)
    labs = np.array([_lab(d) for d in designs])
    step_de = delta_e(labs[:-1], labs[1:], "cie2000").mean(axis=1)
    return ColourSequence(tuple(designs), tuple(float(x) for x in step_de), tuple(principal_steps))


def _even_chords(
    a: FaceFlopTravelGloss, b: FaceFlopTravelGloss, u: NDArray[np.float64], arc: NDArray[np.float64], n: int
) -> NDArray[np.float64]:
    """Parameters of *n* + 1 steps from *a* to *b* with equal d between consecutive steps.

    Start at equal arc length, then reweight: each interval's share of the arc is scaled by
    mean chord / its chord and renormalised, until the chords agree to :data:`CHORD_RTOL` (a path that
    bends in colour space has chords shorter than its arcs, more so where it bends more)."""
    if arc[-1] <= 0:
        return np.linspace(0.0, 1.0, n + 1)
    share = np.full(n, arc[-1] / n)
    us = np.interp(np.concatenate([[0.0], np.cumsum(share)]), arc, u)
    for _ in range(CHORD_ITERATIONS):
        labs = np.array([_lab(_between(a, b, float(x), "")) for x in us])
        chords = delta_e(labs[:-1], labs[1:], "cie2000").mean(axis=1)
        if chords.min() <= 0 or chords.max() / chords.min() - 1 < CHORD_RTOL:
            break
        share = share * chords.mean() / chords
        share *= arc[-1] / share.sum()
        us = np.interp(np.concatenate([[0.0], np.cumsum(share)]), arc, u)
    return us


def _apportion(lengths: NDArray[np.float64], total: int) -> NDArray[np.int64]:
    """Whole intervals per segment, at least one each, in proportion to *lengths* (largest remainder)."""
    n = len(lengths)
    share = lengths / lengths.sum() * total if lengths.sum() > 0 else np.full(n, total / n)
    base = np.maximum(np.floor(share).astype(np.int64), 1)
    while base.sum() > total:
        base[np.argmax(base - share)] -= 1
    order = np.argsort(-(share - base))
    i = 0
    while base.sum() < total:
        base[order[i % n]] += 1
        i += 1
    return base
