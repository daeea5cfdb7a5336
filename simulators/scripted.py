"""A scripted device for byte-exact protocol tests (PyMeasure ``expected_protocol`` spec format), served
on a real pty so pyserial and the driver's own framing run.

``pairs`` is an ordered list of ``(sent, reply)`` byte strings: ``sent`` is exactly what the driver
must write (terminator included), ``reply`` exactly what the device answers (``None`` = no reply).
Anything else written is recorded in ``unexpected``; ``leftover`` lists pairs never reached.
For framed binary protocols set ``frame_len`` to a callable giving a frame's length from its first
bytes (or ``None`` while too short to tell); otherwise commands end at ``terminator``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from simulators.pty_host import PtyHost

__all__ = ["ScriptedDevice"]


class ScriptedDevice:
    """Replays (sent, reply) pairs; records mismatches instead of raising in the host thread."""

    def __init__(
        self,
        pairs: Sequence[tuple[bytes, bytes | None]],
        terminator: bytes = b"\r",
        frame_len: Callable[[bytes], int | None] | None = None,
    ) -> None:
        self.pairs = list(pairs)
        self.terminator = terminator
        self.frame_len = frame_len
        self.buf = bytearray()
        self.unexpected: list[tuple[bytes, bytes]] = []
        self.hangups = 0

    @property
    def leftover(self) -> list[tuple[bytes, bytes | None]]:
        """Pairs the driver never sent."""
        return list(self.pairs)

    def _next_message(self) -> bytes | None:
        if self.frame_len is not None:
            n = self.frame_len(bytes(self.buf))
            if n is None or len(self.buf) < n:
                return None
        else:
            i = self.buf.find(self.terminator)
            if i < 0:
                return None
            n = i + len(self.terminator)
        msg = bytes(self.buf[:n])
        del self.buf[:n]
        return msg

    def feed(self, data: bytes, link: PtyHost) -> None:
        """Match each complete message against the next pair and send its reply."""
        self.buf += data
        while (msg := self._next_message()) is not None:
            if not self.pairs or self.pairs[0][0] != msg:
                self.unexpected.append((msg, self.pairs[0][0] if self.pairs else b""))
                continue
            _, reply = self.pairs.pop(0)
            if reply is not None:
                link.send(reply)

    def on_hangup(self) -> None:
        """Count reconnects."""
        self.hangups += 1

    def tick(self, link: PtyHost) -> None:
        """Nothing to do."""


class ScriptedFirmware:
    """:class:`ScriptedDevice` behind the pyusb simulator backend (``receive`` / ``pop_ready``)."""

    def __init__(
        self, pairs: Sequence[tuple[bytes, bytes | None]], frame_len: Callable[[bytes], int | None]
    ) -> None:
        self.device = ScriptedDevice(pairs, frame_len=frame_len)
        self.out = bytearray()
        self.unplugged = False

    def send(self, data: bytes) -> None:
        """The scripted reply (the device calls this as its link)."""
        self.out += data

    def receive(self, data: bytes) -> None:
        """Bytes from a bulk OUT transfer."""
        self.device.feed(data, self)  # type: ignore[arg-type]

    def wait_ready(self, timeout_s: float) -> bool:
        """Whether reply bytes are waiting (sleeps out the timeout when none will come)."""
        if not self.out:
            import time

            time.sleep(timeout_s)
        return bool(self.out)

    def pop_ready(self, max_bytes: int) -> bytes:
        """Up to *max_bytes* reply bytes."""
        data = bytes(self.out[:max_bytes])
        del self.out[:max_bytes]
        return data

    def on_hangup(self) -> None:
        """Count reconnects."""
        self.device.on_hangup()
