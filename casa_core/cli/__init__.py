"""The ``casa`` command line: thin wrappers over the package.

Each module adds a few commands (``register``) and holds their handlers: each loads its
inputs once, calls the package and reports.
An input file that cannot be used (:class:`~casa_core.config.ConfigError`,
:class:`~casa_core.scene.SceneError`) ends the command with exit status 2 and a message
naming the file and the key, without a traceback.
"""

from __future__ import annotations

import argparse
import sys

from casa_core import __version__
from casa_core.cli import data, figure, learning, robot, study


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="casa",
        description="Confidence-Aware Shared Autonomy: simulation, study and analysis tools.",
    )
    parser.add_argument("--version", action="version", version=f"casa {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (data, robot, figure, learning, study):
        module.register(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    from casa_core.config import ConfigError
    from casa_core.scene import SceneError

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return args.func(args)
    except (ConfigError, SceneError) as error:
        # An input file that cannot be used: the message names it and the key, no traceback.
        print(f"casa {args.command}: {error}", file=sys.stderr)
        return 2
