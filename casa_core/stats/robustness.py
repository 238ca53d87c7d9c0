"""The paper's claims under each modelling variant: one table, and its ``results.md``.

Each variant's claims (:func:`casa_core.stats.claims.evaluate_claims` on that variant's
simulated study) become rows of :data:`ROBUSTNESS_COLUMNS` by :func:`variant_claims`;
:func:`merge_variants` joins the variants' tables into
``data/processed/robustness/claims.csv`` and :func:`robustness_markdown` renders it.
"""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd

from casa_core.config import DEFAULT_VARIANT
from casa_core.io.tables import require_columns
from casa_core.stats.claims import CLAIM_COLUMNS

#: One row per claim and variant: the verdict, the number behind it, the variant's choices.
ROBUSTNESS_COLUMNS = ["claim", "variant", "verdict", "value", "settings", "criterion", "measured"]


def variant_claims(claims: pd.DataFrame, *, variant: str, settings: str = "") -> pd.DataFrame:
    """One variant's claims table as rows of :data:`ROBUSTNESS_COLUMNS`.

    Parameters
    ----------
    claims : pandas.DataFrame
        :func:`~casa_core.stats.claims.evaluate_claims` of the variant's tables.
    variant : str
        The variant's name.
    settings : str
        Its modelling choices in words (:func:`casa_core.experiments.robustness.settings_text`).

    Examples
    --------
    >>> claims = pd.DataFrame([{"claim": "C1", "statement": "s", "criterion": "c",
    ...     "measured": "m", "value": 1.0, "verdict": "holds", "details": ""}])
    >>> variant_claims(claims, variant="default")[["claim", "variant", "verdict", "value"]]
      claim  variant verdict  value
    0    C1  default   holds    1.0
    """
    require_columns(claims, CLAIM_COLUMNS, "claims table")
    rows = claims.assign(variant=variant, settings=settings)
    return rows[ROBUSTNESS_COLUMNS].reset_index(drop=True)


def merge_variants(tables: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """The variants' claims in one table: claims in their order, the default variant first.

    Raises
    ------
    ValueError
        If a table lacks a column, no table is given, or a claim appears twice for one
        variant (two tables of the same variant).

    Examples
    --------
    >>> row = {"criterion": "c", "measured": "m", "settings": ""}
    >>> a = pd.DataFrame([row | {"claim": "C1", "variant": "paper", "verdict": "differs",
    ...     "value": 0.2}])
    >>> b = pd.DataFrame([row | {"claim": "C1", "variant": "default", "verdict": "holds",
    ...     "value": 1.0}])
    >>> merge_variants([a, b])[["claim", "variant", "verdict"]]
      claim  variant  verdict
    0    C1  default    holds
    1    C1    paper  differs
    """
    if not tables:
        raise ValueError("robustness: no variant's claims given")
    for index, table in enumerate(tables):
        require_columns(table, ROBUSTNESS_COLUMNS, f"claims table {index + 1}")
    merged = pd.concat([t[ROBUSTNESS_COLUMNS] for t in tables], ignore_index=True)
    twice = merged[merged.duplicated(["claim", "variant"])]
    if not twice.empty:
        first = twice.iloc[0]
        raise ValueError(
            f"robustness: claim {first['claim']} of variant {first['variant']} is given "
            "twice; each variant's claims come from one table"
        )
    variants = list(dict.fromkeys(merged["variant"]))
    variants.sort(key=lambda name: name != DEFAULT_VARIANT)  # stable: the others keep order
    claims = list(dict.fromkeys(merged["claim"]))
    order = merged.assign(
        _claim=merged["claim"].map(claims.index), _variant=merged["variant"].map(variants.index)
    )
    order = order.sort_values(["_claim", "_variant"], kind="stable")
    return order[ROBUSTNESS_COLUMNS].reset_index(drop=True)


def _value(value) -> str:
    return "" if pd.isna(value) else f" ({float(value):.2f})"


def robustness_markdown(claims: pd.DataFrame, *, provenance: str = "") -> str:
    """``results.md`` of the robustness table: claims x variants, each variant's choices.

    ``provenance``, the configuration that built it
    (:meth:`casa_core.config.Provenance.line`), is written under the title.

    Examples
    --------
    >>> claims = pd.DataFrame([{"claim": "C1", "variant": v, "verdict": verdict,
    ...     "value": value, "settings": f"preset {v}", "criterion": "c", "measured": "m"}
    ...     for v, verdict, value in (("default", "holds", 1.0), ("paper", "partly", 0.6))])
    >>> table = robustness_markdown(claims).split("## Verdicts")[1].strip().splitlines()
    >>> for line in table[:3]:
    ...     print(line)
    | Claim | default (default) | paper |
    | --- | --- | --- |
    | C1 | holds (1.00) | partly (0.60) |
    """
    require_columns(claims, ROBUSTNESS_COLUMNS, "robustness claims table")
    variants = list(dict.fromkeys(claims["variant"]))
    heads = [f"{v} (default)" if v == DEFAULT_VARIANT else v for v in variants]
    settings = claims.drop_duplicates("variant").set_index("variant")["settings"]
    lines = ["# Claims of the paper under each modelling variant", ""]
    lines += [f"{provenance}.", ""] if provenance else []
    lines += [
        "The simulated study run once per variant, with the same participants and seeds in "
        "each; only the modelling choices below differ. Each claim is judged as in a "
        "dataset's results.md (casa_core/stats/claims.py); the number in brackets is the "
        "one behind the verdict (the share of trials or checks meeting the criterion). "
        f"The default variant, `{DEFAULT_VARIANT}`, is the study's own config. A variant's "
        "settings name its setup, the scene file and how its keys move the arm (teleop "
        "held or original, docs/departures.md), where the config names one.",
        "",
        "## Variants",
        "",
    ]
    lines += [f"- `{v}`{' (default)' * (v == DEFAULT_VARIANT)}: {settings[v]}" for v in variants]
    lines += ["", "## Verdicts", "", "| Claim | " + " | ".join(heads) + " |"]
    lines.append("| --- |" + " --- |" * len(variants))
    cells = claims.set_index(["claim", "variant"])
    for claim in dict.fromkeys(claims["claim"]):
        row = []
        for variant in variants:
            if (claim, variant) in cells.index:
                cell = cells.loc[(claim, variant)]
                row.append(f"{cell['verdict']}{_value(cell['value'])}")
            else:
                row.append("")
        lines.append(f"| {claim} | " + " | ".join(row) + " |")
    lines += ["", "## Measured", ""]
    for claim in dict.fromkeys(claims["claim"]):
        lines += [f"### {claim}", "", f"Criterion: {cells.xs(claim)['criterion'].iloc[0]}.", ""]
        for variant in variants:
            if (claim, variant) in cells.index:
                cell = cells.loc[(claim, variant)]
                lines.append(f"- `{variant}`: {cell['verdict']}; {cell['measured']}.")
        lines.append("")
    return "\n".join(lines)
