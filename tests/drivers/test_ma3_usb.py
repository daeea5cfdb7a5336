"""3-angle binary family over the pyusb simulator backend: ``usb.core.find(backend=...)`` and the
driver's real pyusb code. Request/reply frames are built here independently (struct + hashlib) and
compared byte for byte."""

from __future__ import annotations

import hashlib
import struct
import time

import numpy as np
import pytest

from simulators.faults import FaultPlan
from simulators.ma3 import Ma3Firmware
from simulators.physics import DEFAULT_DESIGN, InstrumentCharacter, SpectroPhysics
from simulators.scripted import ScriptedFirmware
from simulators.usb_backend import SimUsbBackend, SimUsbDevice
from station.drivers import (
    BatteryLow,
    CalibrationNeeded,
    DeviceInUse,
    DeviceTimeout,
    Disconnected,
    HardwareFailure,
    Misread,
    ProtocolError,
    TiltDetected,
    open_instrument,
)
from station.drivers.ma3 import MA3Spectro
from station.drivers.transport import UsbTransport
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab
from tests.drivers.conftest import Timing

ANGLES = (15, 45, 110)
FAST: Timing = {"timeout_s": 0.2, "retries": 1, "measure_limit_s": 0.5}


def raw_frame(msg: int, rid: int, payload: bytes = b"", flags: int = 0x02, error: int = 0) -> bytes:
    head = struct.pack("<2sHHHIIII", b"\xc1\xc0", 0x1000, flags, error, msg, rid, len(payload), 0)
    return head + payload + hashlib.md5(head + payload).digest() + b"\xc5\xc4\xc3\xc2"


def reply(msg: int, rid: int, payload: bytes = b"", error: int = 0) -> bytes:
    return raw_frame(msg, rid, payload, 0x01 | (0x08 if error else 0x04), error)


def frame_len(buf: bytes) -> int | None:
    return None if len(buf) < 24 else 24 + struct.unpack_from("<I", buf, 16)[0] + 20


ID_PAYLOAD = (
    b"MA3\0\0\0\0\0"
    + b"300456\0\0"
    + b"2.0.7\0\0\0"
    + bytes([3])
    + struct.pack("<6b", 45, 15, 45, 45, 45, 110)
)
CONNECT = [(raw_frame(0x0001, 1), reply(0x0001, 1, ID_PAYLOAD))]
VALUES = np.linspace(0.05, 0.6, 93).reshape(3, 31)


def data_payload(values=VALUES, warn: int = 0) -> bytes:
    body = struct.pack("<8sIIfHHB", b"300456", 7, 1795413600, 29.25, warn, 0, 3)
    for a, row in zip(ANGLES, values, strict=True):
        body += struct.pack("<bb31f", 45, a, *row)
    return body


def scripted(pairs) -> tuple[MA3Spectro, ScriptedFirmware]:
    fw = ScriptedFirmware(pairs, frame_len)
    inst = MA3Spectro(UsbTransport(0x1209, 0xCA03, backend=SimUsbBackend([SimUsbDevice(fw)])), **FAST)
    return inst, fw


def finish(fw: ScriptedFirmware) -> None:
    assert fw.device.unexpected == [], fw.device.unexpected
    assert fw.device.leftover == []


def test_identify_bytes():
    inst, fw = scripted(CONNECT)
    with inst.open():
        assert inst.info is not None
        assert (inst.info.model, inst.info.serial, inst.info.firmware) == ("MA3", "300456", "2.0.7")
        assert inst.info.geometries == ("45as15", "45as45", "45as110")
    finish(fw)


def test_measure_bytes():
    pairs = [
        *CONNECT,
        (raw_frame(0x20, 2), reply(0x20, 2)),
        (raw_frame(0x21, 3), reply(0x21, 3, b"\x01")),
        (raw_frame(0x21, 4), reply(0x21, 4, b"\x00")),
        (raw_frame(0x22, 5), reply(0x22, 5, data_payload())),
    ]
    inst, fw = scripted(pairs)
    with inst.open():
        r = inst.measure()
    finish(fw)
    np.testing.assert_allclose(r.reflectance, VALUES, rtol=1e-6)
    assert (r.serial, r.calibration_id, r.temperature_c) == ("300456", "CAL-300456-0007", 29.25)
    assert r.time.timestamp() == 1795413600


def test_status_and_calibrate_bytes():
    pairs = [
        *CONNECT,
        (raw_frame(0x02, 2), reply(0x02, 2, struct.pack("<BIIf", 2, 7, 0, 24.5))),
        (raw_frame(0x10, 3), reply(0x10, 3)),
        (raw_frame(0x11, 4), reply(0x11, 4, struct.pack("<I", 8))),
        (raw_frame(0x12, 5), reply(0x12, 5, struct.pack("<fBI", 0.125, 1, 1795442400))),
    ]
    inst, fw = scripted(pairs)
    with inst.open():
        s = inst.status()
        c = inst.calibrate()
    finish(fw)
    assert (s.needed, s.calibration_id, s.expires, s.temperature_c) == (
        "white",
        "CAL-300456-0007",
        None,
        24.5,
    )
    assert (c.calibration_id, c.verification_de, c.passed) == ("CAL-300456-0008", 0.125, True)
    assert c.expires is not None
    assert c.expires.timestamp() == 1795442400


