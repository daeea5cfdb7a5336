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
from typing import NoReturn

from station import __version__


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line on stderr and exit status 2, like every other
    error of the command line (the full usage stays behind ``--help``). Subcommand parsers inherit it."""

    def error(self, message: str) -> NoReturn:
        """Print ``error: PROG: MESSAGE (see PROG --help)`` and exit with status 2."""
        self.exit(2, f"error: {self.prog}: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """Build the top-level parser with every subcommand module found in this package."""
    parser = OneLineParser(prog="station", description="CACAD Station command line")
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

    try:
        return run_handler(handler, args)
    except BrokenPipeError:
        return _closed_pipe()
    except KeyboardInterrupt:  # Ctrl+C: the command is cancelled, said in one line
        print("cancelled (Ctrl+C)", file=sys.stderr)
        return EXIT_INTERRUPTED


EXIT_INTERRUPTED = 130
"""Exit status after Ctrl+C: 128 + SIGINT, as shells report."""
EXIT_PIPE = 141
"""Exit status when the reader of the output went away (``| head``): 128 + SIGPIPE, as shells report."""


def _closed_pipe() -> int:
    """The reader closed the pipe: say nothing (no traceback) and leave with :data:`EXIT_PIPE`.

    Standard output is pointed at ``/dev/null`` so the interpreter's final flush cannot fail again."""
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    finally:
        os.close(devnull)
    return EXIT_PIPE


if __name__ == "__main__":
    sys.exit(main())
