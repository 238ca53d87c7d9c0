"""``casa progress``: how far the power or robustness target has come, and the time left."""

from __future__ import annotations

from casa_core.cli._options import example

#: The example of ``casa progress --help``, also shown by ``casa power --help``.
EXAMPLE = ("casa progress power --config data/interim/config.yaml",)


def register(commands) -> None:
    """Add ``casa progress`` to the ``casa`` subcommands."""
    from casa_core.experiments.progress import BENCHMARKS, INTERIM, UNIT_WORDS

    command = commands.add_parser(
        "progress",
        help="how far the power or robustness target has come, and the time left",
        description="Units done of the total (power replicates, robustness variants), "
        "job time per unit and the time left at the pace so far, from the jobs' "
        f"Snakemake benchmark files. Run it in the workflow's folder, or give --benchmarks: "
        f"the workflow's {BENCHMARKS} folder, beside whose {INTERIM} the units' configs are "
        "read; exit 2 if that folder does not exist.",
        **example(*EXAMPLE),
    )
    command.add_argument(
        "target",
        choices=list(UNIT_WORDS),
        help="the workflow's target whose units to count: " + ", ".join(UNIT_WORDS),
    )
    command.add_argument(
        "--config",
        required=True,
        action="append",
        metavar="YAML",
        help="the workflow's config (its totals); repeat to overlay files in order",
    )
    command.add_argument(
        "--benchmarks",
        default=str(BENCHMARKS),
        metavar="DIR",
        help=f"the workflow's benchmark folder (default {BENCHMARKS}, in the working "
        "directory); the target's files are below it",
    )
    command.add_argument("--done", metavar="UNIT", help="name the unit that just finished")
    command.add_argument("--out", metavar="TXT", help="also write the line to this file")
    command.add_argument("--append", metavar="LOG", help="also append the line, timed, to a log")
    command.set_defaults(func=_progress)


def _progress(args) -> int:
    from datetime import UTC, datetime
    from pathlib import Path

    from casa_core.cli._errors import fail
    from casa_core.config import load_config
    from casa_core.experiments.progress import read_progress, target_units, unit_configs
    from casa_core.io.atomic import atomic_write_text

    config = load_config(*args.config)
    units = target_units(config, args.target)
    benchmarks = Path(args.benchmarks)
    if not benchmarks.is_dir():
        # Counting nothing would print "0 done" for a run that may be far along elsewhere.
        return fail(
            "progress",
            f"no benchmark folder {benchmarks.absolute()}: run casa progress in the "
            "workflow's folder, or give --benchmarks WORKFLOW/benchmarks (no job of the "
            "workflow has finished yet if it is the workflow's folder)",
        )
    # The units' configs are the workflow's, beside its benchmark folder.
    configs = unit_configs(args.target, units, benchmarks.absolute().parent)
    done = read_progress(benchmarks / args.target, units, configs=configs)
    line = done.line(args.target)
    if args.done:
        line = f"{line} (just done: {args.done})"
    print(line, flush=True)
    if args.out:
        atomic_write_text(args.out, line + "\n")
    if args.append:
        stamp = datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
        path = Path(args.append)
        path.parent.mkdir(parents=True, exist_ok=True)
        # A log grows a line at a time: one append per line (atomic for a short write).
        with path.open("a", encoding="utf-8") as log:
            log.write(f"{stamp} {line}\n")
    return 0
