"""The gloss meter behind the HID-over-pty bridge releases its port when an open fails.

A real pty: this test holds the master end and plays the bridge's far side. While it answers the
open call with a reply the driver does not expect, every open fails with that error (never with
:class:`DeviceInUse` left by an earlier failure); once it serves the simulated meter
(``simulators.gloss``), the next open succeeds and measures.
"""

from __future__ import annotations

import os
import select
import struct
import threading
from collections.abc import Iterator

import pytest

from simulators.gloss import GlossDevice, HidBridgeServer
from station.drivers import CommunicationError, DeviceInUse, open_instrument
from tests.drivers.conftest import Timing

FAST: Timing = {"timeout_s": 0.5, "retries": 1, "measure_limit_s": 2.0}


class BridgePeer:
    """The far end of a pty: answers each bridge call with a wrong reply (``refusing``) or serves a
    simulated gloss meter through :class:`HidBridgeServer`."""

    def __init__(self) -> None:
        self.master, slave = os.openpty()
        self.path = os.ttyname(slave)
        os.close(slave)  # the driver opens the slave by path
        self.refusing = True
        self.server = HidBridgeServer(GlossDevice(measure_time_s=0.01))
        self.opens_seen = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def send(self, data: bytes) -> None:
        os.write(self.master, data)

    def unplug(self) -> None:  # HidBridgeServer's link API; not used while the device stays plugged
        pass

    def _run(self) -> None:
        buf = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if not ready:
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError:  # EIO while no process has the slave open
                self._stop.wait(0.02)
                continue
            if self.refusing:
                buf += data
                while len(buf) >= 3:
                    (n,) = struct.unpack_from("<H", buf, 1)
                    if len(buf) < 3 + n:
                        break
                    op, buf = buf[:1], buf[3 + n :]
                    if op == b"O":
                        self.opens_seen += 1
                        self.send(b"x\x00\x00")  # not the "o" the driver waits for
                    elif op == b"C":
                        self.send(b"c\x00\x00")
            else:
                buf = b""
                self.server.feed(data, self)  # type: ignore[arg-type]

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        os.close(self.master)


@pytest.fixture
def peer() -> Iterator[BridgePeer]:
    p = BridgePeer()
    try:
        yield p
    finally:
        p.close()


def test_a_failed_open_leaves_the_port_free(peer: BridgePeer) -> None:
    address = f"gloss@{peer.path}"
    for attempt in range(1, 4):
        with pytest.raises(CommunicationError) as caught:
            open_instrument(address, **FAST)
        assert not isinstance(caught.value, DeviceInUse), (attempt, caught.value)
        assert "reply" in str(caught.value), caught.value
        assert peer.opens_seen == attempt  # each attempt reached the device again
    peer.refusing = False
    with open_instrument(address, **FAST) as meter:
        reading = meter.measure()
    assert abs(reading.gloss_gu[60] - 88.0) < 1.0
