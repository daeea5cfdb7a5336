"""Gloss meter on HID reports. hidapi cannot reach a kernel HID device here (no uhid / hidraw), so the
simulator sits at the hidapi call boundary; the real ``hid.enumerate`` / ``hid.device`` path is
exercised by the not-found tests."""

from __future__ import annotations

import struct
import time

import pytest

from simulators.faults import FaultPlan
from simulators.gloss import PATH, GlossDevice, GlossPhysics, reference_coat
from station.drivers import (
    BatteryLow,
    CalibrationNeeded,
    DeviceInUse,
    DeviceTimeout,
    Disconnected,
    DriverInputError,
    GlossReading,
    HardwareFailure,
    Misread,
    ProtocolError,
    TiltDetected,
    open_instrument,
)
from station.drivers.discovery import list_devices
from station.drivers.gloss import GlossMeter, hid_path_for
from station.drivers.transport import HidTransport
from tests.drivers.conftest import Timing
from tests.waiting import pause

FAST: Timing = {"timeout_s": 0.2, "retries": 1, "measure_limit_s": 0.6}


def x8(b: bytes) -> int:
    out = 0
    for v in b:
        out ^= v
    return out


class ScriptedHid:
    """hid.device look-alike replaying exact reports (written report -> input reports)."""

    def __init__(self, feature: bytes, pairs: list[tuple[bytes, list[bytes]]]) -> None:
        self.feature, self.pairs = feature, list(pairs)
        self.inbox: list[bytes] = []
        self.unexpected: list[bytes] = []
        self.features_sent: list[bytes] = []

    def __call__(self):
        return self

    def open_path(self, path):
        pass

    def close(self):
        pass

    def get_feature_report(self, num, size):
        return list(self.feature)

    def send_feature_report(self, buff):
        self.features_sent.append(bytes(buff))
        return len(buff)

    def write(self, buff):
        data = bytes(buff)
        if not self.pairs or self.pairs[0][0] != data:
            self.unexpected.append(data)
            return len(data)
        self.inbox += self.pairs.pop(0)[1]
        return len(data)

    def read(self, size, timeout_ms=0):
        if not self.inbox:
            pause(timeout_ms / 1000, "hidapi's read blocking for its timeout with nothing to read")
            return []
        return list(self.inbox.pop(0))


def feature_03(needed: int = 0) -> bytes:
    body = struct.pack(
        "<8s8s8sBI3fI", b"GLS3", b"GM0815", b"3.1.0", needed, 5, 100.0, 100.0, 100.0, 1795442400
    )
    body = body.ljust(63, b"\0")
    return b"\x03" + body + bytes([x8(body)])


def out_report(cmd: int, seq: int) -> bytes:
    return bytes([0x01, cmd, seq]) + bytes(62)


def in_report(seq: int, cmd: int, status: int, state: int, body: bytes = b"") -> bytes:
    payload = (bytes([seq, status & 0xFF, status >> 8, cmd, state]) + body).ljust(63, b"\0")
    return b"\x02" + payload + bytes([x8(payload)])


DATA = struct.pack("<7ffHII", 34.5, 88.0, 78.5, 9.25, 213.5, 2.25, 0.25, 24.0, 0, 5, 1795413600)


def scripted(pairs, feature=None) -> tuple[GlossMeter, ScriptedHid]:
    hid = ScriptedHid(feature or feature_03(), pairs)
    return GlossMeter(HidTransport(PATH, hid, lambda v, p: [{"path": PATH}]), **FAST), hid


def test_identify_and_status_from_feature_report():
    inst, _ = scripted([], feature_03(needed=1))
    with inst.open():
        assert inst.info is not None
        assert (inst.info.model, inst.info.serial, inst.info.firmware) == ("GLS3", "GM0815", "3.1.0")
        s = inst.status()
    assert s.expires is not None
    assert (s.needed, s.calibration_id, s.expires.timestamp()) == ("gloss", "CAL-GM0815-0005", 1795442400)


