"""A private X display for the tests that open a real pybullet window."""

from __future__ import annotations

import os
import subprocess


def start_xvfb() -> tuple[subprocess.Popen, str]:
    """Start Xvfb (1024 x 768) on a free display; the server (stop it with ``terminate``)
    and the display's name, e.g. ``":1"``."""
    read, write = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    with os.fdopen(read) as pipe:
        display = pipe.readline().strip()
    assert display, "Xvfb did not report a display number"
    return server, f":{display}"
