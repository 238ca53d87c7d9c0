"""``casa power`` (detections, power table, figure) and ``casa progress`` (long targets).

The ``power`` target (workflow/rules/power.smk) runs ``casa power detect`` once per
replicate study, ``casa power table`` on all of them and ``casa power figure`` on the
table; ``casa progress`` reports how far the power or robustness target has come.
"""

from __future__ import annotations

from casa_core.cli._errors import fail
from casa_core.cli._options import example, positive_int
from casa_core.io import read_table

_EXAMPLES = {
    "detect": (
        "casa power detect --config data/interim/power/default/r1/config.yaml \\",
        "    --trials data/interim/power/default/r1/trials.csv --variant default --replicate 1 \\",
        "    --sizes 6 8 11 16 24 --out data/interim/power/default/r1/detections.csv",
    ),
    "table": (
        "casa power table --detections data/interim/power/*/r*/detections.csv \\",
        "    --out data/processed/power/power.csv",
    ),
    "figure": ("casa power figure --power data/processed/power/power.csv --out figures/power",),
    "progress": ("casa progress power --config data/interim/config.yaml",),
}


def register(commands) -> None:
    """Add ``power`` and ``progress`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "power",
        help="simulated power of H1-H3: per replicate study, the table, the figure",
        **example(*(line for lines in _EXAMPLES.values() for line in lines)),
    )
    steps = command.add_subparsers(dest="step", metavar="STEP", required=True)
    detect = steps.add_parser(
        "detect",
        help="whether one replicate study detects each of H1-H3, per N, metric and form",
        **example(*_EXAMPLES["detect"]),
    )
    detect.add_argument("--config", required=True, metavar="YAML", help="the replicate's config")
    detect.add_argument("--trials", required=True, metavar="CSV", help="its trials.csv")
    detect.add_argument("--variant", required=True, help="the variant's name")
    detect.add_argument("--replicate", required=True, type=positive_int, help="1-based")
    detect.add_argument(
        "--sizes", required=True, nargs="+", type=positive_int, metavar="N", help="the Ns"
    )
    detect.add_argument("--out", required=True, metavar="CSV", help="detections.csv to write")
    detect.set_defaults(func=_detect)
    table = steps.add_parser(
        "table", help="power.csv from the replicates' detections", **example(*_EXAMPLES["table"])
    )
    table.add_argument("--detections", required=True, nargs="+", metavar="CSV")
    table.add_argument("--out", required=True, metavar="CSV", help="power.csv to write")
    table.set_defaults(func=_table)
    figure = steps.add_parser(
        "figure", help="power against N from power.csv", **example(*_EXAMPLES["figure"])
    )
    figure.add_argument("--power", required=True, metavar="CSV", help="power.csv")
    figure.add_argument(
        "--out", required=True, metavar="PREFIX", help="writes PREFIX.pdf and PREFIX.png"
    )
    figure.set_defaults(func=_figure)
    _add_progress(commands)


def _add_progress(commands) -> None:
    from casa_core.experiments.progress import BENCHMARKS, UNIT_WORDS

    command = commands.add_parser(
        "progress",
        help="how far the power or robustness target has come, and the time left",
        description="Units done of the total (power replicates, robustness variants), "
        "job time per unit and the time left at the pace so far, from the jobs' "
        "Snakemake benchmark files.",
        **example(*_EXAMPLES["progress"]),
    )
    command.add_argument("target", choices=list(UNIT_WORDS))
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
        help=f"the benchmark folder (default {BENCHMARKS}); the target's files are below it",
    )
    command.add_argument("--done", metavar="UNIT", help="name the unit that just finished")
    command.add_argument("--out", metavar="TXT", help="also write the line to this file")
    command.add_argument("--append", metavar="LOG", help="also append the line, timed, to a log")
    command.set_defaults(func=_progress)


def _detect(args) -> int:
    from casa_core.config import load_config
    from casa_core.io.atomic import write_csv
    from casa_core.stats.margins import Margins
    from casa_core.stats.power import replicate_detections

    config = load_config(args.config)
    try:
        trials = read_table(args.trials)
        rows = replicate_detections(
            trials,
            sizes=args.sizes,
            variant=args.variant,
            replicate=args.replicate,
            margins=Margins.from_config(config["statistics"]),
        )
    except (OSError, ValueError) as error:
        return fail("power detect", error)
    write_csv(args.out, rows)
    print(f"casa power detect: {int(rows['detected'].sum())} of {len(rows)} detected -> {args.out}")
    return 0


def _table(args) -> int:
    from casa_core.io.atomic import write_csv
    from casa_core.stats.power import power_table

    try:
        table = power_table([read_table(path) for path in sorted(args.detections)])
    except (OSError, ValueError) as error:
        return fail("power table", error)
    write_csv(args.out, table)
    files = len(args.detections)
    print(f"casa power table: {len(table)} row(s) from {files} file(s) -> {args.out}")
    return 0


def _figure(args) -> int:
    from casa_core.figures.power import power_figure
    from casa_core.figures.style import save_figure

    try:
        fig = power_figure(read_table(args.power))
    except (OSError, ValueError) as error:
        return fail("power figure", error)
    written = ", ".join(map(str, save_figure(fig, args.out)))
    print(f"casa power figure: -> {written}")
    return 0


def _progress(args) -> int:
    from datetime import UTC, datetime
    from pathlib import Path

    from casa_core.config import load_config
    from casa_core.experiments.progress import read_progress, target_units, unit_configs
    from casa_core.io.atomic import atomic_write_text

    config = load_config(*args.config)
    units = target_units(config, args.target)
    root = Path(args.benchmarks) / args.target
    done = read_progress(root, units, configs=unit_configs(args.target, units))
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
