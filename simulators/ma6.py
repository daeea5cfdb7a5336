"""Simulated 6-angle spectrophotometer (family 1) speaking the ASCII prompt protocol on a pty.

``python -m simulators.ma6 [--design FILE | --recipe FILE] [--fault SPEC ...] [--rfc2217]`` prints
``ADDRESS ma6@/dev/pts/N`` (or ``ma6@rfc2217://127.0.0.1:PORT``) and serves until stdin closes or
SIGTERM. Protocol: docs/protocols/ma6-ascii.md; physics: :mod:`simulators.physics`.
"""

from __future__ import annotations

import datetime as dt
import re
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from simulators.faults import FaultPlan

if TYPE_CHECKING:
    from simulators.config import SimulatorConfig
    from simulators.physics import SpectroPhysics
    from simulators.pty_host import PtyHost
    from simulators.recipe import RecipePanel

__all__ = ["ASPECULAR_15", "ASPECULAR_45", "BAUD_RATES", "Ma6Device", "build_device"]

ASPECULAR_45 = (-15, 15, 25, 45, 75, 110)
ASPECULAR_15 = (-45, -15, 15, 25, 45, 60)  # second block of 12-geometry instruments (our choice)
BAUD_RATES = (9600, 19200, 38400, 57600, 115200)
GARBAGE = b"\xfe\x13\x80\xf0~"  # what a receiver at the wrong baud rate makes of a CR


def _line(key: str, value: object) -> bytes:
    return f"{key}={value}\r\n".encode("ascii")


def status(code: int) -> bytes:
    """The reply trailer ``<NNN>\\r\\n>``."""
    return f"<{code:03d}>\r\n>".encode("ascii")


def checksum16(data: bytes) -> int:
    """16-bit byte sum (the ``CS=`` line)."""
    return sum(data) & 0xFFFF


