"""Expose a pty-served simulator behind an RFC 2217 server (or a raw TCP one for ``socket://``) (pyserial's ``PortManager``), for the
``rfc2217://host:port`` form of the serial transport (serial-over-LAN converters).

One client at a time; baud-rate changes requested by the client are applied to the pty, so the
simulator's baud negotiation works through the network too.
"""

from __future__ import annotations

import socket
import threading
from typing import Any

import serial
import serial.rfc2217

__all__ = ["Rfc2217Server"]


class Rfc2217Server:
    """Listen on 127.0.0.1:*port* (0 = any free port) and bridge clients to the pty at *path*."""

    def __init__(self, path: str, port: int = 0, raw: bool = False) -> None:
        self.path = path
        self.raw = raw
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind(("127.0.0.1", port))
        self._sock.listen(1)
        self.port = self._sock.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="rfc2217", daemon=True)

    @property
    def url(self) -> str:
        """The ``rfc2217://`` URL clients connect to."""
        return f"{'socket' if self.raw else 'rfc2217'}://127.0.0.1:{self.port}"

    def start(self) -> Rfc2217Server:
        """Start accepting clients."""
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop accepting and close the listening socket."""
        self._stop.set()
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self._sock.accept()
            except OSError:
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            try:
                self._bridge(conn)
            finally:
                conn.close()

    def _bridge(self, conn: socket.socket) -> None:
        ser = _PtySerial(self.path, timeout=0.05)
        manager: Any = (
            _Plain()
            if self.raw
            # types-pyserial types both arguments as rfc2217.Serial; PortManager takes any port and any writer
            else serial.rfc2217.PortManager(ser, _Writer(conn))  # type: ignore[arg-type]
        )
        done = threading.Event()

        def serial_to_net() -> None:
            while not done.is_set():
                try:
                    data = ser.read(ser.in_waiting or 1)
                except serial.SerialException:
                    break
                if data:
                    try:
                        conn.sendall(b"".join(manager.escape(data)))
                    except OSError:
                        break
            done.set()

        reader = threading.Thread(target=serial_to_net, daemon=True)
        reader.start()
        try:
            while not done.is_set():
                try:
                    data = conn.recv(4096)
                except OSError:
                    break
                if not data:
                    break
                ser.write(b"".join(manager.filter(data)))
        finally:
            done.set()
            reader.join(1.0)
            ser.close()


class _PtySerial(serial.Serial):
    """A pty has no modem lines (TIOCMGET fails): report CTS/DSR/CD up, RI down, ignore RTS/DTR."""

    @property
    def cts(self) -> bool:
        return True

    @property
    def dsr(self) -> bool:
        return True

    @property
    def ri(self) -> bool:
        return False

    @property
    def cd(self) -> bool:
        return True

    def _update_rts_state(self) -> None:
        return None

    def _update_dtr_state(self) -> None:
        return None

    def _update_break_state(self) -> None:
        return None


class _Plain:
    """Raw TCP (``socket://``): bytes pass unchanged, no telnet negotiation."""

    def escape(self, data: bytes) -> list[bytes]:
        return [data]

    def filter(self, data: bytes) -> list[bytes]:
        return [data]


class _Writer:
    """The ``write`` half PortManager needs for its telnet negotiation replies."""

    def __init__(self, conn: socket.socket) -> None:
        self._conn = conn

    def write(self, data: bytes) -> None:
        try:
            self._conn.sendall(data)
        except OSError:
            pass
