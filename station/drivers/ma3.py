"""Family 2: 3-angle spectrophotometer (45° illumination, 15/45/110 aspecular) on raw USB bulk
endpoints with a binary framed protocol modelled on Ocean Optics OBP (docs/protocols/ma3-binary.md).

Frame, little-endian: a 24-byte header (start ``C1 C0``, version, flags, error code, message type,
request id, payload length, reserved), the payload, and a 20-byte footer (MD5 of header + payload,
then ``C5 C4 C3 C2``). Unlike seabreeze, which only warns on an MD5 mismatch, this driver rejects the
frame and asks again (a reading is held by the instrument until the next MEASURE). A NACK carries a
device error code (:data:`station.drivers.errors.ERROR_CODES`; 3 = the device saw a bad checksum,
resent). Replies carry the request id, so a late reply to an earlier request is recognised and
dropped instead of being taken for the current one.

The same frames run over any :class:`StreamTransport`: USB bulk (``ma3@usb:1209:ca03``) or a serial
line (``ma3@/dev/pts/N``, how the simulator subprocess serves them).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import math
import struct
import time
from dataclasses import dataclass
from enum import IntEnum, IntFlag

import numpy as np

from station.drivers.errors import (
    DeviceTimeout,
    Disconnected,
    Misread,
    ProtocolError,
    UnexpectedReply,
    error_for_code,
)
from station.drivers.exchange_log import ExchangeLog
from station.drivers.instrument import Instrument
from station.drivers.readings import (
    WAVELENGTHS_NM,
    CalibrationStatus,
    CalibrationStepResult,
    InstrumentInfo,
    SpectralReading,
    geometry_name,
)
from station.drivers.transport import StreamTransport

__all__ = ["HEADER", "Flags", "Frame", "MA3Spectro", "Msg", "encode_frame"]

START = b"\xc1\xc0"
END = b"\xc5\xc4\xc3\xc2"
VERSION = 0x1000
HEADER = struct.Struct(
    "<2s"  # start bytes C1 C0
    "H"  # protocol version 0x1000
    "H"  # flags (Flags)
    "H"  # error code (NACK)
    "I"  # message type (Msg)
    "I"  # request id, echoed in the reply
    "I"  # payload length
    "I"  # reserved, 0
)
FOOTER_LEN = 20  # 16-byte MD5 + END
MAX_PAYLOAD = 4096
ERR_BAD_CHECKSUM = 3
WARN_OUT_OF_RANGE = 0x10
R_MAX = 2.0


class Msg(IntEnum):
    """Message types."""

    GET_ID = 0x0001
    GET_STATUS = 0x0002
    CAL_ZERO = 0x0010
    CAL_WHITE = 0x0011
    CAL_VERIFY = 0x0012
    MEASURE = 0x0020
    POLL = 0x0021
    READ_DATA = 0x0022
    CLEAR = 0x0030


class Flags(IntFlag):
    """Header flag bits."""

    REPLY = 0x01
    ACK_REQUESTED = 0x02
    ACK = 0x04
    NACK = 0x08
    HW_EXCEPTION = 0x10


@dataclass(frozen=True)
class Frame:
    """A decoded frame."""

    flags: int
    error: int
    msg: int
    request_id: int
    payload: bytes


def _msg_name(msg: int) -> str:
    """The message's name (``IDENTIFY``), or its number in hex when it is not one we know."""
    try:
        return Msg(msg).name
    except ValueError:
        return f"{msg:#06x}"


def encode_frame(
    msg: int, request_id: int, payload: bytes = b"", flags: int = Flags.ACK_REQUESTED, error: int = 0
) -> bytes:
    """Build one frame: header, payload, MD5 footer."""
    head = HEADER.pack(START, VERSION, flags, error, msg, request_id, len(payload), 0)
    return head + payload + hashlib.md5(head + payload, usedforsecurity=False).digest() + END


_ID = struct.Struct("<8s8s8sB")
_STATUS = struct.Struct("<BIIf")
_VERIFY = struct.Struct("<fBI")
_DATA_HEAD = struct.Struct("<8sIIfHHB")
_DATA_GEOM = struct.Struct("<bb31f")
_NEEDED = {0: None, 1: "zero", 2: "white", 3: "verify"}


def _text(raw: bytes) -> str:
    return raw.rstrip(b"\0").decode("ascii", "replace")


def _epoch(value: int) -> dt.datetime | None:
    return None if value == 0 else dt.datetime.fromtimestamp(value, dt.UTC)


