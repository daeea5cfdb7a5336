"""Family 3: 20/60/85° gloss meter with haze, log haze, DOI and Rspec, on HID reports
(docs/protocols/gloss-hid.md), through hidapi (``hid.device``) semantics.

Reports are 64 bytes after the report id. Output report 0x01 ``[cmd, seq, 0…]`` asks; input report
0x02 ``[seq, status lo, status hi, cmd, state, payload…, xor]`` answers (byte 63 = XOR of bytes 0–62,
a mismatch rejects the report). Feature report 0x03 (get) is the device information; feature report
0x04 (set) loads the certified values of the calibration standard. ``read`` returning no data is
hidapi's 0 (timeout); an ``OSError`` is its −1. Stale input reports (another sequence number) are
dropped.

For a simulator in another process, :class:`HidBridgeDevice` carries the same hidapi calls over a
serial line (``gloss@/dev/pts/N``); there is no uhid on this machine to create a kernel HID device.
"""

from __future__ import annotations

import datetime as dt
import math
import struct
import time
from collections.abc import Callable, Sequence
from typing import Any

from station.drivers.errors import (
    CommunicationError,
    DeviceTimeout,
    DriverInputError,
    Misread,
    ProtocolError,
    error_for_code,
)
from station.drivers.exchange_log import ExchangeLog
from station.drivers.instrument import Instrument
from station.drivers.readings import CalibrationStatus, CalibrationStepResult, GlossReading, InstrumentInfo
from station.drivers.transport import ReportTransport, SerialTransport

__all__ = ["GEOMETRIES", "GlossMeter", "HidBridgeDevice", "StuckBusy", "hid_path_for", "xor8"]

GEOMETRIES = (20, 60, 85)
REPORT = 64
OUT_ID, IN_ID, INFO_ID, STD_ID = 0x01, 0x02, 0x03, 0x04
CMD_MEASURE, CMD_CALIBRATE, CMD_CLEAR = 0x10, 0x20, 0x30
STATE_DONE, STATE_BUSY = 0, 1
_INFO = struct.Struct("<8s8s8sBI3fI")  # model, serial, fw, cal needed, cal counter, standard GU ×3, expires
_DATA = struct.Struct("<7ffHII")  # g20 g60 g85 haze loghaze doi rspec, temp, warn, cal counter, time
_CAL = struct.Struct("<I3fI")  # counter, standard reading ×3, expires
GU_MAX = {20: 2000.0, 60: 1000.0, 85: 160.0}  # ranges of combined meters (UNCONFIRMED typical claims)
WARN_OUT_OF_RANGE = 0x20  # CM-MISDK "gloss out of range"


class StuckBusy(DeviceTimeout):
    """The meter acknowledged the command as busy and never finished (not retried)."""


def xor8(data: bytes) -> int:
    """XOR of all bytes (the report check byte)."""
    x = 0
    for b in data:
        x ^= b
    return x


def hid_path_for(
    text: str, enumerate_fn: Callable[[int, int], Sequence[dict[str, Any]]] | None = None
) -> bytes:
    """Resolve ``VID:PID`` (hex) to the first enumerated hidapi path, or take *text* as a path."""
    parts = text.split(":")
    if len(parts) == 2 and all(len(p) == 4 for p in parts):
        try:
            vid, pid = int(parts[0], 16), int(parts[1], 16)
        except ValueError as exc:
            raise DriverInputError("address", "hid:VID:PID (hex) or hid:PATH", text) from exc
        if enumerate_fn is None:
            import hid

            enumerate_fn = hid.enumerate
        found = list(enumerate_fn(vid, pid))
        if not found:
            from station.drivers.errors import Disconnected

            raise Disconnected(f"hid:{text}: no such HID device")
        return bytes(found[0]["path"])
    return text.encode()


