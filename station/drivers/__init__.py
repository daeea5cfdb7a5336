"""Instrument drivers: transport → protocol → instrument (typed readings).

Public entry points:

* :func:`open_instrument` — open a device by address and return a connected :class:`Instrument`.
* :func:`station.drivers.simproc.spawn_simulator` — start a simulator subprocess (``sim:ma6``…).
* :func:`station.drivers.discovery.list_devices` — serial ports, USB and HID candidates.

Address forms (``FAMILY@WHERE``; the family may be omitted where the transport implies it):

=====================================  =============================================================
``ma6@/dev/ttyACM0``, ``/dev/ttyACM0``  6-angle ASCII family on a serial path (or a pty)
``ma6@socket://host:port``              same, serial-over-TCP; ``rfc2217://host:port`` with baud control
``ma3@usb:1209:ca03[:SERIAL]``          3-angle binary family on USB bulk endpoints (pyusb)
``ma3@/dev/pts/N``                      the same frames over a serial line (simulator subprocess)
``gloss@hid:1209:ca60`` / ``hid:PATH``  20/60/85° gloss meter on HID reports (hidapi)
``gloss@/dev/pts/N``                    the same reports through the HID-over-pty bridge
=====================================  =============================================================
"""

from __future__ import annotations

from typing import Any

from station.drivers.errors import (
    BatteryLow,
    CalibrationNeeded,
    CommunicationError,
    DeviceInUse,
    DeviceTimeout,
    Disconnected,
    DriverError,
    DriverInputError,
    HardwareFailure,
    Misread,
    ProtocolError,
    TiltDetected,
    UnexpectedReply,
)
from station.drivers.instrument import Instrument
from station.drivers.readings import (
    WAVELENGTHS_NM,
    CalibrationResult,
    CalibrationStatus,
    GlossReading,
    InstrumentInfo,
    SpectralReading,
)

__all__ = [
    "FAMILIES",
    "WAVELENGTHS_NM",
    "BatteryLow",
    "CalibrationNeeded",
    "CalibrationResult",
    "CalibrationStatus",
    "CommunicationError",
    "DeviceInUse",
    "DeviceTimeout",
    "Disconnected",
    "DriverError",
    "DriverInputError",
    "GlossReading",
    "HardwareFailure",
    "Instrument",
    "InstrumentInfo",
    "Misread",
    "ProtocolError",
    "SpectralReading",
    "TiltDetected",
    "UnexpectedReply",
    "make_instrument",
    "open_instrument",
    "split_address",
]

FAMILIES = ("ma6", "ma3", "gloss")


def split_address(address: str) -> tuple[str, str]:
    """Return ``(family, where)`` for an address; infer the family from the transport if omitted."""
    head, sep, rest = address.partition("@")
    if sep and head in FAMILIES:
        family, where = head, rest
    elif address.startswith("usb:"):
        family, where = "ma3", address
    elif address.startswith("hid:"):
        family, where = "gloss", address
    elif address.startswith(("/", "socket://", "rfc2217://", "COM")):
        family, where = "ma6", address
    else:
        raise DriverInputError(
            "address", "FAMILY@WHERE (ma6|ma3|gloss) or a serial path, usb:VID:PID, hid:PATH", address
        )
    if not where:
        raise DriverInputError("address", "a non-empty location after '@'", address)
    return family, where


def make_instrument(address: str, **options: Any) -> Instrument[Any]:
    """Build (not open) the instrument for *address*; *options* go to the instrument class."""
    from station.drivers.transport import HidTransport, SerialTransport, UsbTransport, parse_usb_id

    family, where = split_address(address)
    if family == "ma6":
        from station.drivers.ma6 import MA6Spectro

        return MA6Spectro(SerialTransport(where), **options)
    if family == "ma3":
        from station.drivers.ma3 import MA3Spectro

        if where.startswith("usb:"):
            vid, pid, serial = parse_usb_id(where[4:])
            return MA3Spectro(UsbTransport(vid, pid, serial, backend=options.pop("backend", None)), **options)
        return MA3Spectro(SerialTransport(where, baudrate=115200), **options)
    from station.drivers.gloss import GlossMeter, HidBridgeDevice, hid_path_for

    if where.startswith("hid:"):
        transport = HidTransport(
            hid_path_for(where[4:], options.pop("enumerate_fn", None)),
            options.pop("device_factory", None),
            address=where,
        )
    else:
        transport = HidTransport(
            where.encode(),
            lambda: HidBridgeDevice(),
            lambda v, p: [{"path": where.encode()}],
            address=f"gloss@{where}",
        )
    return GlossMeter(transport, **options)


def open_instrument(address: str, **options: Any) -> Instrument[Any]:
    """Open the instrument at *address* (see the module docstring) and return it connected.

    The caller owns it: close it (``with open_instrument(a) as inst:``). A second open of the same
    address in this process raises :class:`DeviceInUse`.
    """
    return make_instrument(address, **options).open()
