"""ASCII prompt protocol (family 1, after the X-Rite DTP41 serial protocol; docs/protocols/ma6-ascii.md).

A command is ASCII text ending in CR. A reply is zero or more ``KEY=VALUE`` lines ending in CR LF,
then the status ``<NNN>`` (three decimal digits; 000 = OK, 001 = OK with warning), CR LF and the
prompt ``>``::

    host:   b"ID\\r"
    device: b"MODEL=MA6\\r\\nSERIAL=600123\\r\\nFW=1.4.2\\r\\nGEOM=45as-15,...\\r\\n<000>\\r\\n>"

On a device error the host sends ``CE`` (clear error) and raises the typed error for the code. A
timeout or a garbled reply is retried after resynchronising (flush, bare CR until a prompt comes back);
if every retry fails the port is reopened once (a device that hangs after a long run recovers on
reconnect); then :class:`DeviceTimeout` / :class:`ProtocolError` is raised. Worst-case time of one
query is ``(retries + 2) * (timeout_s + resync_timeout_s)``.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass

from station.drivers.errors import (
    OK_CODES,
    CommunicationError,
    DeviceTimeout,
    Disconnected,
    ProtocolError,
    error_for_code,
)
from station.drivers.exchange_log import ExchangeLog
from station.drivers.transport import SerialTransport, StreamTransport

__all__ = ["BAUD_RATES", "PROMPT", "AsciiPromptProtocol", "AsciiReply", "checksum16"]

PROMPT = b"\r\n>"
OK_PROMPT = b"<000>\r\n>"
BAUD_RATES = (9600, 19200, 38400, 57600, 115200)
_REPLY = re.compile(rb"^((?:[^\r\n<>]*\r\n)*)<(\d{3})>\r\n>$")


def checksum16(data: bytes) -> int:
    """Return the 16-bit byte sum of *data* (the ``CS=`` line of data replies)."""
    return sum(data) & 0xFFFF


@dataclass(frozen=True)
class AsciiReply:
    """A parsed reply: its ``KEY=VALUE`` lines in order, the status code and the raw bytes."""

    lines: tuple[str, ...]
    code: int
    raw: bytes

    def fields(self) -> dict[str, str]:
        """Return the ``KEY=VALUE`` lines as a dict (later keys win)."""
        out: dict[str, str] = {}
        for line in self.lines:
            key, sep, value = line.partition("=")
            if not sep:
                raise ProtocolError(f"reply line without '=': {line!r}")
            out[key] = value
        return out


def parse_reply(raw: bytes) -> AsciiReply:
    """Parse one complete reply (through the prompt); :class:`ProtocolError` if it is malformed."""
    m = _REPLY.match(raw)
    if m is None:
        raise ProtocolError(f"malformed reply {raw[:60]!r}")
    body = m.group(1)
    try:
        lines = tuple(body.decode("ascii").split("\r\n")[:-1]) if body else ()
    except UnicodeDecodeError as exc:
        raise ProtocolError(f"non-ASCII reply {raw[:60]!r}") from exc
    return AsciiReply(lines, int(m.group(2)), raw)


class AsciiPromptProtocol:
    """Command/response over a :class:`StreamTransport` with bounded retries and resync.

    Timeouts in seconds. ``log`` keeps the last exchanges as ``(sent, received)`` byte pairs.
    """

    def __init__(
        self,
        transport: StreamTransport,
        timeout_s: float = 1.5,
        retries: int = 2,
        resync_timeout_s: float = 0.2,
        baudrate: int = 115200,
        quiet_s: float = 0.05,
    ) -> None:
        self.transport = transport
        self.quiet_s = quiet_s
        self.timeout_s = timeout_s
        self.retries = retries
        self.resync_timeout_s = resync_timeout_s
        self.baudrate = baudrate
        self.log = ExchangeLog("ma6", transport.address)

    # -- link --------------------------------------------------------------------------------------
    def negotiate_baud(self) -> int:
        """Find the device's rate (target first, then each of ``BAUD_RATES``) and move it to the target.

        Needs a local tty or ``rfc2217://`` (a ``socket://`` link has no baud rate: skipped).
        Returns the rate in use.
        """
        t = self.transport
        if not isinstance(t, SerialTransport) or t.address.startswith("socket://"):
            return 0
        for rate in (self.baudrate, *[r for r in BAUD_RATES if r != self.baudrate]):
            t.set_baudrate(rate)
            if self._ping(self.resync_timeout_s):
                break
        else:
            raise CommunicationError(f"{t.address}: no prompt at any of {BAUD_RATES} baud")
        if rate != self.baudrate:
            self.query(f"{self.baudrate}BR")
            t.set_baudrate(self.baudrate)
            if not self._ping(self.timeout_s):
                raise CommunicationError(f"{t.address}: lost the device after switching to {self.baudrate}")
        return self.baudrate

    def _ping(self, timeout_s: float) -> bool:
        """Send a bare CR; true if exactly an OK prompt comes back."""
        t = self.transport
        t.flush_input()
        t.write(b"\r")
        try:
            raw = t.read_until(PROMPT, timeout_s)
        except DeviceTimeout:
            return False
        return raw.endswith(OK_PROMPT)

    def _drain(self, quiet_s: float) -> bool:
        """Discard input until the line has been quiet for *quiet_s*; true if nothing came at all."""
        silent = True
        while self.transport.read(4096, quiet_s):
            silent = False
        return silent

    def resync(self) -> bool:
        """Drain, then ping until one OK prompt comes back and the line stays quiet (3 rounds at most).

        The quiet check catches a late reply to an earlier command being taken for the ping's reply.
        """
        for _ in range(3):
            self._drain(self.quiet_s)
            if self._ping(self.resync_timeout_s) and self._drain(self.quiet_s):
                return True
        return False

    # -- commands ----------------------------------------------------------------------------------
    def exchange(self, command: str, timeout_s: float | None = None) -> AsciiReply:
        """Send one command and read one reply, no retry; raise the device's typed error if any."""
        data = command.encode("ascii") + b"\r"
        self.transport.flush_input()  # a stale (late) reply already here must not answer this command
        self.transport.write(data)
        raw = self.transport.read_until(PROMPT, self.timeout_s if timeout_s is None else timeout_s)
        reply = parse_reply(raw)
        self.log.record(data, raw, f"{command!r} -> code {reply.code}, {len(reply.lines)} lines")
        if reply.code not in OK_CODES:
            self._clear_error()
            raise error_for_code(reply.code)
        return reply

    def _clear_error(self) -> None:
        try:
            self.transport.write(b"CE\r")
            raw = self.transport.read_until(PROMPT, self.timeout_s)
            self.log.record(b"CE\r", raw, "'CE' (clear error)")
        except (DeviceTimeout, ProtocolError):
            self.resync()

    def query(self, command: str, timeout_s: float | None = None) -> AsciiReply:
        """Exchange with bounded retries, resync between tries and one reconnect at the end."""
        last: Exception | None = None
        for reconnect in (False, True):
            if reconnect:
                self.transport.reopen()
                self.resync()
            for _ in range(self.retries + 1):
                try:
                    return self.exchange(command, timeout_s)
                except (DeviceTimeout, ProtocolError) as exc:
                    last = exc
                    self.resync()
                except Disconnected:
                    raise
        if last is None:  # unreachable: the loops run at least once
            raise DeviceTimeout(f"{command!r}: no attempt made")
        raise type(last)(f"{command!r}: {last} (after {self.retries + 1} tries and a reconnect)")

    def poll(self, command: str, until: str, key: str, period_s: float, limit_s: float) -> AsciiReply:
        """Repeat *command* until field *key* equals *until*; :class:`DeviceTimeout` after *limit_s*."""
        deadline = time.monotonic() + limit_s
        while True:
            reply = self.query(command)
            if reply.fields().get(key) == until:
                return reply
            if time.monotonic() >= deadline:
                self._clear_error()
                raise DeviceTimeout(f"device still {key}={reply.fields().get(key)} after {limit_s:g} s")
            time.sleep(period_s)
