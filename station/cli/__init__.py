"""The ``station`` command line.

Every module in this package that defines ``register(subparsers)`` contributes one top-level
subcommand (``station model …``, ``station render …``). Handlers return a JSON-able ``dict``; the
common runner prints it as JSON with ``--json`` or as readable text without, and turns any
:class:`station.errors.InputError` into exit status 2 with one line on stderr naming the field and
the accepted range.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from collections.abc import Sequence

from station import __version__


def build_parser() -> argparse.ArgumentParser:
    """Build the top-level parser with every subcommand module found in this package."""
    parser = argparse.ArgumentParser(prog="station", description="CACAD Station command line")
    parser.add_argument("--version", action="version", version=f"station {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        register = getattr(module, "register", None)
        if register is not None:
            register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``station`` console script; returns the process exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.error("missing subcommand")
    from station.cli._common import run_handler

    return run_handler(handler, args)


if __name__ == "__main__":
    sys.exit(main())
