"""Simulated 20/60/85° gloss meter with haze, log haze, DOI and Rspec (family 3), at the hidapi call
boundary.

There is no uhid (or hidraw) on this machine, so a kernel HID device cannot be created: the simulator
is an object with ``hid.device``'s methods (``open_path``, ``read``, ``write``, ``get_feature_report``,
``send_feature_report``, ``close``) plus an ``enumerate`` with ``hid.enumerate``'s dict layout. The
driver's :class:`~station.drivers.transport.HidTransport` takes these through its ``device_factory``
and ``enumerate_fn`` arguments; the real ``hid.enumerate`` path is tested separately. For another
process, :class:`HidBridgeServer` serves the same calls over a pty (``python -m simulators.gloss``).

Physics (:class:`GlossPhysics`): the panel's 60° gloss gives its clear coat, a sharp peak plus haze
(``station.model.gloss.coat_from_gloss``), and the meter reads it with
``station.model.gloss.coat_readings``: 20/60/85° gloss of the simulated ISO 2813 meter, haze (ASTM E430
method B), log haze, DOI and Rspec, each relative to the black-glass standard (the closed forms are in
that function's docstring; log haze = 1285 · log10(HU/20 + 1) is Rhopoint's form, UNCONFIRMED). An 88 GU
panel reads about 78/88/97 GU, DOI 90, haze 0.5 HU (before this coat model, one wide lobe read
34/88/79 GU and DOI 2.3). Black-glass references (:func:`reference_coat`) are one lobe of index 1.567.

Noise ±0.2 GU (1σ 0.1 GU) repeatability and a linearity error ≤ 0.2 % of reading, within the
±0.5 GU class of combined meters (research note instruments.md §2, UNCONFIRMED vendor figures).
"""

from __future__ import annotations

import errno
import functools
import math
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from simulators.faults import FaultPlan
from station.drivers.families import FAMILIES

if TYPE_CHECKING:
    from simulators.config import SimulatorConfig
    from simulators.pty_host import PtyHost
    from simulators.recipe import RecipePanel

__all__ = ["GlossDevice", "GlossPhysics", "HidBridgeServer", "build_device", "reference_coat"]

REPORT = 64
GEOMETRIES = (20, 60, 85)
PATH = b"/sim/hidraw0"
#: The USB ids the simulated meter presents: the gloss family's (``station.drivers.families``).
VID, PID = next(f for f in FAMILIES if f.name == "gloss").device_id()


def _xor(data: bytes) -> int:
    x = 0
    for b in data:
        x ^= b
    return x


@functools.cache
def reference_coat(gloss_gu: float, geometry_deg: int) -> Any:
    """A black-glass-like reference reading *gloss_gu* at *geometry_deg*: one Phong lobe of index 1.567
    (exponent solved), as a ``station.model.gloss.CoatLobes``."""
    from scipy.optimize import brentq

    from station.model.gloss import (
        STANDARD_INDEX,
        SpecularLobe,
        coat_from_lobe,
        fresnel_unpolarised,
        simulate_gloss_meter,
    )

    albedo = fresnel_unpolarised(60.0, STANDARD_INDEX)

    def lobe(log_n: float) -> Any:
        return SpecularLobe(math.exp(log_n), albedo, 0.01, STANDARD_INDEX)

    log_n = brentq(
        lambda x: simulate_gloss_meter(lobe(x), geometry_deg) - gloss_gu, 0.0, math.log(1e7), xtol=1e-12
    )
    return coat_from_lobe(lobe(log_n))


