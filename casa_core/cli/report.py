"""``casa report``: the pages of the HTML report (``snakemake --report``) from the tables.

Also the claims under each modelling variant: ``casa report claims`` judges one variant's
tables (:func:`casa_core.stats.claims.evaluate_claims`) into a table with a ``variant``
column; ``casa report robustness`` merges the variants' tables into ``claims.csv``, its
``results.md`` and the figure (workflow/rules/robustness.smk).
"""

from __future__ import annotations

from pathlib import Path

from casa_core.cli._errors import fail
from casa_core.cli._options import (
    example,
    left_out,
    positive_float,
    provenance,
    provenance_options,
    validation_option,
)
from casa_core.defaults import EPSILON
from casa_core.io import read_table

#: One example per page, shown by each command's --help.
_EXAMPLES = {
    "summary": "casa report summary --stats data/processed/simulated/stats.csv "
    "--dataset simulated \\\n      --out-md data/processed/simulated/summary.md "
    "--out-html data/report/simulated/summary.html",
    "markdown": "casa report markdown data/processed/simulated/stats.md "
    "--out data/report/simulated/stats.html",
    "table": "casa report table data/processed/simulated/trials.csv "
    "--out data/report/simulated/trials.html",
    "results": "casa report results --dataset simulated --trials data/processed/simulated/"
    "trials.csv \\\n      --steps data/processed/simulated/steps.csv --stats "
    "data/processed/simulated/stats.csv \\\n      --likert "
    "data/processed/simulated/likert.csv --arbitration "
    "data/processed/case_study/arbitration.csv \\\n      --case-steps "
    "data/processed/case_study/steps.csv --epsilon 1.0 \\\n      --config-files "
    "config/config.yaml --effective-config data/interim/config.yaml \\\n      "
    "--out data/processed/simulated/results.md --out-html data/report/simulated/results.html",
}
#: The examples of the pages of the claims under each variant.
_CLAIMS_EXAMPLE = (
    "casa report claims --trials data/processed/robustness/paper/trials.csv \\",
    "    --steps data/processed/robustness/paper/steps.csv "
    "--stats data/processed/robustness/paper/stats.csv \\",
    "    --variant paper --config data/interim/robustness/paper/config.yaml "
    "--out data/processed/robustness/paper/claims.csv",
)
_MERGE_EXAMPLE = (
    "casa report robustness --claims data/processed/robustness/*/claims.csv \\",
    "    --out-csv data/processed/robustness/claims.csv "
    "--out-md data/processed/robustness/results.md --figure figures/robustness \\",
    "    --config-files config/config.yaml --effective-config data/interim/config.yaml",
)


#: The tables the claims are judged on (:func:`~casa_core.stats.claims.evaluate_claims`),
#: as options: name and help; the first three are required.
CLAIM_TABLES = (
    ("trials", "trials.csv"),
    ("steps", "steps.csv"),
    ("stats", "stats.csv"),
    ("likert", "likert.csv (optional)"),
    ("arbitration", "the case study's arbitration.csv (optional)"),
    ("case_steps", "the case study's steps.csv (optional)"),
)


def _example(*pages: str) -> dict:
    """``add_parser`` keywords ending --help with the examples of ``pages``."""
    return example(*(line for page in pages for line in _EXAMPLES[page].split("\n")))


def add_claim_options(command) -> None:
    """The options of the claims' inputs: ``--trials`` to ``--case-steps``, ``--epsilon``."""
    for index, (name, what) in enumerate(CLAIM_TABLES):
        option = "--" + name.replace("_", "-")
        command.add_argument(option, required=index < 3, metavar="CSV", help=what)
    command.add_argument(
        "--epsilon",
        type=positive_float,
        default=EPSILON,
        help=f"the misspecification threshold on beta_hat (default {EPSILON:g})",
    )


def read_claim_tables(args) -> dict:
    """The tables of :data:`CLAIM_TABLES` that ``args`` names, read; None for the others."""

    paths = {name: getattr(args, name) for name, _ in CLAIM_TABLES}
    return {name: read_table(path) if path else None for name, path in paths.items()}


