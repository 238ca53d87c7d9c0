"""The ``casa`` command line: thin wrappers over the package.

One module per command, named after it; each adds its command (``register``) and holds
its handlers: each loads its inputs once, calls the package and reports.

- :mod:`~casa_core.cli.validate`: ``casa validate``
- :mod:`~casa_core.cli.process`: ``casa process``
- :mod:`~casa_core.cli.stats`: ``casa stats``
- :mod:`~casa_core.cli.import_`: ``casa import`` (``import`` is a Python keyword), its
  ``rosbag`` format in :mod:`~casa_core.cli.import_rosbag`
- :mod:`~casa_core.cli.teleop`: ``casa teleop``
- :mod:`~casa_core.cli.bench`: ``casa bench``
- :mod:`~casa_core.cli.session`: ``casa session``
- :mod:`~casa_core.cli.figure`: ``casa figure``
- :mod:`~casa_core.cli.learn`: ``casa learn``
- :mod:`~casa_core.cli.library`: ``casa library``
- :mod:`~casa_core.cli.simulate`: ``casa simulate``
- :mod:`~casa_core.cli.case_study`: ``casa case-study``
- :mod:`~casa_core.cli.replay`: ``casa replay``
- :mod:`~casa_core.cli.report`: ``casa report`` (its claims and robustness pages included)
- :mod:`~casa_core.cli.power`: ``casa power``
- :mod:`~casa_core.cli.progress`: ``casa progress``
- :mod:`~casa_core.cli.calibrate`: ``casa calibrate``
- :mod:`~casa_core.cli.ros2`: ``casa ros2`` (the ``ros2`` extra's nodes)

An input that cannot be used (:class:`~casa_core.config.ConfigError`,
:class:`~casa_core.scene.SceneError`, a bad table) ends the command with exit status 2
and a message naming the file and the key, without a traceback; a file that cannot be
read or written ends it with exit status 1. ``cli/_errors.py`` gives the handlers the
same rule; ``casa validate`` finding problems in the files it read also exits 1.
"""

from __future__ import annotations

import argparse
import sys

from casa_core import __version__
from casa_core.cli import (
    bench,
    calibrate,
    case_study,
    figure,
    import_,
    learn,
    library,
    power,
    process,
    progress,
    replay,
    report,
    ros2,
    session,
    simulate,
    stats,
    teleop,
    validate,
)
from casa_core.cli._options import CommandParser, ExampleFormatter, example

#: Examples of the commands whose module gives none, by their ``prog``.
EXAMPLES = {
    "casa figure": "casa figure objective --trials data/processed/simulated/trials.csv "
    "--out figures/simulated/objective",
    "casa figure objective": "casa figure objective --trials data/processed/simulated/trials.csv "
    "--stats data/processed/simulated/stats.csv --out figures/simulated/objective",
    "casa figure likert": "casa figure likert --likert data/processed/simulated/likert.csv "
    "--out figures/simulated/likert",
    "casa figure arbitration": "casa figure arbitration "
    "--arbitration data/processed/case_study/arbitration.csv --out figures/arbitration",
    "casa figure case_study": "casa figure case_study --steps data/processed/case_study/steps.csv "
    "--epsilon 1.0 --out figures/case_study",
    "casa figure scene": "casa figure scene --out figures/scene",
    "casa report summary": "casa report summary --stats data/processed/simulated/stats.csv "
    "--dataset simulated --out-md summary.md --out-html summary.html",
    "casa report markdown": "casa report markdown data/processed/simulated/stats.md "
    "--out stats.html",
    "casa report table": "casa report table data/processed/simulated/trials.csv --out trials.html",
}


def build_parser() -> argparse.ArgumentParser:
    parser = CommandParser(
        prog="casa",
        description="Confidence-Aware Shared Autonomy: simulation, study and analysis tools. "
        "Each command's --help ends with an example.",
        **example("casa validate data/raw/mine", "casa teleop --help"),
    )
    parser.add_argument("--version", action="version", version=f"casa {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (
        validate,
        process,
        stats,
        import_,
        teleop,
        bench,
        session,
        figure,
        learn,
        library,
        simulate,
        case_study,
        replay,
        report,
        power,
        progress,
        calibrate,
        ros2,
    ):
        module.register(commands)
    for command in all_parsers(parser)[1:]:
        if command.epilog is None and command.prog in EXAMPLES:
            command.epilog = example(EXAMPLES[command.prog])["epilog"]
            command.formatter_class = ExampleFormatter
    return parser


def all_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """``parser`` and every command and subcommand below it, depth first."""
    found = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):
                found += all_parsers(sub)
    return found


def main(argv: list[str] | None = None) -> int:
    from casa_core.cli._lifetime import end_with_parent
    from casa_core.config import ConfigError
    from casa_core.scene import SceneError

    end_with_parent()  # a job of the workflow ends with Snakemake (cli/_lifetime.py)
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
    except OSError as error:
        # A file or folder the command could not read or write (missing, read-only, disk
        # full); outputs are written atomically, so what was there before is unchanged.
        where = f" {error.filename}" if error.filename else ""
        print(
            f"casa {args.command}: cannot read or write{where}: {error.strerror or error}; "
            "files already there are unchanged",
            file=sys.stderr,
        )
        return 1
