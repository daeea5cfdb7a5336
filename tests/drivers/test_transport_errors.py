"""Each library's errors map onto the one driver error set (pyserial texts/errnos, pyusb errnos)."""

from __future__ import annotations

import errno

import pytest
import serial
import usb.core

from station.drivers import CommunicationError, DeviceInUse, Disconnected
from station.drivers.transport import _serial_error, _usb_error, parse_usb_id


@pytest.mark.parametrize(
    ("exc", "cls"),
    [
        (
            serial.SerialException(
                "device reports readiness to read but returned no data "
                "(device disconnected or multiple access on port?)"
            ),
            Disconnected,
        ),
        (serial.SerialException("read failed: [Errno 5] Input/output error"), Disconnected),
        (
            serial.SerialException(
                "Could not exclusively lock port /dev/ttyACM0: [Errno 11] Resource temporarily unavailable"
            ),
            DeviceInUse,
        ),
        (OSError(errno.EACCES, "Permission denied"), CommunicationError),
        (serial.SerialException("[Errno 2] could not open port /dev/ttyX: No such file"), Disconnected),
    ],
)
def test_serial_errors(exc, cls):
    err = _serial_error("/dev/ttyACM0", exc)
    assert type(err) is cls
    if cls is CommunicationError:
        assert "udev" in str(err)


@pytest.mark.parametrize(
    ("eno", "cls"),
    [
        (errno.EBUSY, DeviceInUse),
        (errno.ENODEV, Disconnected),
        (errno.EPIPE, Disconnected),
        (errno.EACCES, CommunicationError),
    ],
)
def test_usb_errors(eno, cls):
    assert type(_usb_error("usb:1209:ca03", usb.core.USBError("x", -1, eno))) is cls


def test_parse_usb_id():
    assert parse_usb_id("1209:ca03") == (0x1209, 0xCA03, None)
    assert parse_usb_id("1209:ca03:300456") == (0x1209, 0xCA03, "300456")
