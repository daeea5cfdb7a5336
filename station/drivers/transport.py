"""Transports: move bytes (serial, USB bulk) or reports (HID) and nothing else.

Every transport wraps its library's exceptions in :mod:`station.drivers.errors`, so the protocol layer
above sees one error set whichever library runs underneath (seabreeze ``transport.py`` pattern,
research note aesthetics.md §3). A transport is opened by at most one owner: in this process a
registry refuses a second open of the same address (:class:`DeviceInUse`); across processes the serial
transport takes pyserial's exclusive ``flock`` and the USB transport claims the interface (EBUSY).

Timeouts are in seconds (``float``) at this layer; hidapi and pyusb take milliseconds underneath.
"""

from __future__ import annotations

import errno
import select
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import Any

from station.drivers.errors import (
    CommunicationError,
    DeviceInUse,
    DeviceTimeout,
    Disconnected,
    DriverError,
    DriverInputError,
)
from station.drivers.exchange_log import log_wire

__all__ = [
    "HidTransport",
    "ReportTransport",
    "SerialTransport",
    "StreamTransport",
    "Transport",
    "UsbTransport",
]

_OWNERS: set[str] = set()
_OWNERS_LOCK = threading.Lock()


def _claim(address: str) -> None:
    with _OWNERS_LOCK:
        if address in _OWNERS:
            raise DeviceInUse(f"{address} is already open in this process")
        _OWNERS.add(address)


def _release(address: str) -> None:
    with _OWNERS_LOCK:
        _OWNERS.discard(address)


class Transport(ABC):
    """Common life cycle: ``open`` / ``close`` / context manager, one owner per address."""

    def __init__(self, address: str) -> None:
        self.address = address
        self._owned = False

    def open(self) -> None:
        """Open the device; raise :class:`DeviceInUse` if this process already holds it."""
        if self._owned:
            return
        _claim(self.address)
        self._owned = True
        try:
            self._open()
        except BaseException:
            self._owned = False
            _release(self.address)
            raise

    def close(self) -> None:
        """Close the device (idempotent) and release the ownership claim."""
        if not self._owned:
            return
        try:
            self._close()
        finally:
            self._owned = False
            _release(self.address)

    def reopen(self, settle_s: float = 0.05) -> None:
        """Close, wait *settle_s* seconds for the device to notice, open again.

        The ownership claim is kept while the device reopens; when the open fails the claim is
        released (the transport is then closed), so a later :meth:`open` — by this transport or by
        another on the same address — starts afresh instead of meeting :class:`DeviceInUse`.
        """
        try:
            self._close()
        except CommunicationError:
            pass
        time.sleep(settle_s)
        try:
            self._open()
        except BaseException:
            if self._owned:
                self._owned = False
                _release(self.address)
            raise

    @property
    def is_open(self) -> bool:
        """Whether the transport is open."""
        return self._owned

    def __enter__(self) -> Transport:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @abstractmethod
    def _open(self) -> None: ...

    @abstractmethod
    def _close(self) -> None: ...


class StreamTransport(Transport):
    """A byte stream: ``write`` everything, ``read`` up to *size* within a timeout."""

    @abstractmethod
    def write(self, data: bytes, timeout_s: float = 1.0) -> None:
        """Write all of *data* or raise."""

    @abstractmethod
    def read(self, size: int, timeout_s: float) -> bytes:
        """Read between 1 and *size* bytes; return ``b""`` if none arrived within *timeout_s*."""

    def flush_input(self) -> None:
        """Discard whatever is waiting in the input buffer."""
        while self.read(4096, 0.0):
            pass

    def read_exact(self, size: int, timeout_s: float) -> bytes:
        """Read exactly *size* bytes; :class:`DeviceTimeout` (with the partial count) otherwise."""
        deadline = time.monotonic() + timeout_s
        buf = bytearray()
        while len(buf) < size:
            chunk = self.read(size - len(buf), max(0.0, deadline - time.monotonic()))
            if chunk:
                buf += chunk
            elif time.monotonic() >= deadline:
                raise DeviceTimeout(f"{self.address}: {len(buf)} of {size} bytes within {timeout_s:g} s")
        return bytes(buf)

    def read_until(self, terminator: bytes, timeout_s: float, max_bytes: int = 1 << 16) -> bytes:
        """Read through *terminator* (included); :class:`DeviceTimeout` if it does not come in time."""
        deadline = time.monotonic() + timeout_s
        buf = bytearray()
        while not buf.endswith(terminator):
            if len(buf) > max_bytes:
                raise DeviceTimeout(f"{self.address}: no terminator within {max_bytes} bytes")
            chunk = self.read(1 if len(buf) < len(terminator) else 4096, 0.0)
            if not chunk:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise DeviceTimeout(
                        f"{self.address}: reply incomplete after {timeout_s:g} s ({len(buf)} bytes)"
                    )
                chunk = self.read(1, left)
            buf += chunk
        return bytes(buf)


