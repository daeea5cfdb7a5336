"""Errors of the scan path, rooted at :class:`station.errors.StationError`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from station.errors import InputError, StationError

if TYPE_CHECKING:
    from station.scan.calibration import CalibrationStep

__all__ = ["CalibrationCancelled", "CalibrationStepError", "ScanError", "ScanInputError"]


class ScanError(StationError):
    """Base of every error the scan path raises itself (drivers and ingest raise their own)."""


class ScanInputError(ScanError, InputError):
    """A bad argument to the scan path: names the field (``device``, ``gloss_device``, ``instrument``…),
    the accepted values and what was given."""


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
