"""Driver-stack overhead per measurement, for the three families, against the same simulators.

For each family the simulator runs in this process (a pty thread for the ASCII family, the pyusb
simulator backend for the binary family, the hidapi-boundary device for the HID family) and is driven
two ways in the same run:

* **raw**: the minimal byte exchange written inline (pre-built frames, no parsing, no retries), the
  baseline: simulated instrument time plus the bare transport;
* **driver**: ``Instrument.measure()`` through transport → protocol → instrument (typed reading).

The figure is ``driver − raw`` (median and 90th percentile, ms): what the driver stack adds beyond the
simulated instrument. Bar: ≤ 5 ms. Also reported: ``driver − simulated measurement time``.

Run: ``.venv/bin/python -m bench.driver_overhead [--n 30]``.
"""

from __future__ import annotations

import hashlib
import struct
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import serial

from bench._report import Case, bench_parser, write_section
from simulators.gloss import PATH, GlossDevice, GlossPhysics
from simulators.ma3 import Ma3Firmware
from simulators.ma6 import Ma6Device
from simulators.physics import InstrumentCharacter, SpectroPhysics
from simulators.pty_host import PtyHost
from simulators.usb_backend import SimUsbBackend, SimUsbDevice
from station.drivers.gloss import GlossMeter
from station.drivers.ma3 import MA3Spectro
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import HidTransport, SerialTransport, UsbTransport

MEASURE_S = 0.05
POLL_S = 0.005
ROOT = Path(__file__).resolve().parents[1]


def _time(fn: Callable[[], object], n: int) -> np.ndarray:
    fn()  # warm caches (spectral recovery of the panel, lobe)
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return np.asarray(out) * 1000.0


def bench_ma6(n: int) -> tuple[np.ndarray, np.ndarray]:
    dev = Ma6Device(SpectroPhysics(), measure_time_s=MEASURE_S)
    with PtyHost(dev) as host:
        inst = MA6Spectro(SerialTransport(host.path), poll_period_s=POLL_S).open()
        driver = _time(inst.measure, n)
        inst.close()
        ser = serial.Serial(host.path, 115200, timeout=2)

        def ask(cmd: bytes) -> bytes:
            ser.write(cmd)
            buf = b""
            while not buf.endswith(b"\r\n>"):
                buf += ser.read(ser.in_waiting or 1)
            return buf

        def raw() -> None:
            ask(b"MS\r")
            while b"IDLE" not in ask(b"PO\r"):
                time.sleep(POLL_S)
            ask(b"RD\r")

        base = _time(raw, n)
        ser.close()
    return driver, base


def _frame(msg: int, rid: int) -> bytes:
    head = struct.pack("<2sHHHIIII", b"\xc1\xc0", 0x1000, 0x02, 0, msg, rid, 0, 0)
    return head + hashlib.md5(head, usedforsecurity=False).digest() + b"\xc5\xc4\xc3\xc2"


def bench_ma3(n: int) -> tuple[np.ndarray, np.ndarray]:
    fw = Ma3Firmware(SpectroPhysics(character=InstrumentCharacter(serial="300456")), measure_time_s=MEASURE_S)
    backend = SimUsbBackend([SimUsbDevice(fw)])
    inst = MA3Spectro(UsbTransport(0x1209, 0xCA03, backend=backend), poll_period_s=POLL_S).open()
    driver = _time(inst.measure, n)
    inst.close()
    import usb.core
    import usb.util

    dev = usb.core.find(idVendor=0x1209, idProduct=0xCA03, backend=backend)
    dev.set_configuration()
    usb.util.claim_interface(dev, 0)
    rid = [100]

    def ask(msg: int) -> bytes:
        rid[0] += 1
        dev.write(0x01, _frame(msg, rid[0]), 1000)
        data = bytes(dev.read(0x81, 64, 1000))
        need = 24 + struct.unpack_from("<I", data, 16)[0] + 20
        while len(data) < need:
            data += bytes(dev.read(0x81, 64, 1000))
        return data

    def raw() -> None:
        ask(0x20)
        while ask(0x21)[24] != 0:
            time.sleep(POLL_S)
        ask(0x22)

    base = _time(raw, n)
    usb.util.dispose_resources(dev)
    return driver, base


def bench_gloss(n: int) -> tuple[np.ndarray, np.ndarray]:
    dev = GlossDevice(GlossPhysics(), measure_time_s=MEASURE_S)
    inst = GlossMeter(HidTransport(PATH, dev, dev.enumerate)).open()
    driver = _time(inst.measure, n)
    inst.close()
    dev.open_path(PATH)
    seq = [0]

    def raw() -> None:
        seq[0] = (seq[0] + 1) & 0xFF
        dev.write(bytes([1, 0x10, seq[0]]) + bytes(62))
        while True:
            r = dev.read(65, 1000)
            if r and r[1] == seq[0] and r[5] == 0:
                return

    base = _time(raw, n)
    dev.close()
    return driver, base


def _chart(rows: list[tuple[str, float, float]]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 2.8))
    names = [r[0] for r in rows]
    y = np.arange(len(rows))
    ax.barh(y - 0.18, [r[1] for r in rows], 0.36, label="driver − raw exchange")
    ax.barh(y + 0.18, [r[2] for r in rows], 0.36, label="driver − simulated measurement")
    ax.axvline(5.0, color="k", ls="--", lw=1, label="bar: 5 ms")
    ax.set_yticks(y, names)
    ax.set_xlabel("ms per measurement (median)")
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(ROOT / "docs" / "driver-overhead.png", dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    """Run the three families and write the ``driver_overhead`` section of docs/benchmarks.md."""
    p = bench_parser(__doc__, "driver_overhead")
    p.add_argument("--n", type=int, default=30)
    args = p.parse_args(argv)
    cases: list[Case] = []
    rows = []
    for name, fn in (
        ("ma6 ASCII / pty", bench_ma6),
        ("ma3 binary / pyusb", bench_ma3),
        ("gloss HID / hidapi boundary", bench_gloss),
    ):
        driver, base = fn(args.n)
        over = float(np.median(driver) - np.median(base))
        cases += [
            Case(
                f"{name}: driver measure()",
                f"n={args.n}",
                float(np.median(driver)),
                "ms",
                f"simulated measurement {MEASURE_S * 1000:.0f} ms",
            ),
            Case(f"{name}: raw exchange baseline", f"n={args.n}", float(np.median(base)), "ms"),
            Case(f"{name}: overhead (median)", f"n={args.n}", over, "ms", "bar ≤ 5 ms"),
            Case(
                f"{name}: overhead (p90)",
                f"n={args.n}",
                float(np.percentile(driver, 90) - np.percentile(base, 90)),
                "ms",
            ),
        ]
        rows.append((name, over, float(np.median(driver)) - MEASURE_S * 1000))
    _chart(rows)
    table = "\n".join(f"| {r[0]} | {r[1]:.2f} | {r[2]:.2f} |" for r in rows)
    extra = (
        "Overhead = median(driver) − median(raw exchange), same simulator, same run; the raw exchange polls at\n"
        f"the driver's period ({POLL_S * 1000:.0f} ms). Second column: driver time beyond the simulated "
        f"{MEASURE_S * 1000:.0f} ms measurement (includes polling granularity and simulator work).\n\n"
        "| family | driver − raw (ms) | driver − simulated time (ms) |\n|---|---|---|\n"
        + table
        + "\n\n![driver overhead](driver-overhead.png)"
    )
    write_section("driver_overhead", "Driver-stack overhead per measurement", cases, extra)


if __name__ == "__main__":
    main()
