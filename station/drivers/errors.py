"""One error set for every transport and instrument family.

Categories follow ArgyllCMS's ``inst_code`` families and the Konica Minolta CM-MISDK error codes
(research note instruments.md §1, §4): a caller catches :class:`DriverError` (a
:class:`station.errors.StationError`) or one category, whichever transport (pyserial, pyusb, hidapi)
raised underneath. Each library's own exception is chained as ``__cause__``.
"""

from __future__ import annotations

from station.errors import InputError, StationError

__all__ = [
    "BatteryLow",
    "CalibrationNeeded",
    "CommunicationError",
    "DeviceInUse",
    "DeviceTimeout",
    "Disconnected",
    "DriverError",
    "DriverInputError",
    "HardwareFailure",
    "Misread",
    "ProtocolError",
    "TiltDetected",
    "UnexpectedReply",
    "error_for_code",
]


class DriverError(StationError):
    """Base of every instrument-driver error; ``code`` is the device's error code when it sent one."""

    def __init__(self, message: str, code: int | None = None) -> None:
        self.code = code
        super().__init__(message if code is None else f"{message} (device code {code})")


class DriverInputError(InputError):
    """A bad argument to a driver call (address, timeout, geometry name)."""


class CommunicationError(DriverError, ConnectionError):
    """The transport failed: the port could not be opened, written or read.

    Also a :class:`ConnectionError`, so code written for the standard library's errors catches it."""


class Disconnected(CommunicationError):
    """The device went away (unplugged, pty closed, USB ENODEV, hidapi −1 after removal)."""


class DeviceInUse(CommunicationError):
    """Another process or owner holds the device (serial lock, USB EBUSY, open in this process)."""


class DeviceTimeout(DriverError, TimeoutError):
    """No complete reply within the time limit (also: busy for longer than allowed).

    Also a :class:`TimeoutError`, so code written for the standard library's errors catches it."""


class ProtocolError(DriverError):
    """A malformed frame: bad header/footer, bad checksum, truncated or garbled reply."""


class UnexpectedReply(DriverError):
    """A well-formed reply that does not answer the command sent (wrong type, id or fields)."""


class CalibrationNeeded(DriverError):
    """The instrument must be calibrated before measuring; ``step`` names the step (zero/white/verify)."""

    def __init__(self, step: str, code: int | None = None) -> None:
        self.step = step
        super().__init__(f"calibration needed: {step}", code)


class HardwareFailure(DriverError):
    """The instrument reports a hardware fault (lamp failure, A/D, motor)."""


class Misread(DriverError):
    """The reading is out of the instrument's range or inconsistent; it was rejected."""


class TiltDetected(DriverError):
    """The instrument was not flat on the sample."""


class BatteryLow(DriverError):
    """The battery is too low to measure."""


# Device error codes shared by the three simulated families (after CM-MISDK; docs/protocols/*.md).
ERROR_CODES: dict[int, tuple[type[DriverError], str]] = {
    25: (UnexpectedReply, "invalid parameter"),
    30: (UnexpectedReply, "command not accepted in this state"),
    45: (UnexpectedReply, "no data"),
    50: (Misread, "reflectance out of range"),
    51: (Misread, "gloss out of range"),
    110: (HardwareFailure, "device error"),
    111: (HardwareFailure, "lamp failure"),
    120: (HardwareFailure, "calibration failed"),
    130: (CalibrationNeeded, "white"),
    131: (CalibrationNeeded, "zero"),
    132: (CalibrationNeeded, "verify"),
    133: (CalibrationNeeded, "gloss"),
    140: (TiltDetected, "tilt detected"),
    170: (DeviceInUse, "busy"),
    180: (BatteryLow, "battery low"),
    210: (DeviceTimeout, "internal timeout"),
}

OK_CODES = frozenset({0, 1})  # 0 = success, 1 = success with warning (CM-MISDK KmWarning)


def error_for_code(code: int) -> DriverError:
    """Return the typed error for a device error *code* (an unknown code is an UnexpectedReply)."""
    cls, text = ERROR_CODES.get(code, (UnexpectedReply, "unknown device error"))
    if cls is CalibrationNeeded:
        return CalibrationNeeded(text, code)
    return cls(text, code)