class MA3Spectro(Instrument[StreamTransport]):
    """3-angle spectrophotometer on the binary framed protocol. Timeouts in seconds."""

    family = "ma3"

    def __init__(
        self,
        transport: StreamTransport,
        timeout_s: float = 1.0,
        retries: int = 2,
        measure_limit_s: float = 10.0,
        poll_period_s: float = 0.005,
        quiet_s: float = 0.03,
    ) -> None:
        super().__init__(transport)
        self.timeout_s = timeout_s
        self.retries = retries
        self.measure_limit_s = measure_limit_s
        self.poll_period_s = poll_period_s
        self.quiet_s = quiet_s
        self._rid = 0
        self.info: InstrumentInfo | None = None
        self.log = ExchangeLog(self.family, transport.address)

    def _connect(self) -> None:
        self.transport.flush_input()
        self.info = self.identify()

    # -- framing -----------------------------------------------------------------------------------
    def _read_frame(self, deadline: float) -> tuple[Frame, bytes]:
        t = self.transport
        window = b""
        while window != START:  # resynchronise on the start bytes
            b = t.read(1, max(0.0, deadline - time.monotonic()))
            if not b:
                if time.monotonic() >= deadline:
                    raise DeviceTimeout(f"{t.address}: no reply frame")
                continue
            window = (window + b)[-2:]
        rest = t.read_exact(HEADER.size - 2, max(0.0, deadline - time.monotonic()))
        head = START + rest
        _, version, flags, error, msg, rid, length, _ = HEADER.unpack(head)
        if version != VERSION or length > MAX_PAYLOAD:
            raise ProtocolError(f"bad header (version {version:#06x}, length {length})")
        body = t.read_exact(length + FOOTER_LEN, max(0.0, deadline - time.monotonic()))
        payload, digest, end = body[:length], body[length : length + 16], body[length + 16 :]
        if end != END:
            raise ProtocolError("bad footer")
        if hashlib.md5(head + payload, usedforsecurity=False).digest() != digest:
            raise ProtocolError("checksum mismatch: frame rejected")
        return Frame(flags, error, msg, rid, payload), head + body

    def _drain(self) -> None:
        while self.transport.read(4096, self.quiet_s):
            pass

    def _exchange(self, msg: Msg, payload: bytes, timeout_s: float) -> bytes:
        self._rid = (self._rid + 1) & 0xFFFFFFFF
        rid = self._rid
        data = encode_frame(msg, rid, payload)
        self.transport.write(data, timeout_s)
        deadline = time.monotonic() + timeout_s
        while True:
            frame, raw = self._read_frame(deadline)
            self.log.record(
                data,
                raw,
                f"{_msg_name(msg)} #{rid} ({len(payload)} B) -> {_msg_name(frame.msg)} #{frame.request_id}"
                f" flags {frame.flags:#06x} error {frame.error} ({len(frame.payload)} B)",
            )
            if frame.request_id != rid:
                continue  # a late reply to an earlier request: drop it
            if not frame.flags & Flags.REPLY or frame.msg != msg:
                raise UnexpectedReply(f"reply type {frame.msg:#06x} to request {int(msg):#06x}")
            if frame.flags & (Flags.NACK | Flags.HW_EXCEPTION):
                if frame.error == ERR_BAD_CHECKSUM:
                    raise ProtocolError("device reports a bad checksum on our frame")
                if msg != Msg.CLEAR:
                    self._clear()
                raise error_for_code(frame.error)
            return frame.payload

    def _clear(self) -> None:
        try:
            self._exchange(Msg.CLEAR, b"", self.timeout_s)
        except (DeviceTimeout, ProtocolError, UnexpectedReply):
            self._drain()

    def transact(self, msg: Msg, payload: bytes = b"", timeout_s: float | None = None) -> bytes:
        """Request/reply with bounded retries, a drain between tries and one reconnect at the end."""
        timeout = self.timeout_s if timeout_s is None else timeout_s
        last: Exception | None = None
        for reconnect in (False, True):
            if reconnect:
                self.transport.reopen()
            for _ in range(self.retries + 1):
                try:
                    return self._exchange(msg, payload, timeout)
                except (DeviceTimeout, ProtocolError) as exc:
                    last = exc
                    self._drain()
                except Disconnected:
                    raise
        if last is None:
            raise DeviceTimeout(f"{msg.name}: no attempt made")
        raise type(last)(f"{msg.name}: {last} (after {self.retries + 1} tries and a reconnect)")

    # -- instrument --------------------------------------------------------------------------------
    def identify(self) -> InstrumentInfo:
        """Get model, serial, firmware and geometries (GET_ID)."""
        with self._lock:
            p = self.transact(Msg.GET_ID)
        try:
            model, serial, fw, n = _ID.unpack_from(p)
            angles = struct.unpack_from(f"<{2 * n}b", p, _ID.size)
        except struct.error as exc:
            raise UnexpectedReply(f"GET_ID payload of {len(p)} bytes") from exc
        geoms = tuple(geometry_name(angles[2 * i], angles[2 * i + 1]) for i in range(n))
        return InstrumentInfo(_text(model), _text(serial), _text(fw), geoms)

    def _cal_id(self, counter: int) -> str:
        return f"CAL-{self.info.serial if self.info else '?'}-{counter:04d}"

    def status(self) -> CalibrationStatus:
        """Get the calibration state (GET_STATUS)."""
        with self._lock:
            p = self.transact(Msg.GET_STATUS)
        try:
            needed, counter, expires, temp = _STATUS.unpack(p)
        except struct.error as exc:
            raise UnexpectedReply(f"GET_STATUS payload of {len(p)} bytes") from exc
        return CalibrationStatus(_NEEDED.get(needed, "white"), self._cal_id(counter), _epoch(expires), temp)

    def calibrate_step(self, step: str) -> CalibrationStepResult:
        """One step: ``zero`` (CAL_ZERO, black trap), ``white`` (CAL_WHITE, white tile; the new
        calibration counter) or ``verify`` (CAL_VERIFY, verification tile: ΔE00, pass, expiry)."""
        self.check_step(step)
        with self._lock:
            slow = self.timeout_s * 4
            msg = {"zero": Msg.CAL_ZERO, "white": Msg.CAL_WHITE, "verify": Msg.CAL_VERIFY}[step]
            p = self.transact(msg, timeout_s=slow)
        try:
            if step == "zero":
                return CalibrationStepResult("zero")
            if step == "white":
                (counter,) = struct.unpack("<I", p)
                return CalibrationStepResult("white", calibration_id=self._cal_id(counter))
            de, passed, expires = _VERIFY.unpack(p)
        except struct.error as exc:
            raise UnexpectedReply(f"{msg.name} payload of {len(p)} bytes") from exc
        return CalibrationStepResult("verify", "", round(de, 4), bool(passed), _epoch(expires))

    def measure(self) -> SpectralReading:
        """MEASURE, POLL until idle, READ_DATA (a frame with a bad checksum is read again)."""
        with self._lock:
            self.transact(Msg.MEASURE)
            deadline = time.monotonic() + self.measure_limit_s
            while self.transact(Msg.POLL) != b"\x00":
                if time.monotonic() >= deadline:
                    self._clear()
                    raise DeviceTimeout(f"still measuring after {self.measure_limit_s:g} s")
                time.sleep(self.poll_period_s)
            return self._parse_data(self.transact(Msg.READ_DATA, timeout_s=self.timeout_s * 2))

    def _parse_data(self, p: bytes) -> SpectralReading:
        try:
            serial, counter, stamp, temp, warn, diag, n = _DATA_HEAD.unpack_from(p)
            if len(p) != _DATA_HEAD.size + n * _DATA_GEOM.size:
                raise struct.error("length")
            blocks = [_DATA_GEOM.unpack_from(p, _DATA_HEAD.size + i * _DATA_GEOM.size) for i in range(n)]
        except struct.error as exc:
            raise ProtocolError(f"READ_DATA payload of {len(p)} bytes") from exc
        geoms = tuple(geometry_name(b[0], b[1]) for b in blocks)
        if self.info is not None and geoms != self.info.geometries:
            raise UnexpectedReply(f"geometries {geoms} differ from {self.info.geometries}")
        refl = np.asarray([b[2:] for b in blocks], dtype=float)
        if warn & WARN_OUT_OF_RANGE:
            raise Misread("instrument flags the reflectance as out of range")
        if (
            refl.shape[1] != len(WAVELENGTHS_NM)
            or not np.all(np.isfinite(refl))
            or refl.min() < 0
            or refl.max() > R_MAX
            or not math.isfinite(temp)
        ):
            raise Misread(f"reflectance outside [0, {R_MAX}] or non-finite")
        return SpectralReading(
            geometries=geoms,
            reflectance=refl,
            temperature_c=round(temp, 2),
            serial=_text(serial),
            calibration_id=f"CAL-{_text(serial)}-{counter:04d}",
            time=dt.datetime.fromtimestamp(stamp, dt.UTC),
            warnings=warn,
            diagnosis=diag,
            model=self.info.model if self.info else "",
        )
