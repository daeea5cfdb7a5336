"""Family 1: 6-angle spectrophotometer (45° illumination at −15/15/25/45/75/110 aspecular, optionally a
second 15°-illumination block) on USB-CDC serial with the ASCII prompt protocol.

Commands (docs/protocols/ma6-ascii.md): ``ID`` identify, ``ST`` status, ``ZC`` / ``WC`` / ``VC`` zero,
white and verification calibration, ``MS`` start a measurement, ``PO`` poll, ``RD`` read the data,
``CE`` clear error, ``<rate>BR`` baud. Data lines carry reflectance factors (not %) at 400–700 nm in
10 nm steps and a ``CS=`` 16-bit byte sum over the data lines; a mismatch rejects the reading and the
data is read again (the instrument keeps it until the next ``MS``).
"""

from __future__ import annotations

import datetime as dt
import math

import numpy as np

from station.drivers.ascii_protocol import AsciiPromptProtocol, AsciiReply, checksum16
from station.drivers.errors import Misread, ProtocolError, UnexpectedReply
from station.drivers.instrument import Instrument
from station.drivers.readings import (
    WAVELENGTHS_NM,
    CalibrationStatus,
    CalibrationStepResult,
    InstrumentInfo,
    SpectralReading,
    parse_geometry,
)
from station.drivers.transport import StreamTransport

__all__ = ["MA6Spectro", "parse_time"]

WARN_OUT_OF_RANGE = 0x10  # CM-MISDK warning bit "reflectance out of range"
R_MAX = 2.0  # reflectance factors above this are a misread (metallic highlights reach ~1.5)


def parse_time(text: str) -> dt.datetime:
    """Parse the instrument's ``YYYY-MM-DDTHH:MM:SSZ`` clock; :class:`ProtocolError` otherwise."""
    try:
        return dt.datetime.strptime(text, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=dt.UTC)
    except ValueError as exc:
        raise ProtocolError(f"bad time {text!r}") from exc


def _expiry(text: str) -> dt.datetime | None:
    return None if text in ("", "NONE") else parse_time(text)


