"""Discovery: candidate instruments on serial ports, USB (VID:PID) and HID, plus the simulators.

USB and HID ids of the simulated families use the pid.codes open-source VID 0x1209 with test PIDs
(docs/udev.md gives the matching udev rules). Each lookup that fails (no libusb, no hidraw) is
reported in ``notes`` instead of raising, so ``station instruments list`` always answers.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from station.drivers.families import FAMILIES

__all__ = ["GLOSS_USB_ID", "MA3_USB_ID", "DeviceCandidate", "list_devices"]

MA3_USB_ID = (0x1209, 0xCA03)
GLOSS_USB_ID = (0x1209, 0xCA60)
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

    out = []
    for port in list_ports.comports():
        if any(h in port.device for h in SERIAL_HINTS):
            out.append(
                DeviceCandidate(
                    f"ma6@{port.device}", "ma6", "serial", port.description or port.hwid or "serial port"
                )
            )
    return out


def _usb(backend: Any = None) -> list[DeviceCandidate]:
    import usb.core

    devs = usb.core.find(find_all=True, idVendor=MA3_USB_ID[0], idProduct=MA3_USB_ID[1], backend=backend)
    return [
        DeviceCandidate(
            f"ma3@usb:{d.idVendor:04x}:{d.idProduct:04x}", "ma3", "usb", f"bus {d.bus} address {d.address}"
        )
        for d in devs
    ]


def _hid(enumerate_fn: Callable[[int, int], Sequence[dict[str, Any]]] | None = None) -> list[DeviceCandidate]:
    if enumerate_fn is None:
        import hid

        enumerate_fn = hid.enumerate
    out = []
    for d in enumerate_fn(*GLOSS_USB_ID):
        path = d["path"].decode() if isinstance(d["path"], bytes) else str(d["path"])
        out.append(
            DeviceCandidate(
                f"gloss@hid:{path}",
                "gloss",
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
