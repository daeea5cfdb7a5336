"""ColorSnap's results: the matches, the per-query statistics and the thesis Fig. 5.10 warnings.

Thresholds are in ΔE units of the chosen metric (``far``), ΔE*ab (Hue Shift Index, eq 5.3.3) and
degrees (direction of the a*b* travel 15° → 110°).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from station.formulate.library import Library

__all__ = [
    "FAR_THRESHOLD",
    "HUE_SHIFT_THRESHOLD",
    "TRAVEL_ANGLE_THRESHOLD_DEG",
    "SnapMatch",
    "SnapResult",
    "SnapStats",
    "snap_warnings",
]

#: Mean ΔE per angle of the best match above which the design is "far outside the library".
FAR_THRESHOLD: Mapping[str, float] = MappingProxyType({"cie76": 5.0, "cie2000": 3.0, "din6175": 3.0})
#: Hue Shift Index difference (ΔE*ab units) above which the match does not capture the design's travel.
HUE_SHIFT_THRESHOLD = 5.0
#: Angle between design and match a*b* travel vectors (degrees) above which travel is "not captured".
TRAVEL_ANGLE_THRESHOLD_DEG = 45.0


@dataclass(frozen=True)
class SnapMatch:
    """One ColorSnap match: library row, code, summed ΔE and ΔE per angle (same order as the angles)."""

    index: int
    code: str
    sum_de: float
    de_per_angle: tuple[float, ...]


@dataclass(frozen=True)
class SnapStats:
    """How much of the index one query opened: its own numbers, never shared with another query.

    ``leaves_visited`` leaves of ``leaves`` in the index searched were opened (their paints bounded or
    evaluated); ``candidates`` paints went through the exact ΔE kernel; ``path`` names the search:
    ``"compiled"`` (numba CIEDE2000 walk), ``"flat"`` (NumPy CIEDE2000, one kernel call) or
    ``"bounded"`` (leaf-by-leaf branch and bound).
    """

    leaves_visited: int = 0
    leaves: int = 0
    candidates: int = 0
    path: str = ""


@dataclass(frozen=True)
class SnapResult:
    """Top-k matches (best first), the metric, the angles and the Fig. 5.10 warnings."""

    matches: tuple[SnapMatch, ...]
    method: str
    angles_deg: tuple[float, ...]
    design_lab: tuple[tuple[float, float, float], ...]
    warnings: tuple[str, ...] = ()
    stats: SnapStats = field(default=SnapStats(), compare=False)

    def to_dict(self) -> dict[str, object]:
        """JSON-able form used by the CLI and the service."""
        return {
            "matches": [
                {"code": m.code, "sum_de": m.sum_de, "de_per_angle": list(m.de_per_angle), "index": m.index}
                for m in self.matches
            ],
            "warnings": list(self.warnings),
            "method": self.method,
            "angles_deg": list(self.angles_deg),
        }


def snap_warnings(
    library: Library,
    result: SnapResult,
    far_threshold: float | None = None,
    hue_shift_threshold: float = HUE_SHIFT_THRESHOLD,
    travel_angle_threshold_deg: float = TRAVEL_ANGLE_THRESHOLD_DEG,
) -> tuple[str, ...]:
    """The two problems ColorSnap's view exposes (thesis Fig. 5.10), as sentences.

    1. *Far outside the library*: the best match's mean ΔE per angle exceeds *far_threshold*
       (default :data:`FAR_THRESHOLD` for the metric); says whether the design is more chromatic than
       every library paint of similar hue (the "too deep in saturation" case).
    2. *Travel not captured*: the design's a*b* travel (110° − 15°) points in a direction more than
       *travel_angle_threshold_deg* away from the match's, or their Hue Shift Indices (eq 5.3.3)
       differ by more than *hue_shift_threshold* (the "off-radial travel" case).
    """
    from station.model.indices import library_indices

    out: list[str] = []
    if not result.matches:
        return ()
    best = result.matches[0]
    threshold = FAR_THRESHOLD[result.method] if far_threshold is None else far_threshold
    design = np.asarray(result.design_lab)
    mean_de = best.sum_de / len(result.angles_deg)
    if mean_de > threshold:
        msg = (
            f"design lies far outside the library: nearest paint {best.code} differs by mean "
            f"{mean_de:.2f} {result.method} per angle (threshold {threshold:g})"
        )
        c_design = float(np.hypot(design[:, 1], design[:, 2]).max())
        std = library.angle_columns(result.angles_deg)
        c_lib = np.hypot(std[..., 1], std[..., 2]).max(1)
        h_design = math.degrees(math.atan2(design[0, 2], design[0, 1])) % 360
        h_lib = np.degrees(np.arctan2(std[:, 0, 2], std[:, 0, 1])) % 360
        near = np.abs((h_lib - h_design + 180) % 360 - 180) < 20
        if c_design > 10 and near.any() and c_design > float(c_lib[near].max()):
            msg += (
                f"; the design is more chromatic (C* {c_design:.1f}) than every library paint of its hue "
                f"(max C* {float(c_lib[near].max()):.1f})"
            )
        out.append(msg)
    try:
        i15, i110 = result.angles_deg.index(15.0), result.angles_deg.index(110.0)
        i45 = result.angles_deg.index(45.0)
    except ValueError:
        return tuple(out)
    match = library.angle_columns(result.angles_deg)[best.index]
    t_design = design[i110, 1:] - design[i15, 1:]
    t_match = match[i110, 1:] - match[i15, 1:]
    n_d, n_m = float(np.hypot(*t_design)), float(np.hypot(*t_match))
    if n_d > 3.0:
        cosang = float(t_design @ t_match) / (n_d * n_m) if n_m > 1e-9 else -1.0
        ang = math.degrees(math.acos(max(-1.0, min(1.0, cosang))))
        hsi_d = library_indices(design[i15], design[i45], design[i110]).hue_shift_index
        hsi_m = library_indices(match[i15], match[i45], match[i110]).hue_shift_index
        hsi_gap = abs(hsi_d - hsi_m) if hsi_d is not None and hsi_m is not None else 0.0
        if ang > travel_angle_threshold_deg or hsi_gap > hue_shift_threshold:
            out.append(
                f"the match {best.code} does not capture the design's travel direction: a*b* travel "
                f"15°→110° differs by {ang:.0f}° (threshold {travel_angle_threshold_deg:g}°)"
                + (f", Hue Shift Index differs by {hsi_gap:.1f}" if hsi_gap else "")
            )
    return tuple(out)
