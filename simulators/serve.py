"""Serve a built simulator device behind its wire (pty, optionally RFC 2217 or raw TCP).

The device comes ready-made from its family's factory (``build_device`` in :mod:`simulators.ma6`,
:mod:`simulators.ma3`, :mod:`simulators.gloss`); this module only puts it on a pty and reads the
wire options of the :class:`~simulators.config.SimulatorConfig`. It imports neither the command
line nor the device families.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from simulators.config import SimulatorConfig
from simulators.faults import FaultPlan
from simulators.pty_host import PtyHost

__all__ = ["Served", "start"]


@dataclass
class Served:
    """A running simulator: its driver address, the device object and what to close."""

    address: str
    device: Any
    host: PtyHost
    extra: list[Any] = field(default_factory=list)

    def close(self) -> None:
        """Stop serving."""
        for obj in self.extra:
            obj.close()
        self.host.close()


def start(config: SimulatorConfig, device: Any, faults: FaultPlan) -> Served:
    """Serve *device* (built for *config*, sharing the fault plan *faults*) on a pty.

    The address is ``KIND@/dev/pts/N``, or ``KIND@rfc2217://…`` / ``KIND@socket://…`` when
    ``config.rfc2217`` / ``config.tcp`` asks for a network server in front of the pty.
    """
    host = PtyHost(device).start()
    served = Served(f"{config.kind}@{host.path}", device, host)
    if faults.active("port-held"):
        host.hold_port()
    if config.rfc2217 or config.tcp:
        from simulators.rfc2217_server import Rfc2217Server

        srv = Rfc2217Server(host.path, raw=not config.rfc2217).start()
        served.extra.append(srv)
        served.address = f"{config.kind}@{srv.url}"
    return served
