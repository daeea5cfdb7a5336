"""Start an Xvfb server on a free display (``-displayfd``) for headless GL runs (tests, screenshots, bench)."""

from __future__ import annotations

import os
import shutil
import subprocess


class XvfbError(RuntimeError):
    """Xvfb is missing or did not start."""


def start_xvfb(screen: str = "1600x1200x24") -> subprocess.Popen:
    """Start Xvfb, set ``DISPLAY`` to it and return the process (terminate it when done)."""
    if shutil.which("Xvfb") is None:
        raise XvfbError("Xvfb is not installed (scripts/setup.sh installs it)")
    r, w = os.pipe()
    try:
        proc = subprocess.Popen(
            ["Xvfb", "-displayfd", str(w), "-screen", "0", screen, "-nolisten", "tcp", "+extension", "GLX"],
            pass_fds=(w,),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    finally:
        os.close(w)
    with os.fdopen(r) as fh:
        display = fh.readline().strip()
    if not display:
        proc.kill()
        proc.wait()
        raise XvfbError("Xvfb did not report a display number")
    os.environ["DISPLAY"] = f":{display}"
    return proc
