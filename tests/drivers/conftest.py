"""Fixtures: simulators served on real ptys (tests may import simulators; runtime code may not)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import TypedDict

import pytest

from simulators.faults import FaultPlan
from simulators.ma6 import Ma6Device
from simulators.physics import InstrumentCharacter, SpectroPhysics
from simulators.pty_host import PtyHost
from simulators.scripted import ScriptedDevice
from station.drivers.ma6 import MA6Spectro
from station.drivers.transport import SerialTransport


class Timing(TypedDict):
    """Driver timing keywords: reply timeout (s), retries, and the measurement time limit (s)."""

    timeout_s: float
    retries: int
    measure_limit_s: float


FAST: Timing = {"timeout_s": 0.25, "retries": 1, "measure_limit_s": 0.5}


@contextmanager
def scripted_pty(pairs, **kw) -> Iterator[tuple[str, ScriptedDevice]]:
    """Serve *pairs* on a pty; on exit assert every pair was used and nothing unexpected came."""
    dev = ScriptedDevice(pairs, **kw)
    with PtyHost(dev) as host:
        yield host.path, dev
    assert dev.unexpected == [], f"unexpected writes (got, expected): {dev.unexpected}"
    assert dev.leftover == [], f"unprocessed protocol pairs remain: {dev.leftover}"


class Ma6Bench:
    """A simulated MA6 on a pty and the real driver connected to it."""

    def __init__(self, measure_time_s: float = 0.01, **character) -> None:
        self.faults = FaultPlan()
        self.physics = SpectroPhysics(character=InstrumentCharacter(**character))
        self.device = Ma6Device(
            self.physics, self.faults, measure_time_s=measure_time_s, calibrate_time_s=0.0, slow_s=0.4
        )
        self.host = PtyHost(self.device).start()
        self.inst = MA6Spectro(SerialTransport(self.host.path), **FAST)

    def close(self) -> None:
        self.inst.close()
        self.host.close()


@pytest.fixture
def ma6() -> Iterator[Ma6Bench]:
    bench = Ma6Bench()
    bench.inst.open()
    yield bench
    bench.close()
