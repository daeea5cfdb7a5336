"""Shared plumbing of CLI handlers: JSON output, error reporting, argument parsers.

A handler takes the parsed ``argparse.Namespace`` and returns a JSON-able ``dict`` (or ``None`` when it
printed what it had to). Text output is the same dict for a person (:mod:`station.cli._text`): one
``key: value`` line each, lists of rows as aligned tables, numbers rounded and with their units.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from station.errors import InputError, StationError

Handler = Callable[[argparse.Namespace], "dict[str, Any] | None"]

EXIT_OK = 0
EXIT_INPUT = 2
EXIT_FAILURE = 1


class Steps:
    """A progress bar of a long command's steps on stderr (tqdm), shown only on a terminal.

    ``steps("measuring")`` marks the previous step done and names the next; the bar is removed when
    the command ends. Piped or redirected output stays clean: the bar is off when stderr is not a
    terminal. Ctrl+C cancels the command (one line, exit 130).
    """

    def __init__(self, total: int, desc: str) -> None:
        from tqdm import tqdm

        self.bar = tqdm(
            total=total,
            desc=desc,
            unit="step",
            file=sys.stderr,
            leave=False,
            disable=None,
            dynamic_ncols=True,
        )
        self.started = False

    def __call__(self, text: str) -> None:
        if self.started:
            self.bar.update(1)
        self.started = True
        self.bar.set_postfix_str(text)

    def __enter__(self) -> Steps:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.bar.close()


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """Add the ``--json`` flag every command carries."""
    parser.add_argument("--json", action="store_true", help="print machine-readable JSON")


def to_jsonable(value: Any) -> Any:
    """Convert numpy scalars/arrays, tuples and paths into plain JSON types (NaN is refused)."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, float):
        if not math.isfinite(value):
            raise StationError(f"refusing to print a non-finite number ({value})")
        return value
    if isinstance(value, Path):
        return str(value)
    return value


def emit(result: dict[str, Any], as_json: bool) -> None:
    """Print *result* as JSON or as text for a person (:func:`station.cli._text.human_text`)."""
    data = to_jsonable(result)
    if as_json:
        print(json.dumps(data))
        return
    from station.cli._text import human_text

    print(human_text(data))


def run_handler(handler: Handler, args: argparse.Namespace) -> int:
    """Run *handler*, print its result, and map errors to exit statuses (2 for bad input)."""
    try:
        result = handler(args)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except StationError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    if result is not None:
        emit(result, getattr(args, "json", False))
    return EXIT_OK


def parse_floats(text: str, field: str, count: int | None = None) -> list[float]:
    """Parse ``"1,2,3"`` into floats; raise :class:`InputError` naming *field* on failure."""
    try:
        values = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError as exc:
        raise InputError(field, "comma-separated numbers", text) from exc
    if count is not None and len(values) != count:
        raise InputError(field, f"{count} comma-separated numbers", text)
    for v in values:
        if not math.isfinite(v):
            raise InputError(field, "finite numbers", text)
    return values


def parse_lab(text: str, field: str) -> tuple[float, float, float]:
    """Parse ``"L,a,b"`` into one Lab triple; raise :class:`InputError` naming *field* on failure."""
    lightness, a, b = parse_floats(text, field, 3)
    return (lightness, a, b)


def parse_lab_list(text: str, field: str = "lab") -> list[list[float]]:
    """Parse ``"L,a,b;L,a,b;…"`` into a list of Lab triples."""
    parts = [p for p in text.split(";") if p.strip()]
    if not parts:
        raise InputError(field, '"L,a,b;L,a,b;..." with one triple per angle', text)
    return [parse_floats(p, f"{field}[{i}]", 3) for i, p in enumerate(parts)]


def add_design_args(p: argparse.ArgumentParser) -> None:
    """Add ``--design FILE`` or ``--face/--flop/--travel/--gloss``, read by :func:`design_from_args`."""
    from station.model.domain import DEFAULT_GLOSS_GU

    p.add_argument("--design", help="design file (cacad.design/1 JSON)")
    p.add_argument("--face", help="face Lab at 15°: L,a,b")
    p.add_argument("--flop", help="flop Lab at the travel angle: L,a,b (omit for a solid)")
    p.add_argument("--travel", type=float, help="travel θ_clamp in degrees (15 < θ <= 180)")
    p.add_argument(
        "--gloss",
        type=float,
        default=DEFAULT_GLOSS_GU,
        help=f"60° gloss in GU (0–100), default {DEFAULT_GLOSS_GU:g}",
    )


def design_from_args(args: argparse.Namespace) -> Any:
    """A design from ``--design FILE`` or from ``--face/--flop/--travel[/--gloss]``.

    ``--flop`` defaults to the face, and face = flop is a solid (no travel needed); an effect paint
    needs ``--travel``. ``--gloss`` absent or None keeps the model's default gloss.
    """
    from station.model import FaceFlopTravelGloss
    from station.model.design_io import load_design

    if getattr(args, "design", None):
        return load_design(args.design)
    if getattr(args, "face", None) is None:
        raise InputError("face", "--face L,a,b (or --design FILE)")
    face = parse_lab(args.face, "face")
    flop = parse_lab(args.flop, "flop") if getattr(args, "flop", None) else face
    travel = None if face == flop else getattr(args, "travel", None)
    if face != flop and travel is None:
        raise InputError("travel", "--travel DEG (15 < travel <= 180) when face != flop")
    gloss = getattr(args, "gloss", None)
    extra = {} if gloss is None else {"gloss_gu": gloss}
    return FaceFlopTravelGloss(face, flop, travel, **extra)
