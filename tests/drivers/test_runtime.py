"""Service-facing behaviour: async wrappers do not block the loop, one owner, closed on exit,
12-geometry instruments, address parsing."""

from __future__ import annotations

import asyncio
import time
from typing import Any

import pytest

from simulators.ma6 import Ma6Device
from simulators.physics import SpectroPhysics
from simulators.pty_host import PtyHost
from station.drivers import DeviceInUse, DriverInputError, open_instrument, split_address
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import SerialTransport
from tests.drivers.conftest import FAST, Ma6Bench


def test_async_measure_keeps_loop_running_and_serialises():
    bench = Ma6Bench(measure_time_s=0.15)
    bench.inst.open()

    async def scenario() -> tuple[int, tuple[Any, Any]]:
        in_flight = 0  # measurements started and not yet returned
        ticks_while_measuring = 0
        stop = asyncio.Event()

        async def ticker() -> None:
            nonlocal ticks_while_measuring
            while not stop.is_set():
                ticks_while_measuring += in_flight > 0
                await asyncio.sleep(0.01)

        async def measure():
            nonlocal in_flight
            in_flight += 1
            try:
                return await bench.inst.ameasure()
            finally:
                in_flight -= 1

        t = asyncio.create_task(ticker())
        readings = await asyncio.gather(measure(), measure())
        stop.set()
        await t
        return ticks_while_measuring, readings

    try:
        ticks, readings = asyncio.run(scenario())
    finally:
        bench.close()
    assert len(readings) == 2 and all(r.reflectance.shape == (6, 31) for r in readings)
    # a measurement that blocked the loop would run from start to return with no tick in between (then
    # zero); however slow the machine, a loop left running ticks while they are in flight
    assert ticks >= 2


def test_closed_on_exit_and_reopenable():
    with PtyHost(Ma6Device(SpectroPhysics(), measure_time_s=0.01)) as host:
        address = f"ma6@{host.path}"
        with open_instrument(address, **FAST) as inst:
            with pytest.raises(DeviceInUse):
                open_instrument(address, **FAST)
        assert not inst.transport.is_open
        with open_instrument(address, **FAST) as again:  # ownership released, port closed
            assert again.measure().reflectance.shape == (6, 31)


def test_twelve_geometry_instrument():
    dev = Ma6Device(SpectroPhysics(), measure_time_s=0.01, twelve=True)
    with PtyHost(dev) as host, MA6Spectro(SerialTransport(host.path), **FAST).open() as inst:
        assert inst.info is not None
        assert inst.info.model == "MA12" and len(inst.info.geometries) == 12
        r = inst.measure()
    assert r.reflectance.shape == (12, 31)
    angles, rows = r.block(15)
    assert angles == (-45, -15, 15, 25, 45, 60) and rows.shape == (6, 31)


def test_temperature_rises_on_a_cold_instrument():
    clock_t = [0.0]
    phys = SpectroPhysics(warm=False, clock=lambda: clock_t[0])
    with (
        PtyHost(Ma6Device(phys, measure_time_s=0.0, clock=lambda: clock_t[0])) as host,
        MA6Spectro(SerialTransport(host.path), **FAST).open() as inst,
    ):
        cold = inst.measure().temperature_c
        clock_t[0] = 600.0
        warm = inst.measure().temperature_c
    assert cold == pytest.approx(23.0, abs=0.05) and warm > 29.0


@pytest.mark.parametrize(
    ("address", "family"),
    [
        ("/dev/ttyACM0", "ma6"),
        ("usb:1209:ca03", "ma3"),
        ("hid:1209:ca60", "gloss"),
        ("ma3@/dev/pts/3", "ma3"),
        ("rfc2217://h:1", "ma6"),
    ],
)
def test_split_address(address, family):
    assert split_address(address)[0] == family


@pytest.mark.parametrize("address", ["nonsense", "ma6@", "ma3@usb:zz:01"])
def test_bad_addresses(address):
    with pytest.raises(DriverInputError):
        open_instrument(address)


def test_open_failure_is_fast():
    t0 = time.monotonic()
    from station.drivers import CommunicationError

    with pytest.raises(CommunicationError):
        open_instrument("/dev/ttyNOPE0")
    assert time.monotonic() - t0 < 1.0


def test_runtime_code_never_imports_simulators():
    """The import-linter contract, checked here too: no module under station/ or db/ imports simulators."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    offenders = []
    for pkg in ("station", "db"):
        for path in (root / pkg).rglob("*.py"):
            text = path.read_text()
            if "simulators" not in text:
                continue
            tree = ast.parse(text, str(path))
            for node in ast.walk(tree):
                names = (
                    [a.name for a in node.names]
                    if isinstance(node, ast.Import)
                    else ([node.module or ""] if isinstance(node, ast.ImportFrom) else [])
                )
                if any(n == "simulators" or n.startswith("simulators.") for n in names):
                    offenders.append(str(path.relative_to(root)))
    assert offenders == []