def register(commands) -> None:
    """Add ``casa report`` and its pages to the ``casa`` subcommands."""
    command = commands.add_parser(
        "report",
        help="the HTML report's pages: results summary, rendered Markdown, browsable tables",
        **_example(*_EXAMPLES),
    )
    pages = command.add_subparsers(dest="page", metavar="PAGE", required=True)
    summary = pages.add_parser(
        "summary",
        help="per hypothesis, the paper-form and within-subjects tests (stats.csv)",
        **_example("summary"),
    )
    summary.add_argument("--stats", required=True, metavar="CSV", help="stats.csv")
    summary.add_argument("--dataset", required=True, help="the dataset's name, for the title")
    validation_option(summary)
    summary.add_argument("--out-md", required=True, metavar="MD", help="summary.md to write")
    summary.add_argument("--out-html", required=True, metavar="HTML", help="its HTML page")
    summary.set_defaults(func=_summary)
    results = pages.add_parser(
        "results",
        help="each claim of the paper with its criterion, the numbers and a verdict",
        **_example("results"),
    )
    add_claim_options(results)
    results.add_argument("--dataset", required=True, help="the dataset's name, for the title")
    results.add_argument(
        "--operator", help="the simulated operator model, named for a simulated dataset"
    )
    results.add_argument(
        "--population",
        help="whom the simulated participants were drawn from, named for a simulated dataset",
    )
    results.add_argument(
        "--setup",
        help="the layout and teleoperation it was simulated on, named for a simulated dataset",
    )
    validation_option(results)
    results.add_argument("--out", required=True, metavar="MD", help="results.md to write")
    results.add_argument("--out-html", metavar="HTML", help="its HTML page (optional)")
    provenance_options(results)
    results.set_defaults(func=_results)
    markdown = pages.add_parser(
        "markdown",
        help="a Markdown file (e.g. stats.md) as HTML",
        **_example("markdown"),
    )
    markdown.add_argument("markdown", metavar="MD", help="the Markdown page (e.g. stats.md)")
    markdown.add_argument("--out", required=True, metavar="HTML", help="the HTML page to write")
    markdown.set_defaults(func=_markdown)
    table = pages.add_parser(
        "table",
        help="a processed table as a browsable HTML table",
        **_example("table"),
    )
    table.add_argument("table", metavar="CSV", help="the processed table (e.g. trials.csv)")
    table.add_argument("--out", required=True, metavar="HTML", help="the HTML page to write")
    table.add_argument("--title", help="the heading (default: the file's name)")
    table.set_defaults(func=_table)
    # The claims under each modelling variant.
    _add_variant_pages(pages)


def _add_variant_pages(pages) -> None:
    """Add ``claims`` and ``robustness`` to the subcommands of ``casa report``."""
    claims = pages.add_parser(
        "claims",
        help="one modelling variant's claims as a table (claim, variant, verdict, value)",
        **example(*_CLAIMS_EXAMPLE),
    )
    add_claim_options(claims)
    claims.add_argument("--variant", required=True, help="the variant's name")
    claims.add_argument(
        "--config", metavar="YAML", help="the variant's config, for its settings (optional)"
    )
    claims.add_argument("--out", required=True, metavar="CSV", help="claims.csv to write")
    claims.set_defaults(func=_claims)
    merge = pages.add_parser(
        "robustness",
        help="the variants' claims in one table, its results.md and the figure",
        **example(*_MERGE_EXAMPLE),
    )
    merge.add_argument(
        "--claims", required=True, nargs="+", metavar="CSV", help="each variant's claims.csv"
    )
    merge.add_argument("--out-csv", required=True, metavar="CSV", help="the merged table")
    merge.add_argument("--out-md", required=True, metavar="MD", help="results.md to write")
    merge.add_argument(
        "--figure", required=True, metavar="PREFIX", help="writes PREFIX.pdf and PREFIX.png"
    )
    provenance_options(merge)
    merge.set_defaults(func=_robustness)


def _summary(args) -> int:
    from casa_core.io.atomic import atomic_write_text
    from casa_core.report import pages as report_pages
    from casa_core.stats.summary import summary_markdown

    try:
        text = summary_markdown(
            read_table(args.stats), dataset=args.dataset, left_out=left_out(args)
        )
    except (OSError, ValueError) as error:
        return fail("report", error)
    atomic_write_text(args.out_md, text)
    title = f"Results of dataset {args.dataset}"
    atomic_write_text(
        args.out_html, report_pages.page(report_pages.markdown_html(text), title=title)
    )
    print(f"casa report: {args.out_md}, {args.out_html}")
    return 0


