"""What a driver said to its instrument and what came back: kept for errors, logged at debug level.

Every protocol (ASCII, MA-T binary frames, HID reports) records each exchange here: the last
:data:`KEPT` pairs stay in memory for error reports, and each one goes to the logger
``station.drivers.<family>`` at ``DEBUG`` as hex and decoded text (the habit of PyMeasure and
ophyd-async). Nothing is formatted unless that level is enabled. Transports log the raw bytes of each
write and read on ``station.drivers.wire`` the same way.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Iterator

__all__ = ["KEPT", "ExchangeLog", "hex_ascii", "log_wire"]

#: Exchanges kept in memory per driver.
KEPT = 64
#: Bytes shown per frame in a log line; longer frames end with ``…(N bytes)``.
SHOWN_BYTES = 96

WIRE_LOGGER = "station.drivers.wire"


def hex_ascii(data: bytes, limit: int = SHOWN_BYTES) -> str:
    """``'52 44 0d |RD.|'``: the bytes in hex, then printable ASCII with ``.`` for the rest."""
    shown = data[:limit]
    text = "".join(chr(b) if 32 <= b < 127 else "." for b in shown)
    more = f" …({len(data)} bytes)" if len(data) > limit else ""
    return f"{shown.hex(' ')} |{text}|{more}"


def log_wire(address: str, direction: str, data: bytes) -> None:
    """Log one transport write (``direction="tx"``) or read (``"rx"``) of *data* at debug level."""
    logger = logging.getLogger(WIRE_LOGGER)
    if data and logger.isEnabledFor(logging.DEBUG):
        logger.debug("%s %s %s", address, direction, hex_ascii(data))


class ExchangeLog:
    """The last :data:`KEPT` ``(sent, received)`` byte pairs of one driver, each also logged.

    Iterating yields the pairs oldest first; ``len`` counts them."""

    def __init__(self, family: str, address: str = "") -> None:
        self.logger = logging.getLogger(f"station.drivers.{family}")
        self.address = address
        self._pairs: deque[tuple[bytes, bytes]] = deque(maxlen=KEPT)

    def record(self, sent: bytes, received: bytes, decoded: str = "") -> None:
        """Keep the pair and log it: hex and ASCII of both, then *decoded* (the protocol's reading)."""
        self._pairs.append((sent, received))
        if self.logger.isEnabledFor(logging.DEBUG):
            self.logger.debug(
                "%s sent %s; received %s%s",
                self.address or "?",
                hex_ascii(sent),
                hex_ascii(received),
                f"; {decoded}" if decoded else "",
            )

    def __iter__(self) -> Iterator[tuple[bytes, bytes]]:
        return iter(list(self._pairs))

    def __len__(self) -> int:
        return len(self._pairs)

    def __getitem__(self, index: int) -> tuple[bytes, bytes]:
        return self._pairs[index]
