"""``casa report``: the pages of the HTML report (``snakemake --report``) from the tables."""

from __future__ import annotations

from pathlib import Path

from casa_core.cli import robustness
from casa_core.cli._errors import fail
from casa_core.cli._options import example
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
    "data/processed/case_study/steps.csv --epsilon 1.0 "
    "--out data/processed/simulated/results.md --out-html data/report/simulated/results.html",
}


def _example(*pages: str) -> dict:
    """``add_parser`` keywords ending --help with the examples of ``pages``."""
    return example(*(line for page in pages for line in _EXAMPLES[page].split("\n")))


def register(commands) -> None:
    """Add this module's commands to the ``casa`` subcommands."""
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
    summary.add_argument("--out-md", required=True, metavar="MD", help="summary.md to write")
    summary.add_argument("--out-html", required=True, metavar="HTML", help="its HTML page")
    summary.set_defaults(func=_summary)
    results = pages.add_parser(
        "results",
        help="each claim of the paper with its criterion, the numbers and a verdict",
        **_example("results"),
    )
    robustness.add_claim_options(results)
    results.add_argument("--dataset", required=True, help="the dataset's name, for the title")
    results.add_argument(
        "--operator", help="the simulated operator model, named for a simulated dataset"
    )
    results.add_argument("--out", required=True, metavar="MD", help="results.md to write")
    results.add_argument("--out-html", metavar="HTML", help="its HTML page (optional)")
    results.set_defaults(func=_results)
    markdown = pages.add_parser(
        "markdown",
        help="a Markdown file (e.g. stats.md) as HTML",
        **_example("markdown"),
    )
    markdown.add_argument("markdown", metavar="MD")
    markdown.add_argument("--out", required=True, metavar="HTML")
    markdown.set_defaults(func=_markdown)
    table = pages.add_parser(
        "table",
        help="a processed table as a browsable HTML table",
        **_example("table"),
    )
    table.add_argument("table", metavar="CSV")
    table.add_argument("--out", required=True, metavar="HTML")
    table.add_argument("--title", help="the heading (default: the file's name)")
    table.set_defaults(func=_table)
    # The claims under each modelling variant (casa_core/cli/robustness.py).
    robustness.register_pages(pages)


def _summary(args) -> int:
    from casa_core.io.atomic import atomic_write_text
    from casa_core.report import pages as report_pages
    from casa_core.stats.summary import summary_markdown

    try:
        text = summary_markdown(read_table(args.stats), dataset=args.dataset)
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
        tables = robustness.read_claim_tables(args)
        claims = evaluate_claims(tables, epsilon=args.epsilon)
        text = results_markdown(claims, tables, dataset=args.dataset, operator=args.operator)
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