def _results(args) -> int:
    from casa_core.io.atomic import atomic_write_text
    from casa_core.report import pages as report_pages
    from casa_core.stats.claims import evaluate_claims
    from casa_core.stats.results import results_markdown

    try:
        built = provenance(args)
        tables = read_claim_tables(args)
        claims = evaluate_claims(tables, epsilon=args.epsilon)
        text = results_markdown(
            claims,
            tables,
            dataset=args.dataset,
            operator=args.operator,
            population=args.population,
            setup=args.setup,
            provenance=built.line() if built else "",
            left_out=left_out(args),
        )
    except (OSError, ValueError) as error:
        return fail("report", error)
    atomic_write_text(args.out, text)
    written = [args.out]
    if args.out_html:
        title = f"Claims of the paper on dataset {args.dataset}"
        page = report_pages.page(report_pages.markdown_html(text), title=title)
        atomic_write_text(args.out_html, page)
        written.append(args.out_html)
    verdicts = ", ".join(f"{r.claim} {r.verdict}" for r in claims.itertuples())
    print(f"casa report: {verdicts} -> {', '.join(written)}")
    return 0


def _markdown(args) -> int:
    from casa_core.io.atomic import atomic_write_text
    from casa_core.report import pages as report_pages

    try:
        text = Path(args.markdown).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        return fail("report", error)
    body = report_pages.markdown_html(text)
    atomic_write_text(args.out, report_pages.page(body, title=Path(args.markdown).name))
    print(f"casa report: {args.out}")
    return 0


def _table(args) -> int:
    from casa_core.io.atomic import atomic_write_text
    from casa_core.report import pages as report_pages

    try:
        frame = read_table(args.table)
    except (OSError, ValueError) as error:
        return fail("report", error)
    title = args.title or Path(args.table).name
    note = f"{len(frame)} row(s) of {args.table}."
    body = report_pages.table_html(frame, title=title, note=note)
    atomic_write_text(args.out, report_pages.page(body, title=title))
    print(f"casa report: {len(frame)} row(s) -> {args.out}")
    return 0


def _claims(args) -> int:
    from casa_core.io.atomic import write_csv
    from casa_core.stats.claims import evaluate_claims
    from casa_core.stats.robustness import variant_claims

    settings = ""
    if args.config:
        # A ConfigError names the file and the key (exit status 2, casa_core/cli/__init__.py).
        from casa_core.config import load_config
        from casa_core.experiments.robustness import settings_text

        settings = settings_text(load_config(args.config))
    try:
        tables = read_claim_tables(args)
        claims = evaluate_claims(tables, epsilon=args.epsilon)
    except (OSError, ValueError) as error:
        return fail("report", error)
    rows = variant_claims(claims, variant=args.variant, settings=settings)
    write_csv(args.out, rows)
    verdicts = ", ".join(f"{r.claim} {r.verdict}" for r in rows.itertuples())
    print(f"casa report claims: {args.variant}: {verdicts} -> {args.out}")
    return 0


def _robustness(args) -> int:
    from casa_core.figures.robustness import robustness_figure
    from casa_core.figures.style import save_figure
    from casa_core.io.atomic import atomic_write_text, write_csv
    from casa_core.stats.robustness import merge_variants, robustness_markdown

    try:
        built = provenance(args)
        merged = merge_variants([read_table(path) for path in args.claims])
        text = robustness_markdown(merged, provenance=built.line() if built else "")
        fig = robustness_figure(merged)
    except (OSError, ValueError) as error:
        return fail("report", error)
    if built:
        # A constant column: the table names its configuration and stays the same bytes
        # between two runs of it.
        merged = merged.assign(config=built.label)
    write_csv(args.out_csv, merged)
    atomic_write_text(args.out_md, text)
    written = [args.out_csv, args.out_md, *map(str, save_figure(fig, args.figure))]
    variants = merged["variant"].nunique()
    print(f"casa report robustness: {variants} variant(s) -> {', '.join(written)}")
    return 0
