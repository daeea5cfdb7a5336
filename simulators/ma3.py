"""Simulated 3-angle spectrophotometer (family 2): binary OBP-style frames (docs/protocols/ma3-binary.md).

:class:`Ma3Firmware` turns request frames into reply frames with the physics of
:mod:`simulators.physics`. It is reached two ways:

* in-process through :class:`simulators.usb_backend.SimUsbBackend`, a pyusb backend, so
  ``usb.core.find(backend=...)`` and the driver's real USB code run (tests);
* from another process as ``python -m simulators.ma3``, which serves the same frames on a pty
  (``ma3@/dev/pts/N``), because a pyusb backend object cannot cross a process boundary.

Replies are queued with a ready time, so a slow reply really arrives late (the driver must drop it by
request id) rather than blocking the caller.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import struct
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from simulators.faults import FaultPlan

if TYPE_CHECKING:
    from simulators.config import SimulatorConfig
    from simulators.physics import SpectroPhysics
    from simulators.pty_host import PtyHost
    from simulators.recipe import RecipePanel

__all__ = ["ASPECULAR", "Ma3Device", "Ma3Firmware", "build_device"]

ASPECULAR = (15, 45, 110)
START, END, VERSION = b"\xc1\xc0", b"\xc5\xc4\xc3\xc2", 0x1000
HEAD = struct.Struct("<2sHHHIIII")
REPLY, ACK, NACK = 0x01, 0x04, 0x08
LABELS = {
    0x0001: "ID",
    0x0002: "ST",
    0x0010: "ZC",
    0x0011: "WC",
    0x0012: "VC",
    0x0020: "MS",
    0x0021: "PO",
    0x0022: "RD",
    0x0030: "CE",
}


def frame(msg: int, rid: int, payload: bytes = b"", flags: int = REPLY | ACK, error: int = 0) -> bytes:
    """Encode a reply frame (the simulator's own encoder, independent of the driver's)."""
    head = HEAD.pack(START, VERSION, flags, error, msg, rid, len(payload), 0)
    return head + payload + hashlib.md5(head + payload, usedforsecurity=False).digest() + END


class Ma3Firmware:
    """Request frames in (:meth:`receive`), reply frames out (:meth:`pop_ready`)."""

    model, firmware = "MA3", "2.0.7"

    def __init__(
        self,
        physics: SpectroPhysics | None = None,
        faults: FaultPlan | None = None,
        measure_time_s: float = 0.3,
        slow_s: float = 0.4,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if physics is None:
            from simulators.physics import InstrumentCharacter, SpectroPhysics

            physics = SpectroPhysics(character=InstrumentCharacter(serial="300456"))
        self.physics = physics
        self.faults = faults or FaultPlan()
        self.measure_time_s = measure_time_s
        self.slow_s = slow_s
        self.clock = clock
        self.buf = bytearray()
        self._out: list[tuple[float, bytes]] = []
        self._lock = threading.Condition()
        self.state, self.done_at, self.data = 0, 0.0, b""
        self.has_data = False
        self.frames = 0
        self.hung = False
        self.unplugged = False
        self.received: list[bytes] = []
        self.on_unplug: Callable[[], None] | None = None

    # -- transport side ----------------------------------------------------------------------------
    def receive(self, data: bytes) -> None:
        """Bytes from the host; complete frames are handled (garbage before a start is skipped)."""
        self.buf += data
        while True:
            i = self.buf.find(START)
            if i < 0:
                del self.buf[:-1]
                return
            del self.buf[:i]
            if len(self.buf) < HEAD.size:
                return
            _, _, _, _, msg, rid, length, _ = HEAD.unpack_from(self.buf)
            total = HEAD.size + length + 20
            if length > 4096:
                del self.buf[:2]
                continue
            if len(self.buf) < total:
                return
            raw = bytes(self.buf[:total])
            del self.buf[:total]
            self.received.append(raw)
            head, payload = raw[: HEAD.size], raw[HEAD.size : HEAD.size + length]
            digest = hashlib.md5(head + payload, usedforsecurity=False).digest()
            if raw[-20:-4] != digest or raw[-4:] != END:
                self._queue(frame(msg, rid, flags=REPLY | NACK, error=3))
                continue
            self._handle(msg, rid, payload)

    def pop_ready(self, max_bytes: int, now: float | None = None) -> bytes:
        """Up to *max_bytes* of reply bytes whose time has come."""
        now = self.clock() if now is None else now
        with self._lock:
            out = bytearray()
            while self._out and self._out[0][0] <= now and len(out) < max_bytes:
                t, data = self._out[0]
                take = data[: max_bytes - len(out)]
                out += take
                if len(take) == len(data):
                    self._out.pop(0)
                else:
                    self._out[0] = (t, data[len(take) :])
            return bytes(out)

    def wait_ready(self, timeout_s: float) -> bool:
        """Block until some reply bytes are ready or *timeout_s* passes."""
        deadline = time.monotonic() + timeout_s
        with self._lock:
            while True:
                if self._out and self._out[0][0] <= self.clock():
                    return True
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                wait = left if not self._out else min(left, max(0.0005, self._out[0][0] - self.clock()))
                self._lock.wait(wait)

    def on_hangup(self) -> None:
        """The host closed/reset the device: a hung firmware restarts."""
        self.hung = False
        self.frames = 0
        self.buf.clear()
        with self._lock:
            self._out.clear()

    def _queue(self, data: bytes, delay_s: float = 0.0) -> None:
        with self._lock:
            self._out.append((self.clock() + delay_s, data))
            self._lock.notify_all()

    # -- firmware ----------------------------------------------------------------------------------
    def _handle(self, msg: int, rid: int, payload: bytes) -> None:
        label = LABELS.get(msg, "?")
        f = self.faults
        self.frames += 1
        if f.hang_after is not None and self.frames > f.hang_after:
            self.hung = True
        if self.hung or f.fire("no-reply", label):
            return
        if f.fire("unplug", label):
            self.unplugged = True
            if self.on_unplug is not None:
                self.on_unplug()
            return
        if f.fire("device-busy", label):
            self._queue(frame(msg, rid, flags=REPLY | NACK, error=170))
            return
        if f.fire("cal-failure", label):
            self._queue(frame(msg, rid, flags=REPLY | NACK, error=120))
            return
        code, body = self._reply(msg, label)
        out = frame(msg, rid, body, flags=REPLY | (NACK if code else ACK), error=code)
        if label == "RD" and f.fire("corrupt-checksum", "RD"):
            out = out[:-20] + bytes(b ^ 0xFF for b in out[-20:-4]) + out[-4:]
        if f.fire("garbage", label):
            out = b"\x00\xc1\x13\xfe" + out
        if f.fire("partial-frame", label):
            out = out[: len(out) // 2]
        self._queue(out, self.slow_s if f.fire("slow-reply", label) else 0.0)

    def _reply(self, msg: int, label: str) -> tuple[int, bytes]:
        p, now, f = self.physics, self.clock(), self.faults
        if f.active("cal-expired"):
            p.expire_calibration()
            f.clear("cal-expired")
        if label in ("CE",):
            return 0, b""
        if label == "ID":
            body = struct.pack(
                "<8s8s8sB",
                self.model.encode(),
                p.character.serial.encode(),
                self.firmware.encode(),
                len(ASPECULAR),
            )
            return 0, body + b"".join(struct.pack("<bb", 45, a) for a in ASPECULAR)
        if label == "ST":
            needed = {None: 0, "zero": 1, "white": 2, "verify": 3}[p.cal.needed(now)]
            exp = p.cal.expires(now, dt.datetime.now(dt.UTC))
            return 0, struct.pack(
                "<BIIf", needed, p.cal.counter, int(exp.timestamp()) if exp else 0, p.temperature_c()
            )
        if label == "ZC":
            p.calibrate_zero()
            return 0, b""
        if label == "WC":
            if not p.cal.zero_done:
                return 131, b""
            p.calibrate_white()
            return 0, struct.pack("<I", p.cal.counter)
        if label == "VC":
            if p.cal.needed(now) in ("zero", "white"):
                return 130, b""
            de, ok = p.verify()
            exp = p.cal.expires(now, dt.datetime.now(dt.UTC))
            return (0 if ok else 120), struct.pack("<fBI", de, int(ok), int(exp.timestamp()) if exp else 0)
        if label == "MS":
            for fault, code in (("lamp-failure", 111), ("tilt", 140), ("battery-low", 180)):
                if f.fire(fault, "MS"):
                    return code, b""
            due = p.cal.needed(now)
            if due is not None:
                return {"zero": 131, "white": 130, "verify": 132}[due], b""
            self.state, self.done_at, self.has_data = 1, now + self.measure_time_s, False
            return 0, b""
        if label == "PO":
            if self.state == 1 and now >= self.done_at and not f.active("stuck-busy"):
                self._finish()
            return 0, bytes([self.state])
        if label == "RD":
            return (0, self.data) if self.has_data else (45, b"")
        return 30, b""

    def _finish(self) -> None:
        p = self.physics
        refl = p.measure(ASPECULAR)
        warn = 0
        if self.faults.fire("out-of-range", "RD"):
            warn |= 0x10
            refl = refl * 0 + 9.99
        body = struct.pack(
            "<8sIIfHHB",
            p.character.serial.encode(),
            p.cal.counter,
            int(dt.datetime.now(dt.UTC).timestamp()),
            p.temperature_c(),
            warn,
            0,
            len(ASPECULAR),
        )
        for a, row in zip(ASPECULAR, refl, strict=True):
            body += struct.pack("<bb31f", 45, a, *row)
        self.data, self.has_data, self.state = body, True, 0


class Ma3Device:
    """The firmware behind a pty (subprocess route): same frames on a serial line."""

    def __init__(
        self,
        physics: SpectroPhysics | None = None,
        faults: FaultPlan | None = None,
        measure_time_s: float = 0.3,
    ) -> None:
        self.firmware = Ma3Firmware(physics, faults, measure_time_s)
        self._link: PtyHost | None = None
        self.firmware.on_unplug = self._unplug

    def _unplug(self) -> None:
        if self._link is not None:
            self._link.unplug()

    def feed(self, data: bytes, link: PtyHost) -> None:
        """Bytes from the driver."""
        self._link = link
        self.firmware.receive(data)
        self.tick(link)

    def tick(self, link: PtyHost) -> None:
        """Send whatever replies are due."""
        self._link = link
        while out := self.firmware.pop_ready(1 << 16):
            link.send(out)

    def on_hangup(self) -> None:
        """Port closed by the driver."""
        self.firmware.on_hangup()


def build_device(config: SimulatorConfig, faults: FaultPlan, recipe: RecipePanel | None) -> Ma3Device:
    """The device ``python -m simulators.ma3`` serves for *config* (*recipe*: the loaded recipe panel)."""
    from simulators.config import spectro_physics

    return Ma3Device(spectro_physics(config, "300456", recipe), faults, measure_time_s=config.measure_time_s)


if __name__ == "__main__":
    from simulators._cli import main

    raise SystemExit(main("ma3", build_device))
