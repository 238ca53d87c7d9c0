"""Processes on a private DDS domain: the environment, starting, stopping by pid."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: Domains handed out to this run's tests, so that no two tests (or runs) hear each other.
_next_domain = [100 + os.getpid() % 60]


def ros_env() -> dict:
    """A fresh DDS domain on this machine only, with Fast DDS."""
    _next_domain[0] += 1
    env = dict(os.environ)
    env.update(
        RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_DOMAIN_ID=str(_next_domain[0] % 230),
        PYTHONUNBUFFERED="1",
    )
    return env


def casa(args: list[str], env: dict, log: Path) -> subprocess.Popen:
    """``casa ARGS`` in a process of its own, stdout and stderr into ``log``."""
    out = open(log, "w")  # noqa: SIM115  closed with the process
    return subprocess.Popen(
        [sys.executable, "-m", "casa_core.cli", *args], env=env, stdout=out, stderr=out
    )


def script(name: str, args: list[str], env: dict, log: Path) -> subprocess.Popen:
    """A helper script of this folder in a process of its own."""
    out = open(log, "w")  # noqa: SIM115
    return subprocess.Popen(
        [sys.executable, str(HERE / name), *args], env=env, stdout=out, stderr=out
    )


def stop(processes: list[subprocess.Popen], grace: float = 10.0) -> None:
    """SIGINT each process by its pid, then SIGKILL what is left after ``grace`` s."""
    for process in processes:
        if process.poll() is None:
            os.kill(process.pid, signal.SIGINT)
    deadline = time.monotonic() + grace
    for process in processes:
        try:
            process.wait(timeout=max(deadline - time.monotonic(), 0.1))
        except subprocess.TimeoutExpired:
            os.kill(process.pid, signal.SIGKILL)
            process.wait()
