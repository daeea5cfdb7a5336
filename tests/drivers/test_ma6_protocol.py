"""Byte-exact protocol tests of the 6-angle ASCII family, served over a real pty with real pyserial.

Each test lists the exact (sent, reply) pairs, PyMeasure ``expected_protocol`` style; the scripted
device fails the test on any unexpected write and on pairs left over.
"""

from __future__ import annotations

import datetime as dt
import time

import numpy as np
import pytest

from station.drivers import (
    CalibrationNeeded,
    DeviceTimeout,
    HardwareFailure,
    Misread,
    ProtocolError,
    TiltDetected,
    UnexpectedReply,
)
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import SerialTransport
from tests.drivers.conftest import FAST, scripted_pty

OK = b"<000>\r\n>"
GEOM = b"45as-15,45as15,45as25,45as45,45as75,45as110"
ID_REPLY = b"MODEL=MA6\r\nSERIAL=600123\r\nFW=1.4.2\r\nGEOM=" + GEOM + b"\r\n" + OK
CONNECT = [(b"\r", OK), (b"ID\r", ID_REPLY)]


def data_body(values: list[list[float]], warn: str = "00") -> bytes:
    body = b"SN=600123\r\nCALID=CAL-600123-0007\r\nTIME=2026-11-23T06:00:00Z\r\nTEMP=29.4\r\n"
    body += f"WARN={warn}\r\nDIAG=00\r\n".encode()
    for name, row in zip(GEOM.split(b","), values, strict=True):
        body += b"R" + name + b"=" + ",".join(f"{v:.5f}" for v in row).encode() + b"\r\n"
    return body


def with_cs(body: bytes, cs: int | None = None) -> bytes:
    cs = sum(body) & 0xFFFF if cs is None else cs  # independent 16-bit byte sum
    return body + f"CS={cs:04X}\r\n".encode() + OK


VALUES = [[0.1 + 0.01 * g + 0.001 * k for k in range(31)] for g in range(6)]


def driver(path: str) -> MA6Spectro:
    return MA6Spectro(SerialTransport(path), **FAST)


def test_connect_and_identify_bytes():
    with scripted_pty(CONNECT) as (path, _), driver(path).open() as inst:
        assert inst.info is not None
        assert inst.info.model == "MA6"
        assert inst.info.serial == "600123"
        assert inst.info.firmware == "1.4.2"
        assert inst.info.geometries == ("45as-15", "45as15", "45as25", "45as45", "45as75", "45as110")


def test_status_bytes():
    st = b"CAL=OK\r\nCALID=CAL-600123-0007\r\nEXPIRES=2026-11-23T14:00:00Z\r\nTEMP=29.4\r\n" + OK
    with scripted_pty([*CONNECT, (b"ST\r", st)]) as (path, _), driver(path).open() as inst:
        s = inst.status()
    assert s.needed is None
    assert s.calibration_id == "CAL-600123-0007"
    assert s.expires == dt.datetime(2026, 11, 23, 14, 0, tzinfo=dt.UTC)
    assert s.temperature_c == 29.4


def test_calibrate_bytes():
    pairs = [
        *CONNECT,
        (b"ZC\r", OK),
        (b"WC\r", b"CALID=CAL-600123-0008\r\n" + OK),
        (b"VC\r", b"DE=0.120\r\nPASS=1\r\nEXPIRES=2026-11-23T14:00:00Z\r\n" + OK),
    ]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst:
        r = inst.calibrate()
    assert (r.calibration_id, r.steps, r.verification_de, r.passed) == (
        "CAL-600123-0008",
        ("zero", "white", "verify"),
        0.12,
        True,
    )


def test_measure_bytes_and_values():
    pairs = [
        *CONNECT,
        (b"MS\r", OK),
        (b"PO\r", b"STATE=MEASURING\r\n" + OK),
        (b"PO\r", b"STATE=IDLE\r\n" + OK),
        (b"RD\r", with_cs(data_body(VALUES))),
    ]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst:
        r = inst.measure()
    np.testing.assert_allclose(r.reflectance, VALUES, atol=5e-6)
    assert r.reflectance.shape == (6, 31)
    assert r.wavelengths_nm[0] == 400 and r.wavelengths_nm[-1] == 700
    assert (r.serial, r.calibration_id, r.temperature_c) == ("600123", "CAL-600123-0007", 29.4)
    assert r.time == dt.datetime(2026, 11, 23, 6, 0, tzinfo=dt.UTC)
    assert r.aspecular_deg == (-15, 15, 25, 45, 75, 110)


def test_bad_checksum_rejected_and_data_read_again():
    body = data_body(VALUES)
    pairs = [
        *CONNECT,
        (b"MS\r", OK),
        (b"PO\r", b"STATE=IDLE\r\n" + OK),
        (b"RD\r", with_cs(body, (sum(body) & 0xFFFF) ^ 0x0001)),
        (b"\r", OK),  # resync: a late reply drained, the line pinged, before the data is read again
        (b"RD\r", with_cs(body)),
    ]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst:
        r = inst.measure()
    np.testing.assert_allclose(r.reflectance, VALUES, atol=5e-6)