def test_measure_bytes():
    inst, hid = scripted([(out_report(0x10, 1), [in_report(1, 0x10, 0, 1), in_report(1, 0x10, 0, 0, DATA)])])
    with inst.open():
        r = inst.measure()
    assert hid.unexpected == [] and hid.pairs == []
    assert r.gloss_gu == {20: 34.5, 60: 88.0, 85: 78.5}
    assert (r.haze_hu, r.log_haze, r.doi, r.rspec, r.calibration_id) == (
        9.25,
        213.5,
        2.25,
        0.25,
        "CAL-GM0815-0005",
    )


def test_stale_and_corrupt_reports():
    bad = bytearray(in_report(2, 0x10, 0, 0, DATA))
    bad[-1] ^= 0xFF
    pairs = [
        (out_report(0x10, 1), [in_report(7, 0x10, 0, 0, DATA), bytes(bad)]),  # stale seq, then bad xor
        (out_report(0x10, 2), [in_report(2, 0x10, 0, 0, DATA)]),
    ]
    inst, hid = scripted(pairs)
    with inst.open():
        assert inst.measure().gloss_gu[60] == 88.0
    assert hid.unexpected == [] and hid.pairs == []


def test_error_status_clears_then_raises():
    pairs = [
        (out_report(0x10, 1), [in_report(1, 0x10, 140, 0)]),
        (out_report(0x30, 2), [in_report(2, 0x30, 0, 0)]),
    ]
    inst, hid = scripted(pairs)
    with inst.open(), pytest.raises(TiltDetected):
        inst.measure()
    assert hid.unexpected == [] and hid.pairs == []


def test_set_standard_feature_bytes():
    inst, hid = scripted([])
    with inst.open():
        inst.set_standard([94.8, 99.7, 99.9])
        with pytest.raises(DriverInputError):
            inst.set_standard([94.8, float("nan"), 99.9])
    body = struct.pack("<3f", 94.8, 99.7, 99.9).ljust(63, b"\0")
    assert hid.features_sent == [b"\x04" + body + bytes([x8(body)])]


class GlossBench:
    def __init__(self) -> None:
        self.faults = FaultPlan()
        self.dev = GlossDevice(GlossPhysics(), self.faults, measure_time_s=0.01, slow_s=0.3)
        self.inst = GlossMeter(HidTransport(PATH, self.dev, self.dev.enumerate), **FAST)


@pytest.fixture
def gm():
    b = GlossBench()
    b.inst.open()
    yield b
    b.inst.close()


@pytest.mark.parametrize(("value", "geometry"), [(95.0, 60), (69.0, 20), (40.0, 60), (27.0, 85)])
def test_black_glass_references_read_back(gm, value, geometry):
    """EURAMET black-glass artefacts 95/69/40/27 GU read back within ±0.5 GU (mean of 5) after calibration."""
    gm.inst.calibrate()
    gm.dev.physics.coat = reference_coat(value, geometry)
    readings = [gm.inst.measure().gloss_gu[geometry] for _ in range(5)]
    assert abs(sum(readings) / 5 - value) <= 0.5
    assert max(readings) - min(readings) < 1.0


def test_reading_physics(gm):
    r = gm.inst.measure()
    assert isinstance(r, GlossReading)
    assert abs(r.gloss_gu[60] - 88.0) < 0.6
    # the clear coat (peak + haze, index 1.50): below its 60° gloss at 20° (Fresnel and haze), DOI near 90
    assert 70.0 < r.gloss_gu[20] < r.gloss_gu[60]
    assert 0 < r.haze_hu < 50 and 85.0 <= r.doi <= 95.0 and r.rspec >= 0


@pytest.mark.parametrize(
    "spec", ["no-reply@MS", "slow-reply@MS", "corrupt-checksum@MS", "partial-frame@MS", "hang-after:1"]
)
def test_transient_faults_recover(gm, spec):
    gm.faults.add(spec)
    gm.dev.commands = 0
    t0 = time.monotonic()
    assert abs(gm.inst.measure().gloss_gu[60] - 88.0) < 0.6
    assert time.monotonic() - t0 < 3.0


