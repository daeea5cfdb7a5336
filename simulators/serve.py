"""Start a simulator of a given kind behind its wire (pty, RFC 2217), for the command line and tests."""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from typing import Any

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


def start(kind: str, args: argparse.Namespace, faults: FaultPlan) -> Served:
    """Build the device for *kind* (``ma6``, ``ma3``, ``gloss``) and serve it on a pty."""
    from simulators._cli import make_physics

    if kind == "ma6":
        from simulators.ma6 import Ma6Device

        device: Any = Ma6Device(
            make_physics(args, "600123"), faults, measure_time_s=args.measure_time, twelve=args.twelve
        )
    elif kind == "ma3":
        from simulators.ma3 import Ma3Device

        device = Ma3Device(make_physics(args, "300456"), faults, measure_time_s=args.measure_time)
    elif kind == "gloss":
        from simulators.gloss import GlossDevice, HidBridgeServer

        device = HidBridgeServer(GlossDevice.from_args(args, faults))
    else:
        raise ValueError(f"unknown simulator kind {kind!r}")
    host = PtyHost(device).start()
    served = Served(f"{kind}@{host.path}", device, host)
    if faults.active("port-held"):
        host.hold_port()
    if getattr(args, "rfc2217", False) or getattr(args, "tcp", False):
        from simulators.rfc2217_server import Rfc2217Server

        srv = Rfc2217Server(host.path, raw=not args.rfc2217).start()
        served.extra.append(srv)
        served.address = f"{kind}@{srv.url}"
    return served