@dataclass
class GlossPhysics:
    """The panel (a two-lobe clear coat) under a simulated meter with noise, linearity error and calibration."""

    gloss_60_gu: float = 88.0
    coat: Any = None
    serial: str = "GM0815"
    noise_gu: float = 0.1
    linearity: tuple[float, float, float] = (0.0015, -0.001, 0.002)
    seed: int = 7
    calibration_life_s: float = 24 * 3600.0
    _rng: np.random.Generator = field(init=False)

    def __post_init__(self) -> None:
        if self.coat is None:
            from station.model.gloss import coat_from_gloss

            self.coat = coat_from_gloss(float(self.gloss_60_gu))
        self._rng = np.random.default_rng(self.seed)
        self.standard_gu = [100.0, 100.0, 100.0]
        self.counter = 1
        self.calibrated_at: float | None = time.monotonic()
        self.gain = [1.0, 1.0, 1.0]

    def true_readings(self) -> Any:
        """Noise-free readings of the panel (``station.model.gloss.GlossReadings``)."""
        from station.model.gloss import coat_readings

        return coat_readings(self.coat)

    def true_gloss(self) -> list[float]:
        """Noise-free 20/60/85° readings of the panel (GU)."""
        r = self.true_readings()
        return [r.g20_gu, r.g60_gu, r.g85_gu]

    def raw(self, values: list[float]) -> list[float]:
        """What the detector reports for true *values*: linearity error and noise."""
        return [
            v * (1 + e) + self._rng.normal(0.0, self.noise_gu)
            for v, e in zip(values, self.linearity, strict=True)
        ]

    def calibrate(self) -> list[float]:
        """Read the standard (black glass, certified ``standard_gu``) and set the gain; returns raw readings."""
        raw = [r for r in self.raw(self.standard_gu)]
        self.gain = [s / r for s, r in zip(self.standard_gu, raw, strict=True)]
        self.counter += 1
        self.calibrated_at = time.monotonic()
        return raw

    def needs_calibration(self) -> bool:
        """Whether the calibration is missing or expired."""
        return self.calibrated_at is None or time.monotonic() - self.calibrated_at > self.calibration_life_s

    def measure(self) -> dict[str, float]:
        """One reading: gloss per geometry (GU, with noise), haze (HU), log haze, DOI, Rspec."""
        r = self.true_readings()
        true = [r.g20_gu, r.g60_gu, r.g85_gu]
        g = [v * k for v, k in zip(self.raw(true), self.gain, strict=True)]
        return {
            "g20": g[0],
            "g60": g[1],
            "g85": g[2],
            "haze": r.haze_hu,
            "log_haze": r.log_haze,
            "doi": r.doi,
            "rspec": r.rspec_gu,
        }


