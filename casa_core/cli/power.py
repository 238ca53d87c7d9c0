"""``casa power``: the simulated power of H1-H3 (detections, power table, figure).

The ``power`` target (workflow/rules/power.smk) runs ``casa power detect`` once per
replicate study, ``casa power table`` on all of them and ``casa power figure`` on the
table; ``casa progress`` (:mod:`~casa_core.cli.progress`) reports how far it has come.
"""

from __future__ import annotations

from casa_core.cli._errors import fail
from casa_core.cli._options import example, positive_int, provenance, provenance_options
from casa_core.cli.progress import EXAMPLE as PROGRESS_EXAMPLE
from casa_core.io import read_table
from casa_core.io.population import CONFIG_POPULATION

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
    "figure": (
        "casa power figure --power data/processed/power/power.csv --out figures/power \\",
        "    --config-files config/config.yaml --effective-config data/interim/config.yaml",
    ),
    "progress": PROGRESS_EXAMPLE,
}


def register(commands) -> None:
    """Add ``casa power`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "power",
        help="simulated power of H1-H3: per replicate study, the table, the figure",
        description="The steps of the power analysis. To run the whole analysis, run "
        "`snakemake --cores all power` in the workflow's folder (docs/power.md): it simulates "
        "the replicate studies of the config's power.sizes and power.replicates and runs "
        "these steps on them; `casa progress power` says how far it has come.",
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
    table.add_argument(
        "--detections",
        required=True,
        nargs="+",
        metavar="CSV",
        help="the replicates' detections.csv files (casa power detect)",
    )
    table.add_argument(
        "--population",
        default=CONFIG_POPULATION,
        help="whom the simulated participants were drawn from, written in each row",
    )
    table.add_argument("--out", required=True, metavar="CSV", help="power.csv to write")
    table.set_defaults(func=_table)
    figure = steps.add_parser(
        "figure", help="power against N from power.csv", **example(*_EXAMPLES["figure"])
    )
    figure.add_argument("--power", required=True, metavar="CSV", help="power.csv")
    figure.add_argument(
        "--out", required=True, metavar="PREFIX", help="writes PREFIX.pdf and PREFIX.png"
    )
    provenance_options(figure)
    figure.set_defaults(func=_figure)


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
    table["population"] = args.population
    write_csv(args.out, table)
    files = len(args.detections)
    print(f"casa power table: {len(table)} row(s) from {files} file(s) -> {args.out}")
    return 0


def _figure(args) -> int:
    from casa_core.figures.power import power_figure
    from casa_core.figures.style import save_figure

    try:
        built = provenance(args)
        fig = power_figure(read_table(args.power), provenance=built.line() if built else "")
    except (OSError, ValueError) as error:
        return fail("power figure", error)
    written = ", ".join(map(str, save_figure(fig, args.out)))
    print(f"casa power figure: -> {written}")
    return 0