_GONE = ("readiness to read but returned no data", "Errno 5]", "Input/output error", "No such file")


def _serial_error(address: str, exc: Exception) -> CommunicationError:
    text = str(exc)
    if "exclusively lock" in text or getattr(exc, "errno", None) in (errno.EBUSY, errno.EAGAIN):
        return DeviceInUse(f"{address}: held by another process ({text})")
    if any(t in text for t in _GONE) or getattr(exc, "errno", None) in (
        errno.EIO,
        errno.ENXIO,
        errno.ENODEV,
        errno.ENOENT,
    ):
        return Disconnected(f"{address}: disconnected ({text})")
    if getattr(exc, "errno", None) == errno.EACCES:
        return CommunicationError(f"{address}: permission denied; see docs/udev.md ({text})")
    return CommunicationError(f"{address}: {text}")


_SERIAL_URL_SCHEMES = ("socket://", "rfc2217://")


class SerialTransport(StreamTransport):
    """pyserial: a device path (``/dev/ttyACM0``, a pty) or a URL (``socket://``, ``rfc2217://``).

    Paths are opened with ``exclusive=True`` (an advisory ``flock``), so a second process gets
    :class:`DeviceInUse` instead of stealing half the replies.
    """

    def __init__(self, port: str, baudrate: int = 9600) -> None:
        super().__init__(port)
        self.baudrate = baudrate
        self._ser: Any = None

    def _open(self) -> None:
        import serial

        is_url = "://" in self.address
        if is_url and not self.address.startswith(_SERIAL_URL_SCHEMES):
            # pyserial's other handlers (spy:// writes a trace to any file, loop://, hwgrep://, alt://)
            # are no instrument transport; never hand them to serial_for_url.
            raise DriverInputError(
                "address", "a serial device path, socket://HOST:PORT or rfc2217://HOST:PORT"
            )
        try:
            ser = serial.serial_for_url(self.address, do_not_open=True, baudrate=self.baudrate, timeout=0)
            if not is_url:
                ser.exclusive = True
            ser.open()
        except (serial.SerialException, OSError, ValueError) as exc:
            raise _serial_error(self.address, exc) from exc
        self._ser = ser

    def _close(self) -> None:
        ser, self._ser = self._ser, None
        if ser is not None:
            try:
                ser.close()
            except Exception as exc:  # pyserial raises bare OSError on a vanished pty
                raise _serial_error(self.address, exc) from exc

    def _port(self) -> Any:
        if self._ser is None:
            raise CommunicationError(f"{self.address}: not open")
        return self._ser

    def set_baudrate(self, baudrate: int) -> None:
        """Change the host side's baud rate (the device is told with its own command first)."""
        try:
            self._port().baudrate = baudrate
        except Exception as exc:
            raise _serial_error(self.address, exc) from exc
        self.baudrate = baudrate

    def write(self, data: bytes, timeout_s: float = 1.0) -> None:
        ser = self._port()
        try:
            if hasattr(ser, "fd") and ser.write_timeout != timeout_s:
                ser.write_timeout = timeout_s
            log_wire(self.address, "tx", data)
            ser.write(data)
            ser.flush()
        except Exception as exc:
            if type(exc).__name__ == "SerialTimeoutException":
                raise DeviceTimeout(f"{self.address}: write timed out") from exc
            raise _serial_error(self.address, exc) from exc

    def read(self, size: int, timeout_s: float) -> bytes:
        ser = self._port()
        try:
            fd = ser.fileno() if hasattr(ser, "fd") else None
            if fd is not None:  # a local tty: wait with select, pyserial reads without reconfiguring
                if not ser.in_waiting and not select.select([fd], [], [], timeout_s)[0]:
                    return b""
                got = bytes(ser.read(max(1, min(size, ser.in_waiting))))
            else:
                if ser.timeout != timeout_s:  # URL handlers: each timeout change is cheap there
                    ser.timeout = timeout_s
                waiting = ser.in_waiting
                got = bytes(ser.read(min(size, waiting) if waiting else 1))
        except Exception as exc:
            raise _serial_error(self.address, exc) from exc
        log_wire(self.address, "rx", got)
        return got