class Ma6Device:
    """Firmware of the simulated instrument: parses commands, keeps state, builds replies.

    Times in seconds. ``clock`` drives measurement completion and calibration expiry.
    """

    model = "MA6"
    firmware = "1.4.2"

    def __init__(
        self,
        physics: SpectroPhysics | None = None,
        faults: FaultPlan | None = None,
        measure_time_s: float = 0.3,
        calibrate_time_s: float = 0.05,
        slow_s: float = 0.4,
        twelve: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if physics is None:
            from simulators.physics import SpectroPhysics

            physics = SpectroPhysics()
        self.physics = physics
        self.faults = faults or FaultPlan()
        self.measure_time_s = measure_time_s
        self.calibrate_time_s = calibrate_time_s
        self.slow_s = slow_s
        self.clock = clock
        self.blocks = ((45, ASPECULAR_45), (15, ASPECULAR_15)) if twelve else ((45, ASPECULAR_45),)
        if twelve:
            self.model = "MA12"
        self.baud = 9600
        self.buf = bytearray()
        self.state = "IDLE"
        self.done_at = 0.0
        self.data: bytes | None = None
        self.commands = 0
        self.hung = False
        self.received: list[bytes] = []

    @property
    def geometries(self) -> tuple[str, ...]:
        """Geometry names in reply order, e.g. ``45as-15``."""
        return tuple(f"{ill}as{a}" for ill, angles in self.blocks for a in angles)

    # -- host callbacks ----------------------------------------------------------------------------
    def feed(self, data: bytes, link: PtyHost) -> None:
        """Bytes from the driver: run every complete CR-terminated command."""
        self.buf += data
        while b"\r" in self.buf:
            line, _, rest = bytes(self.buf).partition(b"\r")
            self.buf = bytearray(rest)
            self._command(line, link)

    def on_hangup(self) -> None:
        """The driver closed the port: a hung device comes back, the command counter restarts."""
        self.hung = False
        self.commands = 0
        self.buf.clear()

    def tick(self, link: PtyHost) -> None:
        """Idle tick: nothing to do (completion is checked lazily on ``PO``)."""

    # -- commands ----------------------------------------------------------------------------------
    def _command(self, line: bytes, link: PtyHost) -> None:
        self.received.append(line + b"\r")
        rate = link.baudrate()
        if rate and rate != self.baud:
            link.send(GARBAGE)
            return
        cmd = line.decode("ascii", "replace").strip().upper()
        label = "BR" if cmd.endswith("BR") else cmd
        self.commands += 1
        f = self.faults
        if f.hang_after is not None and self.commands > f.hang_after:
            self.hung = True
        if self.hung or f.fire("no-reply", label):
            return
        if f.fire("unplug", label):
            link.unplug()
            return
        if f.fire("slow-reply", label):
            time.sleep(self.slow_s)
        if f.fire("device-busy", label):
            link.send(status(170))
            return
        if f.fire("cal-failure", label):
            link.send(status(120))
            return
        reply = self._reply(cmd, label)
        if f.fire("garbage", label):
            reply = GARBAGE + reply
        if f.fire("partial-frame", label):
            reply = reply[: len(reply) // 2]
        link.send(reply)
        if label == "BR" and reply == status(0):
            self.baud = int(cmd[:-2])

    def _reply(self, cmd: str, label: str) -> bytes:
        p = self.physics
        now = self.clock()
        if self.faults.active("cal-expired"):
            p.expire_calibration()
            self.faults.clear("cal-expired")
        if cmd in ("", "CE"):
            return status(0)
        if cmd == "ID":
            return (
                _line("MODEL", self.model)
                + _line("SERIAL", p.character.serial)
                + _line("FW", self.firmware)
                + _line("GEOM", ",".join(self.geometries))
                + status(0)
            )
        if label == "BR":
            m = re.fullmatch(r"(\d+)BR", cmd)
            return status(0) if m and int(m.group(1)) in BAUD_RATES else status(25)
        if cmd == "ST":
            needed = p.cal.needed(now)
            exp = p.cal.expires(now, dt.datetime.now(dt.UTC))
            return (
                _line("CAL", (needed or "ok").upper())
                + _line("CALID", p.cal.calibration_id)
                + _line("EXPIRES", _stamp(exp) if exp else "NONE")
                + _line("TEMP", f"{p.temperature_c():.1f}")
                + status(0)
            )
        if cmd == "ZC":
            time.sleep(self.calibrate_time_s)
            p.calibrate_zero()
            return status(0)
        if cmd == "WC":
            if not p.cal.zero_done:
                return status(131)
            time.sleep(self.calibrate_time_s)
            return _line("CALID", p.calibrate_white()) + status(0)
        if cmd == "VC":
            if p.cal.needed(now) in ("zero", "white"):
                return status(130)
            time.sleep(self.calibrate_time_s)
            de, ok = p.verify()
            exp = p.cal.expires(now, dt.datetime.now(dt.UTC))
            return (
                _line("DE", f"{de:.3f}")
                + _line("PASS", int(ok))
                + _line("EXPIRES", _stamp(exp) if exp else "NONE")
                + status(0 if ok else 120)
            )
        if cmd == "MS":
            return self._start(now)
        if cmd == "PO":
            if self.state == "MEASURING" and now >= self.done_at and not self.faults.active("stuck-busy"):
                self._finish()
            return _line("STATE", self.state) + status(0)
        if cmd == "RD":
            return self._data()
        return status(30)

    def _start(self, now: float) -> bytes:
        f, p = self.faults, self.physics
        for fault, code in (("lamp-failure", 111), ("tilt", 140), ("battery-low", 180)):
            if f.fire(fault, "MS"):
                return status(code)
        needed = p.cal.needed(now)
        if needed is not None:
            return status({"zero": 131, "white": 130, "verify": 132}[needed])
        self.state, self.done_at, self.data = "MEASURING", now + self.measure_time_s, None
        return status(0)

    def _finish(self) -> None:
        p = self.physics
        rows = [p.measure(angles) for _, angles in self.blocks]
        warn = 0
        age = self.clock() - (p.cal.white_at or 0.0)
        if age > 0.8 * p.cal.life_s:
            warn |= 0x02  # calibration recommended
        body = (
            _line("SN", p.character.serial)
            + _line("CALID", p.cal.calibration_id)
            + _line("TIME", _stamp(dt.datetime.now(dt.UTC)))
            + _line("TEMP", f"{p.temperature_c():.1f}")
        )
        values = [r for block in rows for r in block]
        if self.faults.fire("out-of-range", "RD"):
            warn |= 0x10
            values = [[9.99999] * len(v) for v in values]
        body += _line("WARN", f"{warn:02X}") + _line("DIAG", "00")
        for name, row in zip(self.geometries, values, strict=True):
            body += _line(f"R{name}", ",".join(f"{v:.5f}" for v in row))
        self.data = body
        self.state = "IDLE"

    def _data(self) -> bytes:
        if self.data is None:
            return status(45)
        cs = checksum16(self.data)
        if self.faults.fire("corrupt-checksum", "RD"):
            cs ^= 0x5A5A
        return self.data + _line("CS", f"{cs:04X}") + status(0)


def _stamp(t: dt.datetime) -> str:
    return t.strftime("%Y-%m-%dT%H:%M:%SZ")


def build_device(config: SimulatorConfig, faults: FaultPlan, recipe: RecipePanel | None) -> Ma6Device:
    """The device ``python -m simulators.ma6`` serves for *config* (*recipe*: the loaded recipe panel)."""
    from simulators.config import spectro_physics

    return Ma6Device(
        spectro_physics(config, "600123", recipe),
        faults,
        measure_time_s=config.measure_time_s,
        twelve=config.twelve,
    )


if __name__ == "__main__":
    from simulators._cli import main

    raise SystemExit(main("ma6", build_device))
