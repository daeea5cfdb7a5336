"""The instrument addresses the product accepts from a caller: an allow-list, not a pass-through.

An address handed to :func:`open_instrument` from outside the process (the service's connect route,
a settings file) is checked here first. Accepted forms (``FAMILY`` is a name of
:data:`station.drivers.families.FAMILIES`; ``ma3`` is the USB family, ``gloss`` the HID one):

=============================================  ==============================================================
``sim:ma6`` / ``sim:ma3`` / ``sim:gloss``       a simulator subprocess started for the caller
``FAMILY@/dev/ttyUSBn``, ``/dev/ttyACMn``       a USB serial adapter or CDC-ACM device (``n`` digits)
``FAMILY@/dev/serial/by-id/NAME``               udev's stable name of one (``by-path`` too; no ``/`` in NAME)
``FAMILY@COMn``                                 a Windows serial port
``FAMILY@socket://HOST:PORT``                   serial over raw TCP, HOST in the allowed instrument hosts
``FAMILY@rfc2217://HOST:PORT``                  serial over RFC 2217, HOST in the allowed instrument hosts
``ma3@usb:VID:PID[:SERIAL]``                    USB bulk endpoints (4 hex digits each)
``gloss@hid:VID:PID``, ``gloss@hid:/dev/hidrawN``  a HID device by id or by its hidraw node
=============================================  ==============================================================

Everything else is refused with a :class:`DriverInputError` naming the field ``address``: pyserial's
other URL handlers (``spy://`` writes a trace to any file, ``loop://``, ``hwgrep://``, ``alt://``), any
other file path, query strings and credentials in URLs. The check looks at the text only: it never
touches the filesystem, so its message cannot tell which files exist.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from station.drivers.errors import DriverInputError
from station.drivers.families import FAMILIES, FAMILY_NAMES, SIM_FAMILY_NAMES, names_pattern

__all__ = ["ACCEPTED", "SIM_KINDS", "check_address", "is_serial_url", "parse_host_entry"]

#: The ``sim:NAME`` kinds (the families with a simulator).
SIM_KINDS = SIM_FAMILY_NAMES
#: Human-readable list of the accepted forms (the ``accepted`` of every refusal).
ACCEPTED = (
    f"sim:{names_pattern(SIM_KINDS)}, FAMILY@/dev/ttyUSBn, FAMILY@/dev/ttyACMn, FAMILY@/dev/serial/by-id/NAME, "
    "FAMILY@COMn, FAMILY@socket://HOST:PORT or FAMILY@rfc2217://HOST:PORT (HOST configured in "
    "CACAD_INSTRUMENT_HOSTS)"
    + "".join(f", {f.name}@usb:VID:PID[:SERIAL]" for f in FAMILIES if f.transport == "usb")
    + "".join(
        f", {f.name}@hid:VID:PID or {f.name}@hid:/dev/hidrawN" for f in FAMILIES if f.transport == "hid"
    )
)
MAX_LENGTH = 255

_SIM = re.compile(rf"^sim:({names_pattern(SIM_KINDS)})$")
_SERIAL_PATH = re.compile(
    r"^(?:/dev/tty(?:USB|ACM)\d{1,3}|/dev/serial/by-(?:id|path)/[A-Za-z0-9][A-Za-z0-9._:+-]{0,199}"
    r"|/dev/cu\.usbmodem[A-Za-z0-9]{1,32}|COM\d{1,3})$"
)
_TCP = re.compile(r"^(socket|rfc2217)://([A-Za-z0-9.-]{1,253}|\[[0-9A-Fa-f:.]{2,45}\]):(\d{1,5})$")
_USB = re.compile(r"^usb:[0-9a-fA-F]{4}:[0-9a-fA-F]{4}(?::[A-Za-z0-9._-]{1,64})?$")
_HID = re.compile(r"^hid:(?:[0-9a-fA-F]{4}:[0-9a-fA-F]{4}|/dev/hidraw\d{1,3})$")
_FAMILY = re.compile(rf"^({names_pattern()})@(.+)$", re.DOTALL)
_TRANSPORT = {f.name: f.transport for f in FAMILIES}


def parse_host_entry(entry: str) -> tuple[str, int | None]:
    """``HOST`` or ``HOST:PORT`` (``[v6]:PORT``) of the allowed-hosts setting, host lower-cased."""
    text = entry.strip()
    m = re.fullmatch(r"^(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9.-]+)(?::(\d{1,5}))?$", text)
    if m is None:
        raise DriverInputError("instrument_hosts", "HOST or HOST:PORT entries", entry)
    port = int(m.group(2)) if m.group(2) else None
    if port is not None and not 1 <= port <= 65535:
        raise DriverInputError("instrument_hosts", "a port in 1..65535", entry)
    return m.group(1).lower(), port


def is_serial_url(where: str) -> bool:
    """Whether *where* is one of the two pyserial URL forms the product uses (``socket://``, ``rfc2217://``)."""
    return _TCP.fullmatch(where) is not None


def _refuse(why: str = "") -> DriverInputError:
    # The address is not echoed: it may be long, and the refusal says what is accepted instead.
    return DriverInputError("address", ACCEPTED, detail=why)


def check_address(address: str, *, tcp_hosts: Iterable[str] = ()) -> str:
    """Return *address* when it is an accepted form (see the module docstring); raise otherwise.

    *tcp_hosts* are ``HOST`` or ``HOST:PORT`` entries an administrator allowed for ``socket://`` and
    ``rfc2217://``; with none, no TCP address is accepted. Raises :class:`DriverInputError` (field
    ``address``) for every other form. Purely textual: no file is opened or looked up.
    """
    if not isinstance(address, str) or not 3 <= len(address) <= MAX_LENGTH:
        raise _refuse(f"3 to {MAX_LENGTH} characters")
    if _SIM.fullmatch(address):
        return address
    m = _FAMILY.fullmatch(address)
    if m is None:
        raise _refuse(f"FAMILY@WHERE with FAMILY one of {', '.join(FAMILY_NAMES)}")
    family, where = m.group(1), m.group(2)
    if _SERIAL_PATH.fullmatch(where):  # every family: hid ones through the HID-over-serial bridge
        return address
    tcp = _TCP.fullmatch(where)
    if tcp is not None:
        host, port = tcp.group(2).lower(), int(tcp.group(3))
        if not 1 <= port <= 65535:
            raise _refuse("a TCP port in 1..65535")
        allowed = [parse_host_entry(e) for e in tcp_hosts]
        if not any(h == host and (p is None or p == port) for h, p in allowed):
            raise _refuse("this TCP host and port are not among the configured instrument hosts")
        return address
    if _TRANSPORT[family] == "usb" and _USB.fullmatch(where):
        return address
    if _TRANSPORT[family] == "hid" and _HID.fullmatch(where):
        return address
    raise _refuse("not a supported transport for this family")
