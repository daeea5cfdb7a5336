"""Discovery: candidate instruments on serial ports, USB (VID:PID) and HID, plus the simulators.

The USB and HID ids looked for are the families' (``Family.usb_id`` in
:mod:`station.drivers.families`); a serial port is offered as the first serial family. Each lookup that fails (no libusb, no hidraw) is
reported in ``notes`` instead of raising, so ``station instruments list`` always answers.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from station.drivers.families import FAMILIES, first_on

__all__ = ["DeviceCandidate", "list_devices"]

SERIAL_HINTS = ("ttyACM", "ttyUSB", "usbmodem", "COM")


@dataclass(frozen=True)
class DeviceCandidate:
    """A device that may be an instrument: its open_instrument address and what we know."""

    address: str
    family: str
    transport: str
    description: str

    def to_dict(self) -> dict[str, str]:
        """JSON-able form."""
        return asdict(self)


def _serial() -> list[DeviceCandidate]:
    from serial.tools import list_ports

    name = first_on("serial").name  # a serial port does not say which family answers on it
    out = []
    for port in list_ports.comports():
        if any(h in port.device for h in SERIAL_HINTS):
            out.append(
                DeviceCandidate(
                    f"{name}@{port.device}", name, "serial", port.description or port.hwid or "serial port"
                )
            )
    return out


def _usb(backend: Any = None) -> list[DeviceCandidate]:
    import usb.core

    out = []
    for family in FAMILIES:
        if family.transport != "usb":
            continue
        vid, pid = family.device_id()
        out += [
            DeviceCandidate(
                f"{family.name}@usb:{d.idVendor:04x}:{d.idProduct:04x}",
                family.name,
                "usb",
                f"bus {d.bus} address {d.address}",
            )
            for d in usb.core.find(find_all=True, idVendor=vid, idProduct=pid, backend=backend)
        ]
    return out


def _hid(enumerate_fn: Callable[[int, int], Sequence[dict[str, Any]]] | None = None) -> list[DeviceCandidate]:
    if enumerate_fn is None:
        import hid

        enumerate_fn = hid.enumerate
    out = []
    for family in FAMILIES:
        if family.transport != "hid":
            continue
        for d in enumerate_fn(*family.device_id()):
            path = d["path"].decode() if isinstance(d["path"], bytes) else str(d["path"])
            out.append(
                DeviceCandidate(
                    f"{family.name}@hid:{path}",
                    family.name,
                    "hid",
                    f"{d.get('manufacturer_string') or ''} {d.get('product_string') or ''}".strip(),
                )
            )
    return out


def list_devices(
    usb_backend: Any = None,
    hid_enumerate: Callable[[int, int], Sequence[dict[str, Any]]] | None = None,
) -> tuple[list[DeviceCandidate], list[str]]:
    """Return ``(candidates, notes)``; notes say which lookups could not run and why."""
    found: list[DeviceCandidate] = []
    notes: list[str] = []
    for name, fn in (
        ("serial", _serial),
        ("usb", lambda: _usb(usb_backend)),
        ("hid", lambda: _hid(hid_enumerate)),
    ):
        try:
            found += fn()
        except Exception as exc:  # a missing libusb/hidraw must not hide the other buses
            notes.append(f"{name}: {type(exc).__name__}: {exc}")
    for family in FAMILIES:
        if family.simulator is not None:
            found.append(DeviceCandidate(f"sim:{family.name}", family.name, "simulator", family.label))
    return found, notes