def _usb_error(address: str, exc: Exception) -> CommunicationError:
    code = getattr(exc, "errno", None)
    if code == errno.EBUSY:
        return DeviceInUse(f"{address}: interface claimed by another process ({exc})")
    if code in (errno.ENODEV, errno.ENOENT, errno.EPIPE, errno.EIO):
        return Disconnected(f"{address}: disconnected ({exc})")
    if code == errno.EACCES:
        return CommunicationError(f"{address}: permission denied; see docs/udev.md ({exc})")
    return CommunicationError(f"{address}: {exc}")


class UsbTransport(StreamTransport):
    """pyusb bulk endpoints (``ep_out`` / ``ep_in``) of the first device matching VID:PID[:serial].

    *backend* is a ``usb.backend.IBackend``; ``None`` lets pyusb pick libusb. Bulk packets are buffered
    so the protocol above can read a frame in any slices.
    """

    def __init__(
        self,
        vid: int,
        pid: int,
        serial_number: str | None = None,
        backend: Any = None,
        ep_out: int = 0x01,
        ep_in: int = 0x81,
        interface: int = 0,
    ) -> None:
        super().__init__(f"usb:{vid:04x}:{pid:04x}" + (f":{serial_number}" if serial_number else ""))
        self.vid, self.pid, self.serial_number = vid, pid, serial_number
        self.backend, self.ep_out, self.ep_in, self.interface = backend, ep_out, ep_in, interface
        self._dev: Any = None
        self._rx = bytearray()
        self._packet = 64

    def _open(self) -> None:
        import usb.core
        import usb.util

        def match(dev: Any) -> bool:
            if self.serial_number is None:
                return True
            try:
                return usb.util.get_string(dev, dev.iSerialNumber) == self.serial_number
            except (usb.core.USBError, ValueError):
                return False

        try:
            dev = usb.core.find(
                idVendor=self.vid, idProduct=self.pid, backend=self.backend, custom_match=match
            )
        except usb.core.NoBackendError as exc:
            raise CommunicationError(f"{self.address}: no libusb backend available") from exc
        if dev is None:
            raise Disconnected(f"{self.address}: no such USB device")
        try:
            dev.set_configuration()
            usb.util.claim_interface(dev, self.interface)
            ep = usb.util.find_descriptor(
                dev.get_active_configuration()[(self.interface, 0)], bEndpointAddress=self.ep_in
            )
            self._packet = int(ep.wMaxPacketSize) if ep is not None else 64
        except usb.core.USBError as exc:
            usb.util.dispose_resources(dev)
            raise _usb_error(self.address, exc) from exc
        self._dev = dev
        self._rx.clear()

    def _close(self) -> None:
        import usb.core
        import usb.util

        dev, self._dev = self._dev, None
        if dev is not None:
            try:
                usb.util.release_interface(dev, self.interface)
            except usb.core.USBError:
                pass
            usb.util.dispose_resources(dev)

    def write(self, data: bytes, timeout_s: float = 1.0) -> None:
        import usb.core

        if self._dev is None:
            raise CommunicationError(f"{self.address}: not open")
        log_wire(self.address, "tx", data)
        try:
            n = self._dev.write(self.ep_out, data, max(1, int(timeout_s * 1000)))
        except usb.core.USBTimeoutError as exc:
            raise DeviceTimeout(f"{self.address}: bulk write timed out") from exc
        except usb.core.USBError as exc:
            raise _usb_error(self.address, exc) from exc
        if n != len(data):
            raise CommunicationError(f"{self.address}: wrote {n} of {len(data)} bytes")

    def read(self, size: int, timeout_s: float) -> bytes:
        import usb.core

        if self._dev is None:
            raise CommunicationError(f"{self.address}: not open")
        if not self._rx:
            try:
                self._rx += bytes(self._dev.read(self.ep_in, self._packet, max(1, int(timeout_s * 1000))))
            except usb.core.USBTimeoutError:
                return b""
            except usb.core.USBError as exc:
                raise _usb_error(self.address, exc) from exc
        out = bytes(self._rx[:size])
        del self._rx[:size]
        log_wire(self.address, "rx", out)
        return out

    def flush_input(self) -> None:
        self._rx.clear()
        while self.read(self._packet, 0.001):
            self._rx.clear()


class ReportTransport(Transport):
    """A report channel (HID): output/input reports and feature reports, hidapi semantics."""

    @abstractmethod
    def write_report(self, report: bytes) -> None:
        """Send an output report (first byte = report id)."""

    @abstractmethod
    def read_report(self, size: int, timeout_s: float) -> bytes:
        """Return one input report, or ``b""`` on timeout (hidapi's 0)."""

    @abstractmethod
    def get_feature(self, report_id: int, size: int) -> bytes:
        """Return a feature report (first byte = report id)."""

    @abstractmethod
    def send_feature(self, report: bytes) -> None:
        """Send a feature report (first byte = report id)."""