@pytest.mark.parametrize(
    ("spec", "error"),
    [
        ("lamp-failure", HardwareFailure),
        ("tilt", TiltDetected),
        ("battery-low", BatteryLow),
        ("out-of-range", Misread),
        ("stuck-busy", DeviceTimeout),
        ("corrupt-checksum@MS:9", ProtocolError),
        ("device-busy", DeviceInUse),
        ("cal-expired", CalibrationNeeded),
    ],
)
def test_persistent_faults_typed(gm, spec, error):
    gm.faults.add(spec)
    t0 = time.monotonic()
    with pytest.raises(error):
        gm.inst.measure()
    assert time.monotonic() - t0 < 4.0
    gm.faults.clear()
    if spec == "cal-expired":
        gm.inst.calibrate()
    assert abs(gm.inst.measure().gloss_gu[60] - 88.0) < 0.6


def test_unplug_is_disconnected(gm):
    gm.faults.add("unplug@MS")
    with pytest.raises(Disconnected):
        gm.inst.measure()


def test_port_held_is_device_in_use():
    b = GlossBench()
    b.dev.held = True
    with pytest.raises(DeviceInUse):
        b.inst.open()


def test_real_hidapi_enumerate_and_open_path():
    """The real hidapi: enumerate runs (no HID devices here) and opening a missing path is Disconnected."""
    import hid

    assert isinstance(hid.enumerate(), list)
    with pytest.raises(Disconnected):
        GlossMeter(HidTransport(b"/dev/hidraw-missing")).open()
    with pytest.raises(Disconnected):
        hid_path_for("1209:ca60")  # real enumerate: nothing with our ids
    found, notes = list_devices()
    assert not any(n.startswith("hid") for n in notes)
    assert {d.address for d in found} >= {"sim:ma6", "sim:ma3", "sim:gloss"}


def test_discovery_and_open_by_vid_pid_with_simulated_enumerate():
    b = GlossBench()
    found, _ = list_devices(hid_enumerate=b.dev.enumerate)
    assert "gloss@hid:/sim/hidraw0" in {d.address for d in found}
    with open_instrument(
        "gloss@hid:1209:ca60", device_factory=b.dev, enumerate_fn=b.dev.enumerate, timeout_s=0.2
    ) as inst:
        assert abs(inst.measure().gloss_gu[60] - 88.0) < 0.6


def test_calibrate_and_clear_bytes():
    cal = struct.pack("<I3fI", 6, 99.8, 100.1, 99.9, 1795442400)
    pairs = [(out_report(0x20, 1), [in_report(1, 0x20, 0, 0, cal)])]
    inst, hid = scripted(pairs)
    with inst.open():
        r = inst.calibrate()
    assert hid.unexpected == [] and hid.pairs == []
    assert r.expires is not None
    assert (r.calibration_id, r.steps, r.passed, r.expires.timestamp()) == (
        "CAL-GM0815-0006",
        ("gloss",),
        True,
        1795442400,
    )


def test_failed_open_releases_the_port_claim():
    """An open refused by the device (EBUSY) leaves no claim behind: the next open of the same
    transport, and an open by a second meter on the same address, both succeed."""
    b = GlossBench()
    b.dev.held = True
    with pytest.raises(DeviceInUse):
        b.inst.open()
    assert not b.inst.transport.is_open
    b.dev.held = False
    with b.inst.open():
        assert abs(b.inst.measure().gloss_gu[60] - 88.0) < 0.6
    other = GlossMeter(HidTransport(PATH, b.dev, b.dev.enumerate), **FAST)
    with other.open():
        assert abs(other.measure().gloss_gu[60] - 88.0) < 0.6


def test_failed_reconnect_releases_the_port_claim():
    """A meter that stops answering is reopened once; when that reopen fails (the port was taken
    meanwhile) the claim is released, so opening again after the port is free succeeds."""
    b = GlossBench()
    b.inst.open()
    b.faults.add("hang-after:0")
    real_open = b.dev.open_path

    def taken(path: bytes) -> None:
        b.dev.held = True
        real_open(path)

    b.dev.open_path = taken  # type: ignore[method-assign]  # the reconnect finds the port held by another process
    with pytest.raises(DeviceInUse):
        b.inst.measure()
    assert not b.inst.transport.is_open
    b.dev.open_path = real_open  # type: ignore[method-assign]
    b.dev.held = False
    b.faults.clear()
    with b.inst.open():
        assert abs(b.inst.measure().gloss_gu[60] - 88.0) < 0.6
