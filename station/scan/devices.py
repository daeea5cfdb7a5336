"""Connect: one open instrument and, for a ``sim:KIND`` device, the simulator subprocess behind it.

A device is typed as a person types it: ``sim:ma6`` / ``sim:ma3`` / ``sim:gloss`` (a simulator started
for it by :func:`station.drivers.simproc.spawn_simulator`) or an address that
:func:`station.drivers.open_instrument` accepts (``/dev/ttyACM0``, ``ma3@usb:1209:ca03``,
``gloss@hid:PATH`` …). The viewer, the CLI and the service's hub open instruments through
:func:`open_device`; a paired gloss meter through :func:`open_gloss_meter`, which refuses anything else.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from station.closing import Closing
from station.drivers import Instrument, open_instrument
from station.drivers.simproc import SIM_KINDS, SimulatorProcess, spawn_simulator
from station.scan.errors import ScanInputError

__all__ = ["SIM_DEVICES", "Device", "open_device", "open_gloss_meter"]

#: The simulator devices, ``sim:<kind>`` for each of :data:`station.drivers.simproc.SIM_KINDS`.
SIM_DEVICES = tuple(f"sim:{k}" for k in SIM_KINDS)
_ACCEPTED = " | ".join(SIM_DEVICES) + " or an address"


@dataclass
class Device(Closing):
    """An open instrument, the device as typed (``sim:ma6`` or an address) and its simulator, if any."""

    name: str
    instrument: Instrument[Any]
    simulator: SimulatorProcess | None = None

    @property
    def address(self) -> str:
        """The driver address the instrument was opened at (the pty of a simulator)."""
        return self.simulator.address if self.simulator is not None else self.name

    def close(self) -> None:
        """Close the instrument, then end the simulator (both even when the first fails)."""
        try:
            self.instrument.close()
        finally:
            if self.simulator is not None:
                self.simulator.close()


def open_device(
    device: str,
    *,
    timeout_s: float | None = None,
    design_file: Path | None = None,
    recipe_file: Path | None = None,
    faults: Sequence[str] = (),
    extra_args: Sequence[str] = (),
    field: str = "device",
) -> Device:
    """Open *device* (reply timeout *timeout_s*, seconds; the family's own without it); ``sim:KIND``
    starts its simulator first.

    *design_file*, *recipe_file*, *faults* and *extra_args* set up the simulated panel and are refused
    (:class:`ScanInputError` naming them) for a real address. Raises :class:`ScanInputError` naming
    *field* for an empty device or an unknown simulator kind, and what the driver raises when nothing
    answers; a simulator started here is ended on any failure.
    """
    name = device.strip()
    if not name:
        raise ScanInputError(field, _ACCEPTED, device)
    simulator: SimulatorProcess | None = None
    address = name
    if name.startswith("sim:"):
        kind = name.removeprefix("sim:")
        if kind not in SIM_KINDS:
            raise ScanInputError(field, _ACCEPTED, device)
        simulator = spawn_simulator(
            kind,
            None if design_file is None else design_file.resolve(),  # the child runs elsewhere
            faults,
            recipe_file=None if recipe_file is None else recipe_file.resolve(),
            extra_args=extra_args,
        )
        address = simulator.address
    elif design_file is not None or recipe_file is not None or faults or extra_args:
        raise ScanInputError("--design/--recipe/--fault/--twelve", "only with a sim:* device", device)
    try:
        options = {} if timeout_s is None else {"timeout_s": timeout_s}
        return Device(name, open_instrument(address, **options), simulator)
    except BaseException:
        if simulator is not None:
            simulator.close()
        raise


def open_gloss_meter(device: str, *, timeout_s: float | None = None, field: str = "gloss_device") -> Device:
    """Open *device* as the gloss meter paired with a spectrophotometer; anything that is not a gloss
    meter is closed and refused (:class:`ScanInputError` naming *field*)."""
    opened = open_device(device, timeout_s=timeout_s, field=field)
    if opened.instrument.kind != "gloss":
        opened.close()
        raise ScanInputError(field, "a gloss meter (e.g. sim:gloss)", device)
    return opened