class GlossMeter(Instrument[ReportTransport]):
    """Gloss/haze/DOI meter over a :class:`ReportTransport`. Timeouts in seconds."""

    family = "gloss"
    kind = "gloss"
    calibration_steps = ("gloss",)

    def __init__(
        self,
        transport: ReportTransport,
        timeout_s: float = 1.0,
        retries: int = 2,
        measure_limit_s: float = 5.0,
    ) -> None:
        super().__init__(transport)
        self.timeout_s = timeout_s
        self.retries = retries
        self.measure_limit_s = measure_limit_s
        self._seq = 0
        self.info: InstrumentInfo | None = None
        self.log = ExchangeLog(self.family, transport.address)

    def _connect(self) -> None:
        self.info = self.identify()

    def _feature(self) -> tuple:
        raw = self.transport.get_feature(INFO_ID, REPORT + 1)
        if len(raw) != REPORT + 1 or raw[0] != INFO_ID:
            raise ProtocolError(f"feature report 0x03 of {len(raw)} bytes")
        if xor8(raw[1:REPORT]) != raw[REPORT]:
            raise ProtocolError("feature report check byte mismatch")
        return _INFO.unpack_from(raw, 1)

    def identify(self) -> InstrumentInfo:
        """Get model, serial, firmware (feature report 0x03)."""
        with self._lock:
            model, serial, fw, *_ = self._feature()
        text = [v.rstrip(b"\0").decode("ascii", "replace") for v in (model, serial, fw)]
        return InstrumentInfo(text[0], text[1], text[2], tuple(f"{g}deg" for g in GEOMETRIES))

    def status(self) -> CalibrationStatus:
        """Calibration state from feature report 0x03."""
        with self._lock:
            _, serial, _, needed, counter, *_std, expires = self._feature()
        sn = serial.rstrip(b"\0").decode()
        return CalibrationStatus(
            "gloss" if needed else None,
            f"CAL-{sn}-{counter:04d}",
            dt.datetime.fromtimestamp(expires, dt.UTC) if expires else None,
        )

    def set_standard(self, gloss_gu: Sequence[float]) -> None:
        """Load the certified 20/60/85° values of the calibration standard (feature report 0x04)."""
        vals = [float(v) for v in gloss_gu]
        if len(vals) != 3 or not all(
            math.isfinite(v) and 0 < v <= GU_MAX[g] for v, g in zip(vals, GEOMETRIES, strict=True)
        ):
            raise DriverInputError(
                "standard_gu", "three finite values 0 < GU <= range at 20/60/85°", gloss_gu
            )
        body = struct.pack("<3f", *vals).ljust(REPORT - 1, b"\0")
        with self._lock:
            self.transport.send_feature(bytes([STD_ID]) + body + bytes([xor8(body)]))

    def _request(self, cmd: int, limit_s: float) -> bytes:
        """Send *cmd*, wait for its final input report within *limit_s*; bounded retries, then one
        reconnect (a meter that hangs after a long run answers again once reopened)."""
        last: Exception | None = None
        for reconnect in (False, True):
            if reconnect:
                self.transport.reopen()
            for _ in range(self.retries + 1):
                try:
                    return self._attempt(cmd, limit_s)
                except StuckBusy:
                    self._clear()
                    raise
                except (DeviceTimeout, ProtocolError) as exc:
                    last = exc
                    while self.transport.read_report(REPORT + 1, 0.02):
                        pass
        if last is None:
            raise DeviceTimeout("no attempt made")
        raise type(last)(f"{last} (after {self.retries + 1} tries and a reconnect)")

    def _attempt(self, cmd: int, limit_s: float) -> bytes:
        self._seq = (self._seq + 1) & 0xFF
        seq = self._seq
        out = bytes([OUT_ID, cmd, seq]).ljust(REPORT + 1, b"\0")
        self.transport.write_report(out)
        deadline = time.monotonic() + limit_s
        busy = False  # after the busy acknowledgement the final report may take up to limit_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise (StuckBusy if busy else DeviceTimeout)(
                    f"{self.address}: no final report for command {cmd:#04x} in {limit_s:g} s"
                )
            raw = self.transport.read_report(REPORT + 1, min(left, self.timeout_s))
            if not raw:  # hidapi 0: timeout
                if busy:
                    continue
                raise DeviceTimeout(f"{self.address}: read timed out (hidapi returned 0)")
            self.log.record(out, raw, f"command {cmd:#04x} seq {seq} -> {len(raw)}-byte report, id {raw[0]}")
            if len(raw) != REPORT + 1 or raw[0] != IN_ID:
                raise ProtocolError(f"input report of {len(raw)} bytes, id {raw[0]}")
            if xor8(raw[1:REPORT]) != raw[REPORT]:
                raise ProtocolError("input report check byte mismatch")
            r_seq, status, r_cmd, state = raw[1], raw[2] | raw[3] << 8, raw[4], raw[5]
            if r_seq != seq or r_cmd != cmd:
                continue  # stale report of an earlier request
            if status not in (0, 1):
                if cmd != CMD_CLEAR:
                    self._clear()
                raise error_for_code(status)
            if state == STATE_BUSY:
                busy = True
                continue
            return raw[6:REPORT]

    def _clear(self) -> None:
        try:
            self._request(CMD_CLEAR, self.timeout_s)
        except (DeviceTimeout, ProtocolError):
            pass

    def calibrate_step(self, step: str) -> CalibrationStepResult:
        """The one step, ``gloss``: read the standard (black glass unless :meth:`set_standard` said
        otherwise) and scale to it (command 0x20; the protocol has no other calibration command)."""
        self.check_step(step)
        with self._lock:
            body = self._request(CMD_CALIBRATE, self.timeout_s * 4)
        counter, *_standard_raw, expires = _CAL.unpack_from(body)
        sn = self.info.serial if self.info else "?"
        return CalibrationStepResult(
            "gloss",
            f"CAL-{sn}-{counter:04d}",
            None,
            True,
            dt.datetime.fromtimestamp(expires, dt.UTC) if expires else None,
        )

    def measure(self) -> GlossReading:
        """Measure 20/60/85° gloss, haze, log haze, DOI and Rspec."""
        with self._lock:
            body = self._request(CMD_MEASURE, self.measure_limit_s)
        g20, g60, g85, haze, log_haze, doi, rspec, temp, warn, counter, stamp = _DATA.unpack_from(body)
        gloss = {20: g20, 60: g60, 85: g85}
        values = [*gloss.values(), haze, log_haze, doi, rspec, temp]
        if warn & WARN_OUT_OF_RANGE or not all(math.isfinite(v) for v in values):
            raise Misread("gloss out of range")
        if any(not (0.0 <= gloss[g] <= GU_MAX[g]) for g in GEOMETRIES) or not (0 <= doi <= 100):
            raise Misread(f"gloss outside the meter's range: {gloss}")
        sn = self.info.serial if self.info else "?"
        return GlossReading(
            gloss_gu={g: round(v, 3) for g, v in gloss.items()},
            haze_hu=round(haze, 3),
            log_haze=round(log_haze, 2),
            doi=round(doi, 3),
            rspec=round(rspec, 3),
            serial=sn,
            calibration_id=f"CAL-{sn}-{counter:04d}",
            time=dt.datetime.fromtimestamp(stamp, dt.UTC),
            temperature_c=round(temp, 2),
            warnings=warn,
            model=self.info.model if self.info else "",
        )