HidFactory = Callable[[], Any]
HidEnumerate = Callable[[int, int], Sequence[dict[str, Any]]]


def _default_hid_factory() -> Any:
    import hid

    return hid.device()


def _default_hid_enumerate(vid: int = 0, pid: int = 0) -> Sequence[dict[str, Any]]:
    import hid

    return hid.enumerate(vid, pid)


class HidTransport(ReportTransport):
    """hidapi (``hid.device``): ``read`` returns ``[]`` on timeout and raises ``OSError`` on error.

    hidapi does not tell a disconnect from other errors (signal11/hidapi#171), so after an error the
    transport looks the path up again with ``hid.enumerate``: gone means :class:`Disconnected`.
    *device_factory* and *enumerate_fn* default to hidapi's; the simulator and the HID-over-pty bridge
    pass their own objects with the same call signatures.
    """

    def __init__(
        self,
        path: bytes,
        device_factory: HidFactory | None = None,
        enumerate_fn: HidEnumerate | None = None,
        address: str | None = None,
    ) -> None:
        super().__init__(address or f"hid:{path.decode(errors='replace')}")
        self.path = path
        self._factory = device_factory or _default_hid_factory
        self._enumerate = enumerate_fn or _default_hid_enumerate
        self._dev: Any = None

    def _open(self) -> None:
        dev = self._factory()
        try:
            dev.open_path(self.path)
        except BaseException as exc:
            try:  # hidapi keeps the handle of a half-done open until closed; so does a bridge
                dev.close()
            except (OSError, CommunicationError, DeviceTimeout):
                pass
            if isinstance(exc, OSError) and not isinstance(exc, DriverError):  # ours pass as they are
                raise self._error("open", exc) from exc
            raise
        self._dev = dev

    def _close(self) -> None:
        dev, self._dev = self._dev, None
        if dev is not None:
            dev.close()

    def _present(self) -> bool:
        try:
            return any(d.get("path") == self.path for d in self._enumerate(0, 0))
        except OSError:
            return False

    def _error(self, what: str, exc: BaseException | None = None) -> CommunicationError:
        if not self._present():
            return Disconnected(f"{self.address}: {what} failed, device no longer enumerated")
        if exc is not None and "busy" in str(exc).lower():
            return DeviceInUse(f"{self.address}: {what} failed ({exc})")
        return CommunicationError(f"{self.address}: {what} failed ({exc or 'hidapi returned -1'})")

    def _device(self) -> Any:
        if self._dev is None:
            raise CommunicationError(f"{self.address}: not open")
        return self._dev

    def write_report(self, report: bytes) -> None:
        log_wire(self.address, "tx", report)
        try:
            n = self._device().write(report)
        except DriverError:  # a bridge's own typed error (also an OSError) passes as it is
            raise
        except OSError as exc:
            raise self._error("write", exc) from exc
        if n < 0:
            raise self._error("write")

    def read_report(self, size: int, timeout_s: float) -> bytes:
        try:
            data = bytes(self._device().read(size, max(1, int(timeout_s * 1000))))
        except DriverError:  # a bridge's own typed error (also an OSError) passes as it is
            raise
        except OSError as exc:
            raise self._error("read", exc) from exc
        log_wire(self.address, "rx", data)
        return data

    def get_feature(self, report_id: int, size: int) -> bytes:
        try:
            data = self._device().get_feature_report(report_id, size)
        except DriverError:  # a bridge's own typed error (also an OSError) passes as it is
            raise
        except OSError as exc:
            raise self._error("get_feature_report", exc) from exc
        if not data:
            raise DeviceTimeout(f"{self.address}: feature report {report_id} timed out")
        return bytes(data)

    def send_feature(self, report: bytes) -> None:
        try:
            n = self._device().send_feature_report(report)
        except DriverError:  # a bridge's own typed error (also an OSError) passes as it is
            raise
        except OSError as exc:
            raise self._error("send_feature_report", exc) from exc
        if n < 0:
            raise self._error("send_feature_report")


def parse_usb_id(text: str) -> tuple[int, int, str | None]:
    """Parse ``VID:PID[:SERIAL]`` (hex) into integers; :class:`DriverInputError` on bad input."""
    parts = text.split(":", 2)
    try:
        vid, pid = int(parts[0], 16), int(parts[1], 16)
    except (ValueError, IndexError) as exc:
        raise DriverInputError("address", "usb:VID:PID[:SERIAL] with hex ids", text) from exc
    if not (0 <= vid <= 0xFFFF and 0 <= pid <= 0xFFFF):
        raise DriverInputError("address", "VID and PID in 0000..ffff", text)
    return vid, pid, (parts[2] if len(parts) > 2 and parts[2] else None)