def test_bad_checksum_rejects_reading_and_reads_again():
    good = reply(0x22, 5, data_payload())
    bad = good[:-20] + bytes(16) + good[-4:]
    pairs = [
        *CONNECT,
        (raw_frame(0x20, 2), reply(0x20, 2)),
        (raw_frame(0x21, 3), reply(0x21, 3, b"\x00")),
        (raw_frame(0x22, 4), bad),
        (raw_frame(0x22, 5), reply(0x22, 5, data_payload())),
    ]
    inst, fw = scripted(pairs)
    with inst.open():
        r = inst.measure()
    finish(fw)
    np.testing.assert_allclose(r.reflectance, VALUES, rtol=1e-6)


def test_nack_sends_clear_then_typed_error():
    pairs = [*CONNECT, (raw_frame(0x20, 2), reply(0x20, 2, error=130)), (raw_frame(0x30, 3), reply(0x30, 3))]
    inst, fw = scripted(pairs)
    with inst.open(), pytest.raises(CalibrationNeeded) as info:
        inst.measure()
    finish(fw)
    assert info.value.step == "white"


def test_late_reply_dropped_by_request_id():
    # MEASURE #2 gets no reply in time; the retry #3 is answered after the stale reply to #2
    pairs = [
        *CONNECT,
        (raw_frame(0x20, 2), None),
        (raw_frame(0x20, 3), reply(0x20, 2) + reply(0x20, 3)),
        (raw_frame(0x21, 4), reply(0x21, 4, b"\x00")),
        (raw_frame(0x22, 5), reply(0x22, 5, data_payload())),
    ]
    inst, fw = scripted(pairs)
    with inst.open():
        inst.measure()
    finish(fw)


def test_garbage_before_frame_is_skipped():
    pairs = [(raw_frame(0x0001, 1), b"\x00\xc1\x13" + reply(0x0001, 1, ID_PAYLOAD))]
    inst, fw = scripted(pairs)
    with inst.open():
        assert inst.info is not None
        assert inst.info.serial == "300456"
    finish(fw)


class Ma3Bench:
    def __init__(self, **character) -> None:
        self.faults = FaultPlan()
        self.physics = SpectroPhysics(character=InstrumentCharacter(serial="300456", **character))
        self.fw = Ma3Firmware(self.physics, self.faults, measure_time_s=0.01, slow_s=0.3)
        self.dev = SimUsbDevice(self.fw)
        self.backend = SimUsbBackend([self.dev])
        self.inst = MA3Spectro(UsbTransport(0x1209, 0xCA03, "300456", backend=self.backend), **FAST)


@pytest.fixture
def ma3():
    b = Ma3Bench()
    b.inst.open()
    yield b
    b.inst.close()


def true_reading(r, bench) -> None:
    assert r.reflectance.shape == (3, 31)
    de = delta_e(
        reflectance_to_lab(r.reflectance), bench.physics.design.lab_at(np.asarray(ANGLES)), method="cie2000"
    )
    assert float(de.max()) < 0.15


@pytest.mark.parametrize(
    "spec",
    [
        "no-reply@MS",
        "no-reply@RD",
        "slow-reply@MS",
        "slow-reply@RD",
        "corrupt-checksum",
        "partial-frame",
        "garbage@PO",
        "hang-after:3",
    ],
)
def test_transient_faults_recover(ma3, spec):
    ma3.faults.add(spec)
    ma3.fw.frames = 0
    t0 = time.monotonic()
    true_reading(ma3.inst.measure(), ma3)
    assert time.monotonic() - t0 < 3.0


@pytest.mark.parametrize(
    ("spec", "error"),
    [
        ("lamp-failure", HardwareFailure),
        ("tilt", TiltDetected),
        ("battery-low", BatteryLow),
        ("out-of-range", Misread),
        ("stuck-busy", DeviceTimeout),
        ("corrupt-checksum:9", ProtocolError),
        ("device-busy", DeviceInUse),
        ("cal-expired", CalibrationNeeded),
    ],
)
def test_persistent_faults_typed(ma3, spec, error):
    ma3.faults.add(spec)
    t0 = time.monotonic()
    with pytest.raises(error):
        ma3.inst.measure()
    assert time.monotonic() - t0 < 3.0
    ma3.faults.clear()
    if spec == "cal-expired":
        assert ma3.inst.calibrate().passed
    true_reading(ma3.inst.measure(), ma3)


def test_unplug_is_disconnected(ma3):
    ma3.faults.add("unplug@PO")
    with pytest.raises(Disconnected):
        ma3.inst.measure()
    assert list(ma3.backend.enumerate_devices()) == []


def test_interface_claimed_elsewhere_is_device_in_use():
    b = Ma3Bench()
    other = SimUsbBackend([b.dev]).open_device(b.dev)
    SimUsbBackend([b.dev]).claim_interface(other, 0)  # another process's handle holds the interface
    with pytest.raises(DeviceInUse):
        b.inst.open()


def test_no_such_device_and_open_instrument_by_usb_address():
    b = Ma3Bench()
    with pytest.raises(Disconnected):
        MA3Spectro(UsbTransport(0x1209, 0xBEEF, backend=b.backend)).open()
    with pytest.raises(Disconnected):  # serial number filter goes through string descriptors
        MA3Spectro(UsbTransport(0x1209, 0xCA03, "999999", backend=b.backend)).open()
    with open_instrument("ma3@usb:1209:ca03:300456", backend=b.backend, timeout_s=0.2) as inst:
        true_reading(inst.measure(), b)


def test_round_trip_within_repeatability():
    b = Ma3Bench()
    with b.inst.open():
        labs = np.array([reflectance_to_lab(b.inst.measure().reflectance) for _ in range(10)])
    de = delta_e(labs, DEFAULT_DESIGN.lab_at(np.asarray(ANGLES))[None], method="cie2000")
    assert float(de.mean()) <= 0.05
