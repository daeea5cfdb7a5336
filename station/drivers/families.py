"""The instrument families: the one list of what the station can drive and simulate.

Every other place that names the families — the address parser and allow-list, ``make_instrument``,
device discovery, the simulator spawner, ``station serve --simulators``, the service settings, the
scan module's ``sim:NAME`` devices, the viewer's device picker and the simulators' own configuration —
derives from :data:`FAMILIES`. Adding a family is one :class:`Family` entry here (see CONTRIBUTING,
"Adding an instrument").

The entries name code by dotted path, never by import: the driver class is imported when an
instrument is built, and the simulator is a program (``python -m <simulator>``) because runtime code
never imports :mod:`simulators` (import-linter contract). The simulator finds its family by the name it
is started for (``simulators.config`` checks it against :data:`SIM_FAMILY_NAMES`).

This module imports nothing of the station, so the command line can read the names at start-up.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

__all__ = [
    "FAMILIES",
    "FAMILY_NAMES",
    "SIM_DRIFT_SCALE_MAX",
    "SIM_FAMILY_NAMES",
    "Family",
    "Transport",
    "family_named",
    "first_on",
    "names_pattern",
]

Transport = Literal["serial", "usb", "hid"]
"""How the real device is reached: a serial line (or pty), USB bulk endpoints, HID reports.

Every family is also reachable on a serial line (the simulators serve a pty; ``hid`` families through the
HID-over-pty bridge)."""


@dataclass(frozen=True)
class Family:
    """One instrument family.

    Attributes
    ----------
    name
        The address prefix (``NAME@WHERE``) and simulator device (``sim:NAME``); lower-case letters and
        digits.
    driver
        ``module:Class`` of the :class:`~station.drivers.instrument.Instrument` subclass.
    transport
        The transport of the real device (:data:`Transport`).
    label
        What the device pickers show for its simulator.
    simulator
        The module run as ``python -m <simulator>`` for ``sim:NAME``; ``None``: no simulator.
    baudrate
        Serial line speed in baud (serial transports and the simulator's pty).
    usb_id
        ``(VID, PID)`` of the real device on a ``usb`` or ``hid`` transport: what discovery looks for and
        what the simulator presents. The simulated families use the pid.codes open-source VID 0x1209 with
        test PIDs (docs/udev.md gives the matching udev rules). ``None`` on a serial transport.
    """

    name: str
    driver: str
    transport: Transport
    label: str
    simulator: str | None = None
    baudrate: int = 9600
    usb_id: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        if not (self.name.isascii() and self.name.isalnum() and self.name.islower()):
            raise ValueError(f"family name {self.name!r}: lower-case letters and digits only")
        if ":" not in self.driver:
            raise ValueError(f"family {self.name!r}: driver must be 'module:Class', got {self.driver!r}")
        if (self.usb_id is None) != (self.transport == "serial"):
            raise ValueError(
                f"family {self.name!r}: a usb or hid transport has a (VID, PID), a serial one none"
            )
        if self.usb_id is not None and not all(0 <= n <= 0xFFFF for n in self.usb_id):
            raise ValueError(f"family {self.name!r}: VID and PID are 16-bit, got {self.usb_id!r}")

    def device_id(self) -> tuple[int, int]:
        """``(VID, PID)`` of the real device (:attr:`usb_id`); a serial family has none."""
        if self.usb_id is None:
            raise LookupError(f"family {self.name!r} is reached on a serial line: it has no USB id")
        return self.usb_id


#: The families, in the order the pickers offer them. The first family on a transport is the one an
#: address without ``NAME@`` (``/dev/ttyACM0``, ``usb:…``, ``hid:…``) means.
FAMILIES: tuple[Family, ...] = (
    Family(
        "ma6",
        "station.drivers.ma6:MA6Spectro",
        "serial",
        "simulated 6-angle spectro (ASCII serial)",
        simulator="simulators.ma6",
    ),
    Family(
        "ma3",
        "station.drivers.ma3:MA3Spectro",
        "usb",
        "simulated 3-angle spectro (binary frames)",
        simulator="simulators.ma3",
        baudrate=115200,
        usb_id=(0x1209, 0xCA03),
    ),
    Family(
        "gloss",
        "station.drivers.gloss:GlossMeter",
        "hid",
        "simulated 20/60/85 gloss meter (HID reports)",
        simulator="simulators.gloss",
        usb_id=(0x1209, 0xCA60),
    ),
)

#: Every family's name, in :data:`FAMILIES` order.
FAMILY_NAMES: tuple[str, ...] = tuple(f.name for f in FAMILIES)
#: The families with a simulator (``sim:NAME``), in :data:`FAMILIES` order.
SIM_FAMILY_NAMES: tuple[str, ...] = tuple(f.name for f in FAMILIES if f.simulator is not None)
#: The largest scale of a simulator's stated drift across runs (``--drift``: 1 = stated, 0 = none;
#: dimensionless), for the simulators and for ``station serve --drift`` alike.
SIM_DRIFT_SCALE_MAX = 100.0


def family_named(name: str) -> Family | None:
    """The family called *name*, or ``None``."""
    return next((f for f in FAMILIES if f.name == name), None)


def first_on(transport: Transport) -> Family:
    """The family an address on *transport* without a ``NAME@`` prefix means."""
    return next(f for f in FAMILIES if f.transport == transport)


def names_pattern(names: tuple[str, ...] = FAMILY_NAMES) -> str:
    """A regular-expression alternation of *names* (``ma6|ma3|gloss``), for address patterns."""
    return "|".join(names)
