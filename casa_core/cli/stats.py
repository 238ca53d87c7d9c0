"""``casa stats``: the study's statistics (H1-H4), stats.csv and its APA-style report."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

from casa_core.cli._errors import cannot_write
from casa_core.cli._options import example, left_out, one_sided_level, validation_option
from casa_core.cli._workflow import add_config_option, load_workflow_config
from casa_core.io import read_table


def register(commands) -> None:
    """Add ``casa stats`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "stats",
        help="the study's statistics (H1-H4): stats.csv and an APA-style Markdown report",
        description="Run the study's analyses on trials.csv (and likert.csv) and write "
        "stats.csv and its APA-style rendering, with the non-inferiority margins of the "
        "config's statistics unless --margin or --margin-fraction is given: the tables the "
        "workflow writes. The workflow also writes summary.md and results.md (casa report); "
        "to build one dataset as the workflow does: snakemake --cores all --config "
        "'datasets=[NAME]'.",
        **example(
            "casa stats --trials data/processed/mine/trials.csv "
            "--likert data/processed/mine/likert.csv \\",
            "    --out-csv data/processed/mine/stats.csv --out-md data/processed/mine/stats.md",
        ),
    )
    command.add_argument("--trials", required=True, metavar="CSV", help="trials.csv")
    command.add_argument("--likert", metavar="CSV", help="likert.csv (optional)")
    validation_option(command)
    command.add_argument("--out-csv", required=True, metavar="CSV", help="stats.csv to write")
    command.add_argument("--out-md", required=True, metavar="MD", help="report to write")
    command.add_argument(
        "--out-wide",
        metavar="CSV",
        help="also write each participant's cell means as one row (one column per task, "
        "condition and metric), for JASP, SPSS or R",
    )
    command.add_argument(
        "--margin",
        action="append",
        default=[],
        metavar="[TASK:]METRIC=VALUE",
        help="a non-inferiority margin in the metric's unit (repeatable; with "
        "--margin-fraction, replaces the config's statistics.noninferiority_margins)",
    )
    command.add_argument(
        "--margin-fraction",
        action="append",
        default=[],
        metavar="[TASK:]METRIC=VALUE",
        help="a margin as a fraction of the reference condition's mean (repeatable; "
        "replaces statistics.noninferiority_fractions)",
    )
    command.add_argument(
        "--noninferiority-alpha",
        type=one_sided_level,
        metavar="LEVEL",
        help="the one-sided level of the non-inferiority tests (default: the config's "
        "statistics.noninferiority_alpha, the paper's 0.05)",
    )
    add_config_option(command, "workflow config whose statistics block gives the margins")
    command.set_defaults(func=_stats)


def _stats(args) -> int:
    from casa_core import stats
    from casa_core.io.atomic import atomic_paths, frame_to_csv_text
    from casa_core.stats.margins import Margins, parse_margin
    from casa_core.stats.wide import wide_means

    try:
        margins = Margins(
            absolute=dict(parse_margin(text, "--margin") for text in args.margin),
            fractions=dict(
                parse_margin(text, "--margin-fraction") for text in args.margin_fraction
            ),
        )
        configured = Margins.from_config(load_workflow_config(args)[0]["statistics"])
        if not args.margin and not args.margin_fraction:
            margins = configured
        alpha = args.noninferiority_alpha
        margins = replace(margins, alpha=configured.alpha if alpha is None else alpha)
    except ValueError as error:  # ConfigError and SceneError too: they name file and key
        print(f"casa stats: {error}", file=sys.stderr)
        return 2
    try:
        # read_table keeps the method "NA" as text (pandas' default would make it missing).
        trials = read_table(args.trials)
        likert = read_table(args.likert) if args.likert else None
        table = stats.analyze_study(trials, likert, margins=margins)
        report = stats.report_markdown(table, trials=trials, left_out=left_out(args))
        wide = wide_means(trials) if args.out_wide else None
    except (OSError, ValueError) as error:
        print(f"casa stats: {error}", file=sys.stderr)
        return 1
    texts = [frame_to_csv_text(table), report]
    paths = [args.out_csv, args.out_md]
    if wide is not None:
        texts.append(frame_to_csv_text(wide))
        paths.append(args.out_wide)
    try:
        # The tables and the report belong together: all or none are replaced.
        with atomic_paths(*paths) as temporaries:
            for tmp, text in zip(temporaries, texts, strict=True):
                tmp.write_bytes(text.encode("utf-8"))
    except OSError as error:
        folder = Path(error.filename).parent if error.filename else Path(args.out_csv).parent
        return cannot_write("stats", folder, error)
    # A test that ran has a p-value or an estimate; a skipped one has neither.
    skipped = int((table["p"].isna() & table["estimate"].isna()).sum())
    print(f"casa stats: {len(table)} row(s) -> {', '.join(map(str, paths))}")
    if skipped:
        print(f"casa stats: {skipped} test(s) skipped, see their note", file=sys.stderr)
    return 0
