"""Serve a simulated device on a real pseudo-terminal, so the driver opens it by path with pyserial.

The host thread reads the pty master, hands bytes to the device's ``feed`` and writes what it returns.
Linux pty masters share termios with the slave, so the device sees the baud rate the driver set
(:meth:`PtyHost.baudrate`). When every slave descriptor is closed the master reads ``EIO``: the host
calls ``device.on_hangup()`` (how a hung device is reset by reconnecting). ``unplug()`` closes the
master, which the driver sees as pyserial's "device reports readiness to read but returned no data" /
``EIO``, as after a USB-CDC unplug.
"""

from __future__ import annotations

import errno
import fcntl
import os
import pty
import select
import termios
import threading
import time
import tty
from typing import Protocol

__all__ = ["PtyHost", "StreamDevice"]

_SPEEDS = {getattr(termios, f"B{r}"): r for r in (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)}


class StreamDevice(Protocol):
    """What a simulated byte-stream device implements."""

    def feed(self, data: bytes, link: PtyHost) -> None: ...

    def on_hangup(self) -> None: ...

    def tick(self, link: PtyHost) -> None: ...


class PtyHost:
    """A pty pair with a device behind the master end. ``path`` is the slave's device path."""

    def __init__(self, device: StreamDevice) -> None:
        self.device = device
        self.master, slave = pty.openpty()
        tty.setraw(slave)
        self.path = os.ttyname(slave)
        os.close(slave)
        self._stop = threading.Event()
        self._wake_r, self._wake_w = os.pipe()
        self._write_lock = threading.Lock()
        self._holder: int | None = None
        self.unplugged = False
        self._thread = threading.Thread(target=self._run, name=f"pty-sim {self.path}", daemon=True)

    def start(self) -> PtyHost:
        """Start serving; returns self."""
        self._thread.start()
        return self

    def __enter__(self) -> PtyHost:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def baudrate(self) -> int:
        """The line speed the driver set on the slave (0 when unknown)."""
        try:
            return _SPEEDS.get(termios.tcgetattr(self.master)[4], 0)
        except (termios.error, OSError):
            return 0

    def send(self, data: bytes) -> None:
        """Write *data* towards the driver (dropped once unplugged)."""
        with self._write_lock:
            if self.unplugged:
                return
            view = memoryview(data)
            while view:
                try:
                    n = os.write(self.master, view)
                except BlockingIOError:
                    time.sleep(0.001)
                    continue
                except OSError:
                    return
                view = view[n:]

    def hold_port(self) -> None:
        """Fault 'port-held': open the slave and take the same exclusive flock pyserial takes."""
        fd = os.open(self.path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        self._holder = fd

    def unplug(self) -> None:
        """Close the master: the device is gone for good."""
        with self._write_lock:
            if not self.unplugged:
                self.unplugged = True
                os.close(self.master)
        os.write(self._wake_w, b"x")

    def close(self) -> None:
        """Stop the thread and close the pty (idempotent)."""
        if self._stop.is_set():
            return
        self._stop.set()
        os.write(self._wake_w, b"x")
        if self._thread.is_alive():
            self._thread.join(2.0)
        self.unplug() if not self.unplugged else None
        for fd in (self._wake_r, self._wake_w, self._holder):
            if fd is not None:
                os.close(fd)

    def _run(self) -> None:
        hung_up = False
        while not self._stop.is_set() and not self.unplugged:
            try:
                ready = select.select([self.master, self._wake_r], [], [], 0.01)[0]
            except (OSError, ValueError):
                return
            if self._wake_r in ready:
                os.read(self._wake_r, 64)
                continue
            if not ready:
                self.device.tick(self)
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError as exc:
                if exc.errno != errno.EIO:
                    return
                if not hung_up:  # no slave open: the driver closed the port
                    hung_up = True
                    self.device.on_hangup()
                time.sleep(0.002)
                continue
            hung_up = False
            if data:
                self.device.feed(data, self)
