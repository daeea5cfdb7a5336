"""``station viewer [--service URL [--token T]]`` starts the Qt workstation viewer (scans go to the
workstation's database in ``$CACAD_DATA_DIR`` or ``./var``, or to the service's measurements); ``station viewer screenshots --out DIR``
regenerates the screenshots of every screen (docs/screens). The viewer lives in the ``ui`` package; it is
imported only when these commands run (the core never imports Qt)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from station.cli._common import add_json_flag
from station.errors import InputError


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add ``viewer`` and ``viewer screenshots``."""
    p = subparsers.add_parser("viewer", help="the Qt workstation viewer")
    p.add_argument(
        "--service", metavar="URL", help="station service to use as a client (default: local core)"
    )
    p.add_argument(
        "--token", metavar="TOKEN", default=None, help="bearer token for --service (default: $STATION_TOKEN)"
    )
    p.set_defaults(handler=cmd_viewer)
    sub = p.add_subparsers(dest="viewer_command", metavar="ACTION")
    s = sub.add_parser("screenshots", help="regenerate screenshots of every screen")
    s.add_argument(
        "--out", type=Path, default=Path("docs/screens"), help="output folder (default docs/screens)"
    )
    s.add_argument("--no-scan", action="store_true", help="skip the simulator scan on the instruments screen")
    add_json_flag(s)
    s.set_defaults(handler=cmd_screenshots)


def _check_service(url: str | None) -> None:
    if url is not None and not url.startswith(("http://", "https://")):
        raise InputError("--service", "an http:// or https:// URL", url)


def cmd_viewer(args: argparse.Namespace) -> dict[str, Any] | None:
    """Run the viewer until its window closes."""
    _check_service(args.service)
    if args.token is not None and args.service is None:
        raise InputError("--token", "only together with --service URL", "a token without a service")
    from ui.app import main

    code = main([], service_url=args.service, token=args.token)
    return None if code == 0 else {"exit_code": code}


def cmd_screenshots(args: argparse.Namespace) -> dict[str, Any]:
    """Write one PNG per screen; under no display an Xvfb server is started for the run."""
    xvfb = None
    if not os.environ.get("DISPLAY") and os.environ.get("QT_QPA_PLATFORM") in (None, "", "xcb"):
        from ui.xvfb import start_xvfb

        xvfb = start_xvfb()
    try:
        if xvfb is not None:
            os.environ["QT_QPA_PLATFORM"] = "xcb"
        from PySide6.QtWidgets import QApplication

        from ui.screenshots import take_screenshots
        from ui.widgets.render_view import configure_default_format

        configure_default_format()
        app = QApplication.instance() or QApplication([])
        paths = take_screenshots(args.out, scan=not args.no_scan)
        platform = QApplication.platformName()
        app.shutdown()  # tear Qt down while Python objects are alive (avoids a crash at interpreter exit)
    finally:
        if xvfb is not None:
            xvfb.terminate()
            xvfb.wait(5)
    return {"written": [str(p) for p in paths], "platform": platform}