def test_a_stray_reply_to_rd_is_drained_and_the_data_read_again():
    """A reply without the CS= line (what a late poll reply looks like on a busy host) is rejected, the line
    resynchronised (drained, pinged) and the held data read again."""
    body = data_body(VALUES)
    pairs = [
        *CONNECT,
        (b"MS\r", OK),
        (b"PO\r", b"STATE=IDLE\r\n" + OK),
        (b"RD\r", b"STATE=IDLE\r\n" + OK),
        (b"\r", OK),
        (b"RD\r", with_cs(body)),
    ]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst:
        r = inst.measure()
    np.testing.assert_allclose(r.reflectance, VALUES, atol=5e-6)


def test_bad_checksum_every_time_is_a_protocol_error():
    body = data_body(VALUES)
    bad = with_cs(body, (sum(body) + 1) & 0xFFFF)
    pairs = [
        *CONNECT,
        (b"MS\r", OK),
        (b"PO\r", b"STATE=IDLE\r\n" + OK),
        (b"RD\r", bad),
        (b"\r", OK),
        (b"RD\r", bad),
    ]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst, pytest.raises(ProtocolError):
        inst.measure()


@pytest.mark.parametrize(
    ("code", "error", "attr"),
    [
        (130, CalibrationNeeded, ("step", "white")),
        (131, CalibrationNeeded, ("step", "zero")),
        (111, HardwareFailure, ("code", 111)),
        (140, TiltDetected, ("code", 140)),
        (50, Misread, ("code", 50)),
        (999, UnexpectedReply, ("code", 999)),
    ],
)
def test_device_error_sends_clear_error_then_raises(code, error, attr):
    pairs = [*CONNECT, (b"MS\r", f"<{code:03d}>\r\n>".encode()), (b"CE\r", OK)]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst, pytest.raises(error) as info:
        inst.measure()
    assert getattr(info.value, attr[0]) == attr[1]


def test_partial_reply_resync_then_retry():
    st = b"CAL=OK\r\nCALID=C1\r\nEXPIRES=NONE\r\nTEMP=25.0\r\n" + OK
    pairs = [*CONNECT, (b"ST\r", st[:9]), (b"\r", OK), (b"ST\r", st)]
    t0 = time.monotonic()
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst:
        assert inst.status().calibration_id == "C1"
    assert time.monotonic() - t0 < 2.0


def test_garbage_before_reply_is_protocol_error_then_retry():
    st = b"CAL=WHITE\r\nCALID=C1\r\nEXPIRES=NONE\r\nTEMP=25.0\r\n" + OK
    pairs = [*CONNECT, (b"ST\r", b"\xfe\x13" + st), (b"\r", OK), (b"ST\r", st)]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst:
        assert inst.status().needed == "white"


def test_reflectance_out_of_range_is_misread():
    values = [row[:] for row in VALUES]
    values[2][5] = 3.5
    pairs = [
        *CONNECT,
        (b"MS\r", OK),
        (b"PO\r", b"STATE=IDLE\r\n" + OK),
        (b"RD\r", with_cs(data_body(values))),
    ]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst, pytest.raises(Misread):
        inst.measure()


def test_missing_geometry_is_unexpected_reply():
    body = data_body(VALUES).replace(b"R45as110=", b"R45as111=")
    pairs = [*CONNECT, (b"MS\r", OK), (b"PO\r", b"STATE=IDLE\r\n" + OK), (b"RD\r", with_cs(body))]
    with scripted_pty(pairs) as (path, _), driver(path).open() as inst, pytest.raises(UnexpectedReply):
        inst.measure()


def test_stuck_busy_times_out_bounded():
    busy = b"STATE=MEASURING\r\n" + OK
    with scripted_pty(
        [*CONNECT, (b"MS\r", OK)] + [(b"PO\r", busy)] * 200,
    ) as (path, dev):
        inst = driver(path).open()
        t0 = time.monotonic()
        with pytest.raises(DeviceTimeout):
            inst.measure()
        elapsed = time.monotonic() - t0
        inst.close()
        # the number of polls depends on timing; the bound is what matters, then a clear-error
        assert dev.unexpected[0][0] == b"CE\r"
        dev.pairs.clear()
        dev.unexpected.clear()
    assert 0.5 <= elapsed < 2.0  # limit + clear-error timeout + resync rounds


def test_baud_negotiation_bytes(ma6):
    # power-on rate 9600: the probe at 115200 gives line noise, 9600 answers, then 115200BR
    assert ma6.device.received[:5] == [b"\r", b"\r", b"115200BR\r", b"\r", b"ID\r"]
    assert ma6.device.baud == 115200
    assert ma6.host.baudrate() == 115200
