"""The vocabulary of a reproduced thesis result: one compared quantity, one figure, one experiment.

A :class:`Quantity` holds the thesis's value, ours, a stated tolerance and how they are compared
(:data:`MODES`); its verdict is computed, never stored: ``agrees`` when ours lies within the tolerance of
the thesis's value, ``differs`` otherwise, and a quantity that differs must carry the documented reason
(construction refuses one that does not, so no disagreement goes unexplained). A quantity that a parameter
of ours was set to reproduce states that calibration and reads ``calibrated to the thesis`` whatever the
difference: a number tuned to match is no evidence of agreement.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from station.reproduce.errors import ReproduceError, ReproduceInputError
from station.wire import wire_form

Mode = Literal["within", "at_most", "at_least"]
#: How ours is compared with the thesis's value t under tolerance τ:
#: ``within`` |ours − t| ≤ τ; ``at_most`` ours ≤ t + τ (the thesis states a bound, e.g. "real time");
#: ``at_least`` ours ≥ t − τ (e.g. "over 96 %").
MODES: tuple[Mode, ...] = ("within", "at_most", "at_least")
Verdict = Literal["agrees", "differs", "calibrated to the thesis"]
#: The verdict of a quantity that a parameter of ours was set to reproduce (:attr:`Quantity.calibration`).
CALIBRATED: Verdict = "calibrated to the thesis"


def _finite(value: float, name: str) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ReproduceError(f"{name} is not a finite number ({value!r})")
    return v


@dataclass(frozen=True)
class Quantity:
    """One number of the thesis beside ours.

    Parameters
    ----------
    figure
        Thesis figure, equation or section id, e.g. ``"4.4"``, ``"eq 3.3.8"``, ``"§5.3.4"``.
    quantity
        What is compared, in words.
    unit
        Unit of ``thesis``, ``ours`` and ``tolerance`` (``"ΔE*ab"``, ``"deg"``, ``"ms"``, ``"%"``, …).
    thesis
        The thesis's value (where it gives words, "about 2 ΔE", the number it names).
    ours
        The value our code computes.
    tolerance
        The stated tolerance (≥ 0), in ``unit``.
    reason
        Why ours differs (required when the verdict is ``differs``; reported only then).
    mode
        One of :data:`MODES`.
    source
        Where the thesis's value comes from (section, figure caption, closed form).
    reference
        What ``thesis`` holds: ``"thesis"`` (a value the thesis states or implies), or another reference
        where the thesis gives none (e.g. ``"shipped table"`` for the basis errors it omits).
    calibration
        Which parameter of ours was set so that ours meets the thesis's value, and how (empty when
        nothing was). A calibrated quantity's verdict is :data:`CALIBRATED`, never ``agrees``.
    """

    figure: str
    quantity: str
    unit: str
    thesis: float
    ours: float
    tolerance: float
    reason: str = ""
    mode: Mode = "within"
    source: str = ""
    reference: str = "thesis"
    calibration: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "thesis", _finite(self.thesis, f"{self.quantity}: thesis value"))
        object.__setattr__(self, "ours", _finite(self.ours, f"{self.quantity}: our value"))
        tol = _finite(self.tolerance, f"{self.quantity}: tolerance")
        if tol < 0:
            raise ReproduceInputError("tolerance", "a tolerance >= 0", tol)
        object.__setattr__(self, "tolerance", tol)
        if self.mode not in MODES:
            raise ReproduceInputError("mode", " | ".join(MODES), self.mode)
        if self._met() is False and not self.calibration.strip() and not self.reason.strip():
            raise ReproduceError(
                f"{self.figure} {self.quantity}: ours ({self.ours:.4g}) differs from the thesis "
                f"({self.thesis:.4g} ± {self.tolerance:.3g}) and no reason is documented"
            )

    @property
    def difference(self) -> float:
        """ours − thesis, in ``unit``."""
        return self.ours - self.thesis

    @property
    def verdict(self) -> Verdict:
        """``agrees`` when ours meets the thesis's value under :attr:`mode` and :attr:`tolerance`;
        :data:`CALIBRATED` when a parameter of ours was set to meet it (:attr:`calibration`)."""
        if self.calibration.strip():
            return CALIBRATED
        return "agrees" if self._met() else "differs"

    def _met(self) -> bool:
        """Whether ours meets the thesis's value under :attr:`mode` and :attr:`tolerance`."""
        d = self.difference
        slack = 1e-12 * max(1.0, abs(self.thesis))
        if self.mode == "within":
            ok = abs(d) <= self.tolerance + slack
        elif self.mode == "at_most":
            ok = d <= self.tolerance + slack
        else:
            ok = d >= -self.tolerance - slack
        return bool(ok)

    def to_dict(self) -> dict[str, Any]:
        """The JSON record of ``station reproduce --json``: the difference and the verdict beside the
        values, the reason only where ours differs, no calibration as ``None``."""
        return wire_form(
            self,
            omit={"reason", "calibration"},
            after={
                "ours": {"difference": self.difference},
                "mode": {
                    "verdict": self.verdict,
                    "reason": self.reason if self.verdict == "differs" else None,
                    "calibration": self.calibration or None,
                },
            },
        )


@dataclass(frozen=True)
class Figure:
    """A PNG written by an experiment: our picture to set beside the thesis's figure."""

    figure: str
    path: Path
    caption: str


@dataclass(frozen=True)
class ExperimentResult:
    """What one experiment produced: the compared quantities, its pictures and notes (markdown)."""

    experiment: str
    quantities: tuple[Quantity, ...]
    figures: tuple[Figure, ...] = ()
    notes: str = ""
    seconds: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.quantities:
            raise ReproduceError(f"experiment {self.experiment} compared no quantity")


@dataclass(frozen=True)
class Experiment:
    """One thesis experiment run on our code.

    Parameters
    ----------
    key
        Short id, e.g. ``"ch4-fig4.4"``.
    chapter
        Thesis chapter (2–5) or ``"gloss"``.
    title
        One line.
    figures
        The thesis ids it reproduces (``"4.4"``, ``"3.3"``, ``"5.4"``); ``--figure`` selects by them.
    run
        ``run(out_dir)`` → :class:`ExperimentResult`; ``out_dir`` is where PNGs go (``None``: no PNG).
    slow
        True for experiments that take more than a few seconds (run by the command, not by the tests).
    quick_of
        Key of the slow experiment this one is the quick version of (left out when that one runs).
    """

    key: str
    chapter: str
    title: str
    figures: tuple[str, ...]
    run: Callable[[Path | None], ExperimentResult]
    slow: bool = False
    quick_of: str = ""
