"""Injectable faults, shared by the three simulators (tests call :meth:`FaultPlan.add`; the command
line takes ``--fault SPEC``, repeatable).

``SPEC`` is ``NAME[@COMMAND][:N]``. A transient fault fires on the next *N* (default 1) matching
commands; a persistent one stays on until cleared; ``hang-after:N`` hangs after *N* commands.
COMMAND names are the family-neutral labels ``ID ST ZC WC VC MS PO RD`` (default per fault below).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

__all__ = ["FAULTS", "FaultPlan", "FaultSpecError"]

# name -> (default command, persistent, what happens)
FAULTS: dict[str, tuple[str, bool, str]] = {
    "unplug": ("MS", False, "device vanishes during the measurement (pty/USB/HID gone)"),
    "no-reply": ("MS", False, "the command is swallowed, no reply"),
    "slow-reply": ("MS", False, "the reply comes after the slow delay (past a short driver timeout)"),
    "corrupt-checksum": ("RD", False, "the data reply carries a wrong checksum"),
    "partial-frame": ("RD", False, "only the first half of the reply is sent"),
    "garbage": ("ID", False, "line noise is sent before the reply"),
    "stuck-busy": ("PO", True, "the measurement never finishes"),
    "cal-expired": ("MS", True, "white calibration expired: calibration needed"),
    "lamp-failure": ("MS", True, "lamp failure (hardware)"),
    "out-of-range": ("RD", True, "saturated reading, out-of-range warning bit"),
    "tilt": ("MS", True, "instrument not flat on the sample"),
    "battery-low": ("MS", True, "battery too low to measure"),
    "port-held": ("", True, "another process holds the port (serial flock / USB EBUSY / HID busy)"),
    "hang-after": ("", True, "stops answering after N commands until reconnected"),
    "device-busy": ("MS", False, "device answers busy (code 170) once"),
    "cal-failure": ("WC", False, "a calibration step (ZC, WC, VC) answers error 120, calibration failed"),
}


class FaultSpecError(ValueError):
    """An unknown fault name or a malformed spec."""


@dataclass
class _Armed:
    command: str
    remaining: int  # < 0: persistent


class FaultPlan:
    """Thread-safe set of armed faults."""

    def __init__(self, specs: tuple[str, ...] | list[str] = ()) -> None:
        self._lock = threading.Lock()
        self._armed: dict[str, _Armed] = {}
        self.hang_after: int | None = None
        for spec in specs:
            self.add(spec)

    def add(self, spec: str) -> None:
        """Arm a fault from ``NAME[@COMMAND][:N]``."""
        head, _, count = spec.partition(":")
        name, _, command = head.partition("@")
        if name not in FAULTS:
            raise FaultSpecError(f"unknown fault {name!r}; known: {', '.join(FAULTS)}")
        default_cmd, persistent, _ = FAULTS[name]
        try:
            n = int(count) if count else (-1 if persistent else 1)
        except ValueError as exc:
            raise FaultSpecError(f"bad count in {spec!r}") from exc
        with self._lock:
            if name == "hang-after":
                self.hang_after = n if count else 20
                return
            self._armed[name] = _Armed(command or default_cmd, n)

    def clear(self, name: str | None = None) -> None:
        """Disarm one fault, or all."""
        with self._lock:
            if name is None:
                self._armed.clear()
                self.hang_after = None
            elif name == "hang-after":
                self.hang_after = None
            else:
                self._armed.pop(name, None)

    def active(self, name: str) -> bool:
        """Whether *name* is armed (does not consume it)."""
        with self._lock:
            return name in self._armed

    def fire(self, name: str, command: str) -> bool:
        """Consume one firing of *name* if it is armed for *command*; return whether it fires."""
        with self._lock:
            armed = self._armed.get(name)
            if armed is None or (armed.command and armed.command != command):
                return False
            if armed.remaining > 0:
                armed.remaining -= 1
                if armed.remaining == 0:
                    del self._armed[name]
            return True
