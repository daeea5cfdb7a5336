"""Command line shared by ``python -m simulators.{ma6,ma3,gloss}``.

Prints one line ``ADDRESS <family>@<where>`` on stdout as soon as the device is ready, then serves
until stdin reaches end of file (the parent died or closed the pipe) or SIGTERM/SIGINT.

The panel is ``--design FILE`` (face/flop/travel/gloss) or ``--recipe FILE`` (a recipe of the
synthetic colorants, :mod:`simulators.recipe`). A recipe file that cannot define a panel ends the
process with status 2 after one line ``INPUT-ERROR {"field": …, "accepted": …, "got": …}`` on stdout
(and the message on stderr), which :func:`station.drivers.simproc.spawn_simulator` turns back into a
typed :class:`~station.drivers.errors.DriverInputError`; so does a setting outside its range (the
arguments become a validated :class:`~simulators.config.SimulatorConfig`).
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from simulators import serve
from simulators.config import SimulatorConfig
from simulators.faults import FAULTS, FaultPlan, FaultSpecError
from station.errors import InputError

if TYPE_CHECKING:
    from simulators.recipe import RecipePanel

__all__ = ["DeviceFactory", "build_parser", "config_from_args", "main"]

DeviceFactory = Callable[[SimulatorConfig, FaultPlan, "RecipePanel | None"], Any]
"""Builds the device a family serves: ``(config, faults, loaded recipe panel or None) -> device``."""


def build_parser(kind: str) -> argparse.ArgumentParser:
    """Arguments common to the simulators."""
    p = argparse.ArgumentParser(
        prog=f"python -m simulators.{kind}", description=f"simulated {kind} instrument"
    )
    panel = p.add_mutually_exclusive_group()
    panel.add_argument("--design", type=Path, help="design file (cacad.design/1 JSON) of the virtual panel")
    panel.add_argument(
        "--recipe",
        type=Path,
        help="recipe file of the virtual panel (`station formulate --json` output or its recipe object)",
    )
    p.add_argument(
        "--fault",
        action="append",
        default=[],
        metavar="SPEC",
        help="NAME[@COMMAND][:N]; known: " + ", ".join(FAULTS),
    )
    p.add_argument(
        "--family",
        default=kind,
        help=f"the family served (its address prefix; a family whose simulator is simulators.{kind})",
    )
    p.add_argument("--serial", help="instrument serial number")
    p.add_argument(
        "--bias", type=float, default=0.0, help="inter-instrument bias scale (0 = none, 1 = typical)"
    )
    p.add_argument("--noise", type=float, default=1.0, help="noise scale (1 = published repeatability)")
    p.add_argument("--measure-time", type=float, default=0.3, help="seconds per measurement")
    p.add_argument("--cold", action="store_true", help="start cold (warm-up drift and temperature rise)")
    p.add_argument("--seed", type=int, help="noise seed: a reproducible run (default: fresh noise each run)")
    runs = p.add_mutually_exclusive_group()
    runs.add_argument("--run-index", type=int, help="this run's index for the drift across runs (default 0)")
    runs.add_argument(
        "--state", type=Path, help="run-state file: each start takes its run counter and adds one"
    )
    p.add_argument(
        "--drift",
        type=float,
        default=1.0,
        help="scale of the stated drift across runs (1 = stated, 0 = none)",
    )
    p.add_argument("--rfc2217", action="store_true", help="also serve the pty behind an RFC 2217 server")
    p.add_argument("--tcp", action="store_true", help="also serve the pty on raw TCP (socket:// URL)")
    p.add_argument("--twelve", action="store_true", help="ma6 only: add the 15° illumination block")
    return p


def config_from_args(kind: str, args: argparse.Namespace) -> SimulatorConfig:
    """The validated configuration of the parsed command line (SimulatorConfigError, FaultSpecError)."""
    return SimulatorConfig(
        kind=args.family,
        protocol=kind,
        design=args.design,
        recipe=args.recipe,
        faults=tuple(args.fault),
        serial=args.serial,
        bias=args.bias,
        noise=args.noise,
        measure_time_s=args.measure_time,
        cold=args.cold,
        seed=args.seed,
        run_index=args.run_index,
        state=args.state,
        drift=args.drift,
        rfc2217=args.rfc2217,
        tcp=args.tcp,
        twelve=args.twelve,
    )


def _input_error(exc: InputError) -> int:
    print(
        "INPUT-ERROR "
        + json.dumps({"field": exc.field, "accepted": exc.accepted, "got": exc.got}, default=str),
        flush=True,
    )
    print(f"error: {exc}", file=sys.stderr)
    return 2


def main(kind: str, build: DeviceFactory, argv: list[str] | None = None) -> int:
    """Run simulator *kind*, its device made by *build*, until told to stop; return the exit status."""
    args = build_parser(kind).parse_args(argv)
    try:
        config = config_from_args(kind, args)
    except FaultSpecError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except InputError as exc:
        return _input_error(exc)
    recipe: RecipePanel | None = None
    if config.recipe is not None:
        from simulators.recipe import load_recipe

        try:
            recipe = load_recipe(config.recipe)
        except InputError as exc:
            return _input_error(exc)
    faults = config.fault_plan()
    try:
        server = serve.start(config, build(config, faults, recipe), faults)
    except Exception as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"ADDRESS {server.address}", flush=True)
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())

    def watch_stdin() -> None:
        try:
            while sys.stdin.buffer.read(1):
                pass
        except (OSError, ValueError):
            pass
        stop.set()

    threading.Thread(target=watch_stdin, daemon=True).start()
    stop.wait()
    server.close()
    return 0
