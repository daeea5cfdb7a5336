"""The simulator configuration: a frozen, validated value; bad settings name the field and the range."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simulators._cli import build_parser, config_from_args
from simulators.config import SimulatorConfig, SimulatorConfigError
from simulators.faults import FaultSpecError
from station.drivers import DriverInputError
from station.drivers.simproc import spawn_simulator
from station.errors import InputError


def test_command_line_becomes_the_config() -> None:
    argv = ["--design", "d.json", "--fault", "tilt", "--noise", "0.5", "--measure-time", "0.02", "--twelve"]
    config = config_from_args("ma6", build_parser("ma6").parse_args(argv))
    assert config == SimulatorConfig(
        kind="ma6", design=Path("d.json"), faults=("tilt",), noise=0.5, measure_time_s=0.02, twelve=True
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.noise = 2.0  # type: ignore[misc]
    assert config.fault_plan().active("tilt")
    assert config.fault_plan() is not config.fault_plan()  # each run arms its own plan


@pytest.mark.parametrize(
    ("changes", "field", "accepted"),
    [
        ({"kind": "ma9"}, "kind", "ma6 | ma3 | gloss"),
        ({"noise": -0.1}, "noise", "0 <= noise <= 100"),
        ({"noise": float("nan")}, "noise", "0 <= noise <= 100"),
        ({"bias": 11.0}, "bias", "0 <= bias <= 10"),
        ({"measure_time_s": 61.0}, "measure_time_s", "0 <= measure_time_s <= 60"),
        ({"kind": "ma3", "twelve": True}, "twelve", "only with the ma6 protocol"),
        ({"kind": "ma3", "protocol": "ma6"}, "kind", "a family served by simulators.ma6"),
        ({"design": Path("a"), "recipe": Path("b")}, "recipe", "either design or recipe, not both"),
        ({"serial": " "}, "serial", "a non-empty serial number or none"),
    ],
)
def test_bad_setting_names_field_and_range(changes: dict[str, object], field: str, accepted: str) -> None:
    settings: dict[str, object] = {"kind": "ma6", **changes}
    with pytest.raises(SimulatorConfigError) as info:
        SimulatorConfig(**settings)  # type: ignore[arg-type]
    assert isinstance(info.value, InputError)
    assert (info.value.field, info.value.accepted) == (field, accepted)


def test_bad_fault_spec_refused() -> None:
    with pytest.raises(FaultSpecError):
        SimulatorConfig(kind="ma3", faults=("meltdown",))


def test_out_of_range_setting_reaches_the_driver_as_input_error() -> None:
    """The child reports INPUT-ERROR for a setting out of range; spawn_simulator re-raises it typed."""
    with pytest.raises(DriverInputError) as info:
        spawn_simulator("ma3", extra_args=["--noise", "-1"])
    assert info.value.field == "noise"