class GlossDevice:
    """The meter's firmware behind hidapi-shaped calls (one handle at a time)."""

    model, firmware = "GLS3", "3.1.0"

    def __init__(
        self,
        physics: GlossPhysics | None = None,
        faults: FaultPlan | None = None,
        measure_time_s: float = 0.2,
        slow_s: float = 0.4,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.physics = physics or GlossPhysics()
        self.faults = faults or FaultPlan()
        self.measure_time_s = measure_time_s
        self.slow_s = slow_s
        self.clock = clock
        self._out: list[tuple[float, bytes]] = []
        self._cv = threading.Condition()
        self.opened = False
        self.unplugged = False
        self.held = False
        self.hung = False
        self.commands = 0
        self.written: list[bytes] = []

    @classmethod
    def from_config(
        cls, config: SimulatorConfig, faults: FaultPlan, recipe: RecipePanel | None = None
    ) -> GlossDevice:
        """Build from a simulator configuration (``design`` sets the panel's 60° gloss; *recipe*, the
        loaded ``config.recipe`` panel, sets the 60° gloss the colorant model predicts from its
        matting fraction)."""
        gloss = 88.0
        if recipe is not None:
            gloss = recipe.gloss_gu
        elif config.design:
            from station.model.design_io import load_design

            gloss = load_design(config.design).gloss_gu
        return cls(
            GlossPhysics(gloss_60_gu=gloss, serial=config.serial or "GM0815", noise_gu=0.1 * config.noise),
            faults,
            measure_time_s=config.measure_time_s,
        )

    # -- hid.enumerate / hid.device surface ----------------------------------------------------------
    def enumerate(self, vid: int = 0, pid: int = 0) -> list[dict[str, Any]]:
        """``hid.enumerate`` dicts for this device (none once unplugged)."""
        if self.unplugged or (vid and vid != VID) or (pid and pid != PID):
            return []
        return [
            {
                "path": PATH,
                "vendor_id": VID,
                "product_id": PID,
                "serial_number": self.physics.serial,
                "release_number": 0x0310,
                "manufacturer_string": "CACAD Sim",
                "product_string": "GLS3 gloss meter",
                "usage_page": 0xFF00,
                "usage": 1,
                "interface_number": 0,
            }
        ]

    def __call__(self) -> GlossDevice:
        """Act as the ``device_factory`` (``hid.device`` is called the same way)."""
        return self

    def open_path(self, path: bytes) -> None:
        if self.unplugged or path != PATH:
            raise OSError("open failed")
        if self.held or self.faults.active("port-held"):
            raise OSError(errno.EBUSY, "open failed: device busy")
        self.opened = True
        self.hung = False
        self.commands = 0

    def close(self) -> None:
        self.opened = False
        with self._cv:
            self._out.clear()

    def _check(self) -> None:
        if self.unplugged or not self.opened:
            raise OSError("read error" if self.unplugged else "not open")

    def write(self, buff: Any) -> int:
        self._check()
        data = bytes(buff)
        self.written.append(data)
        if len(data) != REPORT + 1 or data[0] != 0x01:
            return -1
        self._command(data[1], data[2])
        return len(data)

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        self._check()
        deadline = time.monotonic() + timeout_ms / 1000.0
        with self._cv:
            while True:
                if self.unplugged:
                    raise OSError("read error")
                if self._out and self._out[0][0] <= self.clock():
                    return list(self._out.pop(0)[1][:max_length])
                left = deadline - time.monotonic()
                if left <= 0:
                    return []  # hidapi's 0: timeout
                self._cv.wait(min(left, 0.002))

    def get_feature_report(self, report_num: int, max_length: int) -> list[int]:
        self._check()
        if report_num != 0x03:
            raise OSError("get_feature_report: no such report")
        p = self.physics
        exp = int(time.time() + p.calibration_life_s - (time.monotonic() - (p.calibrated_at or 0)))
        body = struct.pack(
            "<8s8s8sBI3fI",
            self.model.encode(),
            p.serial.encode(),
            self.firmware.encode(),
            int(p.needs_calibration()),
            p.counter,
            *p.standard_gu,
            0 if p.calibrated_at is None else exp,
        ).ljust(REPORT - 1, b"\0")
        return list((bytes([0x03]) + body + bytes([_xor(body)]))[:max_length])

    def send_feature_report(self, buff: Any) -> int:
        self._check()
        data = bytes(buff)
        if len(data) != REPORT + 1 or data[0] != 0x04 or _xor(data[1:REPORT]) != data[REPORT]:
            return -1
        self.physics.standard_gu = list(struct.unpack_from("<3f", data, 1))
        return len(data)

    # -- firmware ------------------------------------------------------------------------------------
    def _emit(
        self, seq: int, cmd: int, status: int, state: int, body: bytes, delay_s: float = 0.0, label: str = ""
    ) -> None:
        payload = bytes([seq, status & 0xFF, status >> 8, cmd, state]) + body
        payload = payload.ljust(REPORT - 1, b"\0")
        report = bytes([0x02]) + payload + bytes([_xor(payload)])
        f = self.faults
        if label and f.fire("corrupt-checksum", label):
            report = report[:-1] + bytes([report[-1] ^ 0x55])
        if label and f.fire("partial-frame", label):
            report = report[: len(report) // 2]
        if label and f.fire("slow-reply", label):
            delay_s += self.slow_s
        with self._cv:
            self._out.append((self.clock() + delay_s, report))
            self._out.sort(key=lambda item: item[0])
            self._cv.notify_all()

    def _command(self, cmd: int, seq: int) -> None:
        f, p = self.faults, self.physics
        label = {0x10: "MS", 0x20: "WC", 0x30: "CE"}.get(cmd, "?")
        self.commands += 1
        if f.hang_after is not None and self.commands > f.hang_after:
            self.hung = True
        if self.hung or f.fire("no-reply", label):
            return
        if f.fire("unplug", label):
            self.unplugged = True
            with self._cv:
                self._cv.notify_all()
            return
        if f.active("cal-expired"):
            p.calibrated_at = None
            f.clear("cal-expired")
        if cmd == 0x30:
            self._emit(seq, cmd, 0, 0, b"")
        elif cmd == 0x20 and f.fire("cal-failure", label):
            self._emit(seq, cmd, 120, 0, b"")
        elif cmd == 0x20:
            raw = p.calibrate()
            exp = int(time.time() + p.calibration_life_s)
            self._emit(seq, cmd, 0, 0, struct.pack("<I3fI", p.counter, *raw, exp), label="WC")
        elif cmd == 0x10:
            for fault, code in (
                ("lamp-failure", 111),
                ("tilt", 140),
                ("battery-low", 180),
                ("device-busy", 170),
            ):
                if f.fire(fault, "MS"):
                    self._emit(seq, cmd, code, 0, b"")
                    return
            if p.needs_calibration():
                self._emit(seq, cmd, 133, 0, b"")
                return
            self._emit(seq, cmd, 0, 1, b"")  # busy acknowledgement
            if f.active("stuck-busy"):
                return
            m = p.measure()
            warn = 0
            if f.fire("out-of-range", "RD"):
                warn |= 0x20
                m["g20"] = m["g60"] = m["g85"] = 9999.0
            body = struct.pack(
                "<7ffHII",
                m["g20"],
                m["g60"],
                m["g85"],
                m["haze"],
                m["log_haze"],
                m["doi"],
                m["rspec"],
                24.0,
                warn,
                p.counter,
                int(time.time()),
            )
            self._emit(seq, cmd, 0, 0, body, delay_s=self.measure_time_s, label="MS")
        else:
            self._emit(seq, cmd, 30, 0, b"")


class HidBridgeServer:
    """Serves :class:`GlossDevice`'s hidapi calls over a pty (see ``station.drivers.gloss.HidBridgeDevice``)."""

    def __init__(self, device: GlossDevice) -> None:
        self.device = device
        self.buf = bytearray()

    def feed(self, data: bytes, link: PtyHost) -> None:
        """Decode ``op, length, payload`` calls and answer each."""
        self.buf += data
        while len(self.buf) >= 3:
            (n,) = struct.unpack_from("<H", self.buf, 1)
            if len(self.buf) < 3 + n:
                return
            op, payload = bytes(self.buf[:1]), bytes(self.buf[3 : 3 + n])
            del self.buf[: 3 + n]
            if self.device.unplugged and op != b"C":
                link.unplug()
                return
            try:
                out = self._call(op, payload)
                link.send(op.lower() + struct.pack("<H", len(out)) + out)
            except OSError as exc:
                msg = str(exc).encode()
                link.send(b"E" + struct.pack("<H", len(msg)) + msg)
            if self.device.unplugged:
                link.unplug()
                return

    def _call(self, op: bytes, payload: bytes) -> bytes:
        d = self.device
        if op == b"O":
            d.open_path(PATH)
            return b""
        if op == b"W":
            return struct.pack("<h", d.write(payload))
        if op == b"R":
            size, timeout_ms = struct.unpack("<HI", payload)
            return bytes(d.read(size, timeout_ms))
        if op == b"G":
            num, size = struct.unpack("<BH", payload)
            return bytes(d.get_feature_report(num, size))
        if op == b"S":
            return struct.pack("<h", d.send_feature_report(payload))
        if op == b"C":
            d.close()
            return b""
        raise OSError(f"bridge: unknown op {op!r}")

    def on_hangup(self) -> None:
        """Driver closed the pty: the HID handle is closed too."""
        self.buf.clear()
        self.device.close()

    def tick(self, link: PtyHost) -> None:
        """Nothing periodic."""


def build_device(config: SimulatorConfig, faults: FaultPlan, recipe: RecipePanel | None) -> HidBridgeServer:
    """The device ``python -m simulators.gloss`` serves for *config* (the gloss meter behind its bridge)."""
    return HidBridgeServer(GlossDevice.from_config(config, faults, recipe))


if __name__ == "__main__":
    from simulators._cli import main

    raise SystemExit(main("gloss", build_device))