class MA6Spectro(Instrument[StreamTransport]):
    """Multi-angle spectrophotometer speaking the ASCII prompt protocol.

    Parameters
    ----------
    transport
        A :class:`SerialTransport` (device path, pty, ``socket://`` or ``rfc2217://``).
    timeout_s
        Per-command reply timeout (s); calibration and data reads get ``4 ×`` this.
    measure_limit_s
        How long a measurement may stay busy before :class:`DeviceTimeout` (s).
    """

    family = "ma6"

    def __init__(
        self,
        transport: StreamTransport,
        timeout_s: float = 1.5,
        retries: int = 2,
        measure_limit_s: float = 10.0,
        poll_period_s: float = 0.005,
        baudrate: int = 115200,
    ) -> None:
        super().__init__(transport)
        self.protocol = AsciiPromptProtocol(transport, timeout_s, retries, min(0.2, timeout_s), baudrate)
        self.measure_limit_s = measure_limit_s
        self.poll_period_s = poll_period_s
        self.info: InstrumentInfo | None = None

    def _connect(self) -> None:
        self.protocol.negotiate_baud()
        self.info = self.identify()

    def identify(self) -> InstrumentInfo:
        """Get model, serial, firmware and geometry names (``ID``)."""
        with self._lock:
            f = self.protocol.query("ID").fields()
        try:
            geoms = tuple(f["GEOM"].split(","))
            for g in geoms:
                parse_geometry(g)
            return InstrumentInfo(f["MODEL"], f["SERIAL"], f["FW"], geoms)
        except (KeyError, ValueError) as exc:
            raise UnexpectedReply(f"ID reply lacks fields: {f}") from exc

    def status(self) -> CalibrationStatus:
        """Get the calibration state (``ST``): the next step needed, id, expiry, temperature."""
        with self._lock:
            f = self.protocol.query("ST").fields()
        try:
            needed = None if f["CAL"] == "OK" else f["CAL"].lower()
            return CalibrationStatus(needed, f["CALID"], _expiry(f["EXPIRES"]), float(f["TEMP"]))
        except (KeyError, ValueError) as exc:
            raise UnexpectedReply(f"ST reply lacks fields: {f}") from exc

    def calibrate_step(self, step: str) -> CalibrationStepResult:
        """One step: ``zero`` (``ZC``, black trap), ``white`` (``WC``, white tile; the new calibration
        id) or ``verify`` (``VC``, verification tile: ΔE00 against its certificate, expiry)."""
        self.check_step(step)
        with self._lock:
            slow = self.protocol.timeout_s * 4
            command = {"zero": "ZC", "white": "WC", "verify": "VC"}[step]
            f = self.protocol.query(command, slow).fields()
        if step == "zero":
            return CalibrationStepResult("zero")
        if step == "white":
            return CalibrationStepResult("white", calibration_id=f.get("CALID", ""))
        try:
            return CalibrationStepResult(
                "verify",
                verification_de=float(f["DE"]),
                passed=f["PASS"] == "1",
                expires=_expiry(f["EXPIRES"]),
            )
        except (KeyError, ValueError) as exc:
            raise UnexpectedReply(f"VC reply lacks fields: {f}") from exc

    def measure(self) -> SpectralReading:
        """Measure once: ``MS``, poll ``PO`` until idle, ``RD``; checksum and ranges checked."""
        with self._lock:
            p = self.protocol
            p.query("MS")
            p.poll("PO", "IDLE", "STATE", self.poll_period_s, self.measure_limit_s)
            last: ProtocolError | None = None
            for attempt in range(p.retries + 1):
                reply = p.query("RD", p.timeout_s * 4)
                try:
                    return self._parse_data(reply)
                except ProtocolError as exc:  # checksum or layout: read the held data again, after
                    last = exc  # draining a late reply (a busy host) and pinging the line back in step
                    if attempt < p.retries:
                        p.resync()
            raise ProtocolError(f"data rejected {p.retries + 1} times: {last}")

    def _parse_data(self, reply: AsciiReply) -> SpectralReading:
        lines = list(reply.lines)
        if not lines or not lines[-1].startswith("CS="):
            raise ProtocolError("data reply without CS= line")
        body = "".join(line + "\r\n" for line in lines[:-1]).encode("ascii")
        try:
            sent = int(lines[-1][3:], 16)
        except ValueError as exc:
            raise ProtocolError(f"bad checksum field {lines[-1]!r}") from exc
        if sent != checksum16(body):
            raise ProtocolError(f"checksum mismatch: sent {sent:04X}, computed {checksum16(body):04X}")
        f: dict[str, str] = {}
        geoms: list[str] = []
        rows: list[list[float]] = []
        for line in lines[:-1]:
            key, _, value = line.partition("=")
            if key.startswith("R") and "as" in key:
                geoms.append(key[1:])
                rows.append([float(v) for v in value.split(",")])
            else:
                f[key] = value
        expected = self.info.geometries if self.info else tuple(geoms)
        if tuple(geoms) != expected:
            raise UnexpectedReply(f"geometries {geoms} differ from the instrument's {list(expected)}")
        if any(len(r) != len(WAVELENGTHS_NM) for r in rows):
            raise ProtocolError("a spectrum does not have 31 bands")
        refl = np.asarray(rows, dtype=float)
        if int(f.get("WARN", "0") or "0", 16) & WARN_OUT_OF_RANGE:
            raise Misread("instrument flags the reflectance as out of range")
        if not np.all(np.isfinite(refl)) or refl.min() < 0.0 or refl.max() > R_MAX:
            raise Misread(f"reflectance outside [0, {R_MAX}]")
        try:
            temp = float(f["TEMP"])
            if not math.isfinite(temp):
                raise ValueError(temp)
            return SpectralReading(
                geometries=tuple(geoms),
                reflectance=refl,
                temperature_c=temp,
                serial=f["SN"],
                calibration_id=f["CALID"],
                time=parse_time(f["TIME"]),
                warnings=int(f["WARN"], 16),
                diagnosis=int(f["DIAG"], 16),
                model=self.info.model if self.info else "",
            )
        except (KeyError, ValueError) as exc:
            raise ProtocolError(f"data reply lacks fields: {sorted(f)}") from exc
