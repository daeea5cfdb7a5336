"""Statistical process control of ΔE over time: an individuals (X) chart with moving-range limits.

For values x_1 … x_n in time order (n >= 2), the moving ranges are MR_i = |x_i − x_{i−1}|
(i = 2 … n); σ̂ = MR̄ / d₂ with d₂ = 1.128 (the bias factor of a range of two, Montgomery,
*Introduction to Statistical Quality Control*, individuals chart); the centre line is x̄ and the
control limits x̄ ± QC_SPC_SIGMAS · σ̂ (3σ). The lower limit is clipped at 0, since ΔE >= 0. A point is
out of control beyond either limit (Western Electric rule 1). The moving range, rather than the overall
standard deviation, estimates the short-term σ, so a drift widens the limits less and stands out.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.model.domain import QC_SPC_SIGMAS
from station.qc.errors import QcInputError

__all__ = ["D2_RANGE_OF_TWO", "ControlLimits", "control_limits"]

#: d₂ for subgroups of two: E[range of two standard normal values] = 2/√π.
D2_RANGE_OF_TWO = 1.128


@dataclass(frozen=True)
class ControlLimits:
    """Centre line, σ̂ from the moving range, lower and upper control limits and the points beyond them."""

    centre: float
    sigma: float
    mr_bar: float
    lcl: float
    ucl: float
    out_of_control: tuple[int, ...]

    def to_dict(self) -> dict[str, Any]:
        return {
            "centre": self.centre,
            "sigma": self.sigma,
            "mr_bar": self.mr_bar,
            "lcl": self.lcl,
            "ucl": self.ucl,
            "out_of_control": list(self.out_of_control),
            "rule": f"individuals chart, sigma = mean moving range / {D2_RANGE_OF_TWO}, "
            f"limits centre ± {QC_SPC_SIGMAS:g} sigma (lower clipped at 0)",
        }


def control_limits(values: Sequence[float]) -> ControlLimits:
    """Individuals-chart limits of *values* in time order (module docstring); needs n >= 2 finite values."""
    x = np.asarray(values, dtype=float).reshape(-1)
    if x.size < 2 or not np.all(np.isfinite(x)):
        raise QcInputError("values", "at least two finite values in time order", x.size)
    mr_bar = float(np.abs(np.diff(x)).mean())
    sigma = mr_bar / D2_RANGE_OF_TWO
    centre = float(x.mean())
    ucl = centre + QC_SPC_SIGMAS * sigma
    lcl = max(0.0, centre - QC_SPC_SIGMAS * sigma)
    out = tuple(int(i) for i in np.flatnonzero((x > ucl) | (x < lcl)))
    return ControlLimits(centre, sigma, mr_bar, lcl, ucl, out)
