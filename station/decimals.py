"""How many decimals show every multiple of a step: the one rule for amounts weighed on a scale.

A scale weighs in steps of its resolution (0.1 g, 0.25 g, 2.5 g); a table of amounts rounded to that
step, in grams or scaled to grams per kg, shows each of them only with enough decimals.
"""

from __future__ import annotations

import math

__all__ = ["step_decimals"]


def step_decimals(step: float, most: int = 4) -> int:
    """Decimals that show every multiple of *step* (> 0) exactly: 0.05 → 2, 0.25 → 2, 0.2 → 1, 2.5 → 1,
    5 → 0. A step with no short decimal form (0.1 g in a 3 kg batch: 0.0333… g/kg) gets one digit past
    its first significant one; never more than *most*.

    >>> [step_decimals(s) for s in (0.05, 0.25, 0.2, 2.5, 5.0, 0.1 / 3)]
    [2, 2, 1, 1, 0, 3]
    """
    for d in range(most + 1):
        scaled = step * 10**d
        if abs(scaled - round(scaled)) <= 1e-6 * max(1.0, scaled):
            return d
    return min(most, max(0, -math.floor(math.log10(step))) + 1)