class HidBridgeDevice:
    """``hid.device`` look-alike that forwards each call over a serial line to a HID simulator process.

    Wire: ``op (1 byte), length (2 bytes LE), payload``; replies use the lower-case op. ``R`` carries
    ``max_length (2) + timeout_ms (4)`` and is answered with the report or nothing (hidapi's 0);
    ``E`` answers any call that failed (hidapi's −1, raised here as ``OSError``).
    """

    def __init__(self, baudrate: int = 115200) -> None:
        self._t: SerialTransport | None = None
        self._baud = baudrate

    def open_path(self, path: bytes) -> None:
        """Open the serial line and the HID handle behind it; on any failure the line is closed again
        (its claim and ``flock`` released), so a later open of the same path starts afresh."""
        t = SerialTransport(path.decode(), self._baud)
        t.open()
        self._t = t
        try:
            self._call(b"O", path, 2.0)
        except BaseException:
            self._t = None
            t.close()
            raise

    def _call(self, op: bytes, payload: bytes, timeout_s: float) -> bytes:
        if self._t is None:
            raise CommunicationError("HID bridge not open")
        self._t.write(op + struct.pack("<H", len(payload)) + payload)
        head = self._t.read_exact(3, timeout_s + 1.0)
        (n,) = struct.unpack("<H", head[1:])
        body = self._t.read_exact(n, 1.0) if n else b""
        if head[:1] == b"E":
            raise OSError(body.decode(errors="replace") or "hidapi error")
        if head[:1] != op.lower():
            raise CommunicationError(f"HID bridge: reply {head[:1]!r} to {op!r}")
        return body

    def write(self, buff: bytes | list[int]) -> int:
        return struct.unpack("<h", self._call(b"W", bytes(buff), 1.0))[0]

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        return list(self._call(b"R", struct.pack("<HI", max_length, timeout_ms), timeout_ms / 1000.0))

    def get_feature_report(self, report_num: int, max_length: int) -> list[int]:
        return list(self._call(b"G", struct.pack("<BH", report_num, max_length), 5.0))

    def send_feature_report(self, buff: bytes | list[int]) -> int:
        return struct.unpack("<h", self._call(b"S", bytes(buff), 5.0))[0]

    def close(self) -> None:
        if self._t is not None:
            try:
                self._call(b"C", b"", 0.5)
            except (CommunicationError, DeviceTimeout, OSError):
                pass
            self._t.close()
            self._t = None
