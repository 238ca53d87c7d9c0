"""``casa report claims`` and ``casa report robustness``: the claims under each variant.

``claims`` judges one variant's tables (:func:`casa_core.stats.claims.evaluate_claims`)
into a table with a ``variant`` column; ``robustness`` merges the variants' tables into
``claims.csv``, its ``results.md`` and the figure (workflow/rules/robustness.smk).
"""

from __future__ import annotations

from casa_core.cli._errors import fail
from casa_core.cli._options import example, positive_float
from casa_core.defaults import EPSILON
from casa_core.io import read_table

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
    "--out-md data/processed/robustness/results.md --figure figures/robustness",
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


def register_pages(pages) -> None:
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
    merge.set_defaults(func=_robustness)


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
        merged = merge_variants([read_table(path) for path in args.claims])
        text = robustness_markdown(merged)
        fig = robustness_figure(merged)
    except (OSError, ValueError) as error:
        return fail("report", error)
    write_csv(args.out_csv, merged)
    atomic_write_text(args.out_md, text)
    written = [args.out_csv, args.out_md, *map(str, save_figure(fig, args.figure))]
    variants = merged["variant"].nunique()
    print(f"casa report robustness: {variants} variant(s) -> {', '.join(written)}")
    return 0
