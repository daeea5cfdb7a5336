"""Instrument base: one owner, a call lock, retries, context manager and async wrappers.

The service calls drivers from its event loop through the ``a*`` coroutines, which run the blocking
call in a worker thread (``asyncio.to_thread``) under the instrument's lock, so two requests never
interleave bytes on one device and the loop never blocks on I/O.

:class:`Instrument` is generic over its transport type: a family declares the transport it speaks
over (``class MA6Spectro(Instrument[StreamTransport])``), so ``self.transport`` is typed as that
transport in the family's code, and construction refuses another kind of transport with a
:class:`~station.drivers.errors.DriverInputError` naming the accepted class.
"""

from __future__ import annotations

import asyncio
import threading
from abc import ABC, abstractmethod
from typing import Any, ClassVar, Generic, Self, TypeVar, get_args, get_origin

from station.drivers.errors import DriverInputError
from station.drivers.readings import CalibrationResult, CalibrationStatus, InstrumentInfo
from station.drivers.transport import Transport

__all__ = ["Instrument", "TransportT"]

TransportT = TypeVar("TransportT", bound=Transport)


class Instrument(ABC, Generic[TransportT]):
    """A typed instrument over one transport of type *TransportT*; subclasses implement the family's
    protocol and name their transport type as the class parameter."""

    family: str = ""
    kind: str = "spectro"  # "spectro" or "gloss"
    #: The transport class a family accepts (its class parameter; Transport when none was given).
    transport_type: ClassVar[type] = Transport

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        for base in cls.__dict__.get("__orig_bases__", ()):
            if get_origin(base) is Instrument:
                (arg,) = get_args(base)
                if isinstance(arg, type) and issubclass(arg, Transport):
                    cls.transport_type = arg

    def __init__(self, transport: TransportT) -> None:
        if not isinstance(transport, self.transport_type):
            raise DriverInputError(
                "transport",
                f"a {self.transport_type.__name__} for {self.family or 'this instrument'}",
                type(transport).__name__,
            )
        self.transport: TransportT = transport
        self._lock = threading.RLock()

    @property
    def address(self) -> str:
        """Transport address this instrument was opened on."""
        return self.transport.address

    def open(self) -> Self:
        """Open the transport and bring the link up (baud negotiation, identify)."""
        with self._lock:
            self.transport.open()
            try:
                self._connect()
            except BaseException:
                self.transport.close()
                raise
        return self

    def close(self) -> None:
        """Close the transport (idempotent)."""
        with self._lock:
            self.transport.close()

    def __enter__(self) -> Self:
        if not self.transport.is_open:
            self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _connect(self) -> None:
        """Bring the link up once the transport is open; default: nothing."""
        return None

    @abstractmethod
    def identify(self) -> InstrumentInfo:
        """Get model, serial number, firmware and geometries."""

    @abstractmethod
    def status(self) -> CalibrationStatus:
        """Get the calibration state."""

    @abstractmethod
    def calibrate(self) -> CalibrationResult:
        """Run the full calibration sequence (zero, white/standard, verification)."""

    @abstractmethod
    def measure(self) -> Any:
        """Measure once and return a typed reading."""

    async def aidentify(self) -> InstrumentInfo:
        """Async :meth:`identify` (worker thread)."""
        return await asyncio.to_thread(self.identify)

    async def astatus(self) -> CalibrationStatus:
        """Async :meth:`status` (worker thread)."""
        return await asyncio.to_thread(self.status)

    async def acalibrate(self) -> CalibrationResult:
        """Async :meth:`calibrate` (worker thread)."""
        return await asyncio.to_thread(self.calibrate)

    async def ameasure(self) -> Any:
        """Async :meth:`measure` (worker thread)."""
        return await asyncio.to_thread(self.measure)

    async def aclose(self) -> None:
        """Async :meth:`close`."""
        await asyncio.to_thread(self.close)
