"""The configuration of one simulated instrument: a frozen, validated value built from the command line.

:class:`SimulatorConfig` is what ``python -m simulators.{ma6,ma3,gloss}`` parses its arguments into
and what :mod:`simulators.serve` and the device factories read; nothing downstream sees an
``argparse.Namespace``. Construction checks every field and raises :class:`SimulatorConfigError`
(an :class:`~station.errors.InputError`: field, accepted range, value) for a bad one, and
:class:`~simulators.faults.FaultSpecError` for a fault spec that does not parse.

This module sits at the bottom of the simulator command line: it imports neither the command line
(:mod:`simulators._cli`) nor the server (:mod:`simulators.serve`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from simulators.faults import FaultPlan
from simulators.repeatability import MAX_RUN_INDEX, next_run_index
from station.drivers.families import SIM_DRIFT_SCALE_MAX, SIM_FAMILY_NAMES, family_named
from station.errors import InputError

if TYPE_CHECKING:
    from simulators.physics import SpectroPhysics
    from simulators.recipe import RecipePanel

__all__ = ["KINDS", "SimulatorConfig", "SimulatorConfigError", "spectro_physics"]

#: The families a simulator can be started for (:data:`station.drivers.families.FAMILIES`).
KINDS = SIM_FAMILY_NAMES
MAX_BIAS_SCALE = 10.0
MAX_NOISE_SCALE = 100.0
MAX_MEASURE_TIME_S = 60.0
MAX_DRIFT_SCALE = SIM_DRIFT_SCALE_MAX


class SimulatorConfigError(InputError):
    """A simulator setting outside its accepted range (names the field and the range)."""


def _check_scale(name: str, value: float, upper: float) -> float:
    v = float(value)
    if not math.isfinite(v) or not 0.0 <= v <= upper:
        raise SimulatorConfigError(name, f"0 <= {name} <= {upper:g}", value)
    return v


@dataclass(frozen=True)
class SimulatorConfig:
    """Everything a simulator process is started with.

    Attributes
    ----------
    kind
        The family served, one of :data:`KINDS`: the prefix of the address (``KIND@/dev/pts/N``).
    protocol
        The simulator module's own family (``ma6`` for :mod:`simulators.ma6`); empty: *kind*. The
        family *kind* must name this module as its simulator.
    design, recipe
        The virtual panel: a ``cacad.design/1`` file or a recipe file of the synthetic colorants, at
        most one of the two (neither: the built-in default panel).
    faults
        Fault specs ``NAME[@COMMAND][:N]`` armed at start (:mod:`simulators.faults`).
    serial
        Instrument serial number; ``None`` takes the family default.
    bias
        Inter-instrument bias scale, 0 (none) .. 10 (1 = typical), dimensionless.
    noise
        Noise scale, 0 .. 100 (1 = published repeatability), dimensionless.
    measure_time_s
        Seconds per measurement, 0 .. 60 s.
    cold
        Start cold (warm-up drift and temperature rise).
    seed
        Noise seed (a reproducible run); ``None`` combines the serial with fresh entropy, so two runs
        read the same panel differently (:func:`simulators.repeatability.run_seed`).
    run_index, state
        This run's index for the drift across runs (:mod:`simulators.repeatability`): ``run_index``
        given, or the counter kept in the file ``state`` (each start takes it and writes one more), at
        most one of the two; neither: run 0 (no drift).
    drift
        Scale of the stated drift across runs, 0 .. 100 (1 = stated, 0 = none), dimensionless.
    rfc2217, tcp
        Also serve the pty behind an RFC 2217 server, or on raw TCP (``socket://`` URL).
    twelve
        ma6 only: add the 15° illumination block.
    """

    kind: str
    protocol: str = ""
    design: Path | None = None
    recipe: Path | None = None
    faults: tuple[str, ...] = ()
    serial: str | None = None
    bias: float = 0.0
    noise: float = 1.0
    measure_time_s: float = 0.3
    cold: bool = False
    seed: int | None = None
    run_index: int | None = None
    state: Path | None = None
    drift: float = 1.0
    rfc2217: bool = False
    tcp: bool = False
    twelve: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise SimulatorConfigError("kind", " | ".join(KINDS), self.kind)
        protocol = self.protocol or self.kind
        family = family_named(self.kind)
        if family is None or family.simulator != f"simulators.{protocol}":
            raise SimulatorConfigError(
                "kind",
                f"a family served by simulators.{protocol}",
                None if family is None else family.simulator,
            )
        object.__setattr__(self, "protocol", protocol)
        if self.design is not None and self.recipe is not None:
            raise SimulatorConfigError("recipe", "either design or recipe, not both", str(self.recipe))
        if self.serial is not None and not self.serial.strip():
            raise SimulatorConfigError("serial", "a non-empty serial number or none", self.serial)
        object.__setattr__(self, "faults", tuple(self.faults))
        FaultPlan(self.faults)  # raises FaultSpecError for an unknown name or a malformed spec
        object.__setattr__(self, "bias", _check_scale("bias", self.bias, MAX_BIAS_SCALE))
        object.__setattr__(self, "noise", _check_scale("noise", self.noise, MAX_NOISE_SCALE))
        object.__setattr__(
            self, "measure_time_s", _check_scale("measure_time_s", self.measure_time_s, MAX_MEASURE_TIME_S)
        )
        object.__setattr__(self, "drift", _check_scale("drift", self.drift, MAX_DRIFT_SCALE))
        if self.run_index is not None:
            if self.state is not None:
                raise SimulatorConfigError("run_index", "either run_index or state, not both", self.run_index)
            if not 0 <= self.run_index <= MAX_RUN_INDEX:
                raise SimulatorConfigError("run_index", f"0 <= run_index <= {MAX_RUN_INDEX}", self.run_index)
        if self.twelve and self.protocol != "ma6":
            raise SimulatorConfigError("twelve", "only with the ma6 protocol", self.protocol)

    def fault_plan(self) -> FaultPlan:
        """A fresh plan with this configuration's faults armed (plans are consumed as faults fire)."""
        return FaultPlan(self.faults)


def spectro_physics(
    config: SimulatorConfig, default_serial: str, recipe: RecipePanel | None = None
) -> SpectroPhysics:
    """The spectrophotometer physics of *config*; *recipe* is the loaded ``config.recipe`` panel.

    With ``config.state`` this is a new run: the file's counter is read and advanced
    (:func:`simulators.repeatability.next_run_index`)."""
    from simulators.physics import DEFAULT_DESIGN, InstrumentCharacter, SpectroPhysics
    from station.model.design_io import load_design

    ch = InstrumentCharacter(serial=config.serial or default_serial, bias_scale=config.bias)
    ch.noise_band *= config.noise
    ch.noise_scale *= config.noise
    design = load_design(config.design) if config.design else DEFAULT_DESIGN
    run = config.run_index if config.state is None else next_run_index(config.state)
    return SpectroPhysics(
        design=design,
        character=ch,
        warm=not config.cold,
        seed=config.seed,
        recipe=recipe,
        run_index=run or 0,
        drift_scale=config.drift,
    )
