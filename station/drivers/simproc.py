"""Start a simulator as a subprocess (``python -m <simulator> --family <kind>``) and learn its address.

Runtime code never imports :mod:`simulators` (import-linter contract); it runs them as programs. The
child prints ``ADDRESS <family>@<where>`` once it serves; :func:`spawn_simulator` waits for that line
(bounded) and returns a :class:`SimulatorProcess` whose ``address`` goes to
:func:`station.drivers.open_instrument`. The child exits when its stdin closes, so it never outlives
the parent.

The virtual panel is a design file or a recipe file (``station formulate --json`` output); a recipe
file the simulator refuses comes back as a typed :class:`DriverInputError` naming the field (the child
reports it on one ``INPUT-ERROR {json}`` line instead of its address).

Kinds: the families of :data:`station.drivers.families.FAMILIES` with a simulator module, e.g. ``ma6`` (ASCII prompt protocol on a pty), ``ma3`` (the binary framed protocol; across a
process boundary it is served on a pty instead of a pyusb backend, see docs/protocols/ma3-binary.md),
``gloss`` (HID reports through the HID-over-pty bridge, docs/protocols/gloss-hid.md).
"""

from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from station.closing import Closing
from station.drivers.errors import CommunicationError, DriverInputError
from station.drivers.families import SIM_FAMILY_NAMES, family_named

__all__ = ["SIM_KINDS", "SimulatorProcess", "spawn_simulator"]

#: The kinds that can be spawned: the families of :data:`station.drivers.families.FAMILIES` with a simulator.
SIM_KINDS = SIM_FAMILY_NAMES
_ROOT = Path(__file__).resolve().parents[2]


class SimulatorProcess(Closing):
    """A running simulator child process; ``address`` is what :func:`open_instrument` takes."""

    def __init__(self, kind: str, proc: subprocess.Popen[bytes], address: str) -> None:
        self.kind = kind
        self.proc = proc
        self.address = address

    def close(self, timeout_s: float = 3.0) -> None:
        """Stop the child (close its stdin, then terminate, then kill) and reap it."""
        if self.proc.poll() is None:
            try:
                if self.proc.stdin is not None:
                    self.proc.stdin.close()
                self.proc.wait(timeout_s / 2)
            except subprocess.TimeoutExpired:
                self.proc.terminate()
                try:
                    self.proc.wait(timeout_s / 2)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
        for stream in (self.proc.stdout, self.proc.stderr):
            if stream is not None:
                stream.close()

    def __repr__(self) -> str:
        return f"SimulatorProcess(kind={self.kind!r}, address={self.address!r}, pid={self.proc.pid})"


def spawn_simulator(
    kind: str,
    design_file: Path | None = None,
    faults: Sequence[str] = (),
    recipe_file: Path | None = None,
    extra_args: Sequence[str] = (),
    startup_timeout_s: float = 20.0,
) -> SimulatorProcess:
    """Start simulator *kind* (one of :data:`SIM_KINDS`) and return once it serves.

    *design_file* is a ``cacad.design/1`` JSON file for the virtual panel, or *recipe_file* a recipe
    (``station formulate --json`` output or its ``"recipe"`` object; the panel's spectra and gloss then
    come from the colorant model); *faults* are fault specs (``NAME[@COMMAND][:N]``, list in
    docs/protocols/faults.md). Raises :class:`DriverInputError` for an unknown kind, a missing design
    or recipe file, both at once, or a recipe the simulator refuses (field and accepted range named),
    :class:`CommunicationError` if the child fails to start.
    """
    family = family_named(kind)
    if family is None or family.simulator is None:
        raise DriverInputError("kind", " | ".join(SIM_KINDS), kind)
    cmd = [sys.executable, "-m", family.simulator, "--family", kind]
    if design_file is not None and recipe_file is not None:
        raise DriverInputError("recipe_file", "either design_file or recipe_file, not both", str(recipe_file))
    if design_file is not None:
        if not Path(design_file).is_file():
            raise DriverInputError("design_file", "an existing design JSON file", str(design_file))
        cmd += ["--design", str(Path(design_file).resolve())]  # the child runs in the repository
    if recipe_file is not None:
        if not Path(recipe_file).is_file():
            raise DriverInputError("recipe_file", "an existing recipe JSON file", str(recipe_file))
        cmd += ["--recipe", str(Path(recipe_file).resolve())]
    for spec in faults:
        cmd += ["--fault", spec]
    cmd += list(extra_args)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(_ROOT), env.get("PYTHONPATH", "")) if p)
    proc = subprocess.Popen(
        cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=_ROOT
    )
    address = _read_address(proc, startup_timeout_s)
    return SimulatorProcess(kind, proc, address)


def _read_address(proc: subprocess.Popen[bytes], timeout_s: float) -> str:
    if proc.stdout is None:
        raise CommunicationError("simulator started without a stdout pipe")
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    deadline = time.monotonic() + timeout_s
    buf = b""
    try:
        while b"\n" not in buf:
            left = deadline - time.monotonic()
            if left <= 0 or not sel.select(left):
                break
            chunk = os.read(proc.stdout.fileno(), 4096)
            if not chunk:
                break
            buf += chunk
    finally:
        sel.close()
    line = buf.split(b"\n", 1)[0].decode(errors="replace").strip()
    if line.startswith("INPUT-ERROR "):
        proc.kill()
        proc.communicate(timeout=5)
        try:
            info = json.loads(line.split(" ", 1)[1])
            field, accepted, got = str(info["field"]), str(info["accepted"]), info.get("got")
        except (ValueError, KeyError, TypeError) as exc:
            raise CommunicationError(f"simulator refused its input: {line[:400]}") from exc
        raise DriverInputError(field, accepted, got)
    if not line.startswith("ADDRESS "):
        proc.kill()
        _, err = proc.communicate(timeout=5)
        raise CommunicationError(
            f"simulator did not start: {line or 'no output'}; {err.decode(errors='replace').strip()[-400:]}"
        )
    return line.split(" ", 1)[1]
