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
from station.drivers.families import FAMILIES, FAMILY_NAMES, family_named, first_on
from station.drivers.instrument import Instrument
from station.drivers.readings import (
    WAVELENGTHS_NM,
    CalibrationResult,
    CalibrationStatus,
    CalibrationStepResult,
    GlossReading,
    InstrumentInfo,
    SpectralReading,
)

__all__ = [
    "FAMILIES",
    "FAMILY_NAMES",
    "WAVELENGTHS_NM",
    "BatteryLow",
    "CalibrationNeeded",
    "CalibrationResult",
    "CalibrationStatus",
    "CalibrationStepResult",
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


def split_address(address: str) -> tuple[str, str]:
    """Return ``(family, where)`` for an address; infer the family from the transport if omitted.

    Without ``NAME@``, ``usb:…`` means the first USB family of :data:`FAMILIES`, ``hid:…`` the first HID
    family and a serial path or URL the first serial family.
    """
    head, sep, rest = address.partition("@")
    if sep and head in FAMILY_NAMES:
        family, where = head, rest
    elif address.startswith("usb:"):
        family, where = first_on("usb").name, address
    elif address.startswith("hid:"):
        family, where = first_on("hid").name, address
    elif address.startswith(("/", "socket://", "rfc2217://", "COM")):
        family, where = first_on("serial").name, address
    else:
        raise DriverInputError(
            "address",
            f"FAMILY@WHERE ({'|'.join(FAMILY_NAMES)}) or a serial path, usb:VID:PID, hid:PATH",
            address,
        )
    if not where:
        raise DriverInputError("address", "a non-empty location after '@'", address)
    return family, where


def make_instrument(address: str, **options: Any) -> Instrument[Any]:
    """Build (not open) the instrument for *address*; *options* go to the instrument class.

    The family's entry in :data:`FAMILIES` names the driver class and its transport: ``usb:…`` opens USB
    bulk endpoints, ``hid:…`` a HID device, any other location a serial line at the family's baud rate
    (a ``hid`` family's serial line is the HID-over-pty bridge of its simulator).
    """
    import importlib

    from station.drivers.transport import HidTransport, SerialTransport, UsbTransport, parse_usb_id

    name, where = split_address(address)
    family = family_named(name)
    if family is None:  # split_address returns registered names only
        raise DriverInputError("address", f"FAMILY@WHERE ({'|'.join(FAMILY_NAMES)})", address)
    module, _, cls_name = family.driver.partition(":")
    cls = getattr(importlib.import_module(module), cls_name)
    if family.transport == "usb" and where.startswith("usb:"):
        vid, pid, serial = parse_usb_id(where[4:])
        return cls(UsbTransport(vid, pid, serial, backend=options.pop("backend", None)), **options)
    if family.transport == "hid":
        from station.drivers.gloss import HidBridgeDevice, hid_path_for

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
                address=f"{family.name}@{where}",
            )
        return cls(transport, **options)
    return cls(SerialTransport(where, baudrate=family.baudrate), **options)


def open_instrument(address: str, **options: Any) -> Instrument[Any]:
    """Open the instrument at *address* (see the module docstring) and return it connected.

    The caller owns it: close it (``with open_instrument(a) as inst:``). A second open of the same
    address in this process raises :class:`DeviceInUse`.
    """
    return make_instrument(address, **options).open()
