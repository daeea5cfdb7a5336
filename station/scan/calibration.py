"""Calibrate step by step: each reference (black trap, white tile, verification tile, gloss standard) is
asked for, then read by its own instrument command, one at a time.

A :class:`CalibrationSession` lists the steps of the spectrophotometer and of the paired gloss meter
(:attr:`CalibrationSession.steps`, each with the prompt to show before it); :meth:`~CalibrationSession.run_next`
runs the next one; :meth:`~CalibrationSession.cancel` stops between steps. The families' protocols give
each spectrophotometer step its own command (``ZC`` / ``WC`` / ``VC``; ``CAL_ZERO`` / ``CAL_WHITE`` /
``CAL_VERIFY``); the gloss meter's protocol has one calibration command (0x20), its one step. A zero
invalidates the white calibration on the instrument itself, so a session cancelled or failed after
its first step leaves the instrument needing calibration (its own status says which step); cancelled
before its first step, it leaves the instrument as it was. The session is "calibrated" only when every
step passed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from station.drivers import CalibrationResult, CalibrationStepResult, DriverError
from station.drivers.instrument import combine_steps
from station.scan.devices import Device
from station.scan.errors import ScanError

__all__ = [
    "STEP_PROMPTS",
    "CalibrationCancelled",
    "CalibrationSession",
    "CalibrationStep",
    "CalibrationStepError",
    "calibrate",
]

#: step → (title, what to do before it); ``{device}`` is the device as typed.
STEP_PROMPTS: Mapping[str, tuple[str, str]] = MappingProxyType(
    {
        "zero": (
            "Black trap",
            "Place {device} on its black trap (zero calibration): the trap clean and dry, the "
            "measuring port fully on its opening.",
        ),
        "white": (
            "White tile",
            "Place {device} on its white calibration tile: clean, the serial number of the tile matching "
            "the instrument's certificate.",
        ),
        "verify": (
            "Verification tile",
            "Place {device} on its verification tile: it is read and compared with the tile's certificate "
            "(ΔE00).",
        ),
        "gloss": (
            "Gloss standard",
            "Place the gloss meter {device} on its calibration standard (the black glass tile), clean and flat.",
        ),
    }
)

#: The session's states: "calibrated" only once every step has passed.
CALIBRATED, NOT_CALIBRATED = "calibrated", "not calibrated"


@dataclass(frozen=True)
class CalibrationStep:
    """One step of a session: the device (as typed), the step name, its place (1-based) and prompt."""

    device: str
    step: str
    index: int
    total: int

    @property
    def title(self) -> str:
        """Short name of the reference read (``White tile``)."""
        return STEP_PROMPTS[self.step][0]

    @property
    def prompt(self) -> str:
        """What the operator does before the step."""
        head = f"Step {self.index} of {self.total} — {self.title.lower()}. "
        return head + STEP_PROMPTS[self.step][1].format(device=self.device)


class CalibrationSession:
    """The calibration steps of *devices* (``None`` skipped), run one at a time.

    Not thread-safe: one front drives it (the viewer from its worker thread, one step at a time).
    """

    def __init__(self, *devices: Device | None) -> None:
        self._devices = {d.name: d for d in devices if d is not None}
        names = [(d.name, s) for d in self._devices.values() for s in d.instrument.calibration_steps]
        self.steps = tuple(CalibrationStep(n, s, i + 1, len(names)) for i, (n, s) in enumerate(names))
        self._done: list[CalibrationStepResult] = []
        self._stopped = False

    @property
    def next(self) -> CalibrationStep | None:
        """The step to prompt for and run next; ``None`` once all ran, or after a cancel or failure."""
        if self._stopped or len(self._done) == len(self.steps):
            return None
        return self.steps[len(self._done)]

    @property
    def state(self) -> str:
        """``calibrated`` once every step passed, else ``not calibrated``."""
        done = len(self._done) == len(self.steps) and bool(self.steps)
        return CALIBRATED if done and not self._stopped else NOT_CALIBRATED

    def run_next(self) -> CalibrationStepResult:
        """Run :attr:`next` on its instrument.

        Raises :class:`CalibrationStepError` naming the step (the driver's error as its cause, or the
        verification ΔE00 the instrument failed); the session then stops, not calibrated.
        """
        step = self.next
        if step is None:
            raise ScanError("calibration: no step left, the session is over (cancelled, failed or done)")
        try:
            result = self._devices[step.device].instrument.calibrate_step(step.step)
        except DriverError as exc:
            self._stopped = True
            raise CalibrationStepError(step, str(exc)) from exc
        if not result.passed:
            self._stopped = True
            de = "" if result.verification_de is None else f" (ΔE00 {result.verification_de:.3f})"
            raise CalibrationStepError(step, f"the instrument failed the reading{de}")
        self._done.append(result)
        return result

    def cancel(self) -> None:
        """Stop between steps: nothing more runs and the session stays not calibrated."""
        self._stopped = True

    def run_all(self) -> list[tuple[str, CalibrationResult]]:
        """Run every remaining step without prompting (the service, ``--yes``): :meth:`results`."""
        while self.next is not None:
            self.run_next()
        return self.results()

    def results(self) -> list[tuple[str, CalibrationResult]]:
        """``(device, result)`` per device of the steps run so far (all of them once calibrated)."""
        out = []
        for name in self._devices:
            mine = [r for s, r in zip(self.steps, self._done, strict=False) if s.device == name]
            if mine:
                out.append((name, combine_steps(mine)))
        return out


class CalibrationStepError(ScanError):
    """A calibration step failed: names the device, the step and its place, and why (the driver's error
    as ``__cause__``, or the verification ΔE00 the instrument failed). The session is then over, not
    calibrated."""

    def __init__(self, step: CalibrationStep, reason: str) -> None:
        self.step = step
        self.reason = reason
        super().__init__(
            f"calibration of {step.device} failed at step {step.index} of {step.total} "
            f"({step.title.lower()}): {reason}; the instrument is not calibrated"
        )


class CalibrationCancelled(ScanError):
    """The operator cancelled a calibration before *step*: nothing more was read and the instrument is
    not calibrated (after a first step it needs calibrating again; before one, it is as it was)."""

    def __init__(self, step: CalibrationStep) -> None:
        self.step = step
        super().__init__(
            f"calibration of {step.device} cancelled before step {step.index} of {step.total} "
            f"({step.title.lower()}): not calibrated"
        )


def calibrate(*devices: Device | None) -> list[tuple[str, CalibrationResult]]:
    """Run every calibration step of each open device in order (``None`` skipped), without prompting:
    ``(device, result)``. A failed step raises :class:`~station.scan.CalibrationStepError` naming it;
    to prompt before each step, drive a :class:`~station.scan.CalibrationSession` instead."""
    return CalibrationSession(*devices).run_all()
