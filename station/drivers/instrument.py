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
from station.drivers.readings import (
    CalibrationResult,
    CalibrationStatus,
    CalibrationStepResult,
    InstrumentInfo,
)
from station.drivers.transport import Transport

__all__ = ["Instrument", "TransportT", "combine_steps"]

TransportT = TypeVar("TransportT", bound=Transport)


class Instrument(ABC, Generic[TransportT]):
    """A typed instrument over one transport of type *TransportT*; subclasses implement the family's
    protocol and name their transport type as the class parameter."""

    family: str = ""
    kind: str = "spectro"  # "spectro" or "gloss"
    #: The transport class a family accepts (its class parameter; Transport when none was given).
    transport_type: ClassVar[type] = Transport
    #: The calibration steps in the order the instrument reads its references (black trap, white
    #: tile, verification tile; a gloss meter: its gloss standard).
    calibration_steps: ClassVar[tuple[str, ...]] = ("zero", "white", "verify")

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
    def calibrate_step(self, step: str) -> CalibrationStepResult:
        """Run one step of :attr:`calibration_steps` (the instrument's own command for that step)."""

    def check_step(self, step: str) -> None:
        """Refuse a step this family does not have (:class:`DriverInputError` naming ``step``)."""
        if step not in self.calibration_steps:
            raise DriverInputError("step", " | ".join(self.calibration_steps), step)

    def calibrate(self) -> CalibrationResult:
        """Run the whole sequence, :attr:`calibration_steps` in order, without pausing between them."""
        results = [self.calibrate_step(s) for s in self.calibration_steps]
        return combine_steps(results)

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


def combine_steps(results: list[CalibrationStepResult]) -> CalibrationResult:
    """One :class:`CalibrationResult` from the step results of a whole sequence, in order: the id of
    the last step that set one, the verification ΔE00 and expiry of the last that reported them."""
    cal_id = next((r.calibration_id for r in reversed(results) if r.calibration_id), "")
    de = next((r.verification_de for r in reversed(results) if r.verification_de is not None), None)
    expires = next((r.expires for r in reversed(results) if r.expires is not None), None)
    return CalibrationResult(
        cal_id, tuple(r.step for r in results), de, all(r.passed for r in results), expires
    )
