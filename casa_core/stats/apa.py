"""APA-style rendering: numbers, p-values, test results and the Markdown report of stats.csv.

Every piece of text the statistics produce is written here, from one test
(``F(2, 30) = 104.93, p < .001``) to the report of the whole stats table
(:func:`report_markdown`, the study's ``stats.md``).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from casa_core.defaults import SIGNIFICANCE
from casa_core.io.tables import require_columns
from casa_core.stats.descriptives import data_lines
from casa_core.stats.study import MODEL_OUTPUT_NOTE, STATS_COLUMNS

#: Section titles of the report, one per hypothesis, in order.
TITLES = {
    "H1": "H1: no misspecification (Known Goal)",
    "H2": "H2: misspecification, CASA before learning",
    "H3": "H3: misspecification, CASA after learning",
    "H4": "H4: subjective (Likert)",
}
#: How the report names each ``analysis`` of the stats table.
ANALYSIS_NAMES = {
    "anova": "ANOVA",
    "ancova": "ANCOVA (task as covariate)",
    "tukey": "Tukey HSD",
    "noninferiority": "non-inferiority",
    "rm_anova": "repeated-measures ANOVA",
    "mixedlm": "mixed model (Kenward-Roger F)",
    "mixedlm_lrt": "mixed model (LR test)",
    "noninferiority_ratio": "non-inferiority, ratio margin",
    "friedman": "Friedman",
    "wilcoxon": "Wilcoxon signed-rank",
}
_INTRODUCTION = (
    "Paper form: each participant-condition an independent observation (ANOVA, ANCOVA "
    "with the method x task interaction beside it, Tukey HSD -- from the ANCOVA model "
    "where tasks are pooled -- and independent non-inferiority, pooled and Welch). "
    "Within-subjects form: repeated-measures ANOVA (Greenhouse-Geisser corrected where "
    "epsilon < 1, Mauchly's test in stats.csv), a mixed model with random intercepts per "
    "participant and, where tasks are pooled, per participant x method and participant x "
    "task (Kenward-Roger F, the likelihood-ratio χ² of ML fits beside it) and paired "
    "non-inferiority; effort also as log(effort + 1) with participant effects "
    "(log_effort). Non-inferiority reports the one-sided upper bound of mean(CASA) - "
    "mean(reference) at the configured level (stats.csv's note; the paper's: 95%), the "
    "smallest margin at which CASA is non-inferior (lower is better for every metric), "
    "and the test at the configured margin; where the margin is a fraction f of the "
    "reference mean, the ratio form tests mean(CASA) - (1 + f) mean(reference), Fieller's "
    "bound on the ratio beside it."
)


#: Said under H4's title when its answers are a model's output (:data:`MODEL_OUTPUT_NOTE`).
MODEL_OUTPUT_SENTENCE = (
    "The Likert answers are model output: simulated participants' answers computed by a "
    "formula (casa_core/study/likert.py), not people's ratings. These tests describe the "
    "model; they do not test H4."
)


def model_output_lines(rows: pd.DataFrame) -> list[str]:
    """``[sentence, ""]`` when any of ``rows`` (a hypothesis' rows) was computed from a model.

    Examples
    --------
    >>> model_output_lines(pd.DataFrame({"note": ["", MODEL_OUTPUT_NOTE]}))[0][:35]
    'The Likert answers are model output'
    """
    notes = rows["note"].fillna("").astype(str)
    model = notes.str.contains(MODEL_OUTPUT_NOTE, regex=False).any()
    return [MODEL_OUTPUT_SENTENCE, ""] if model else []


def _number(value: float, digits: int = 2) -> str:
    return f"{value:.{digits}f}"


def _df(value: float) -> str:
    """Degrees of freedom: integers as integers, corrected ones with two decimals."""
    if not math.isfinite(value):
        return "n/a"
    return str(int(round(value))) if abs(value - round(value)) < 1e-9 else f"{value:.2f}"


def _no_leading_zero(text: str) -> str:
    """APA drops the leading zero of quantities that cannot exceed 1 (p, eta squared, r)."""
    return text.replace("0.", ".", 1) if text.lstrip("-").startswith("0.") else text


def p_value(p: float) -> str:
    """``p < .001`` below one in a thousand, else ``p = .xxx``.

    Examples
    --------
    >>> p_value(0.0381), p_value(2e-5), p_value(float("nan"))
    ('p = .038', 'p < .001', 'p = n/a')
    """
    if not math.isfinite(p):
        return "p = n/a"
    if p < 0.001:
        return "p < .001"
    return "p = " + _no_leading_zero(f"{p:.3f}")


def proportion(value: float) -> str:
    """A bounded quantity (effect size) with APA's missing leading zero, two decimals.

    Examples
    --------
    >>> proportion(0.371), proportion(-0.5)
    ('.37', '-.50')
    """
    return _no_leading_zero(_number(value))


def f_test(f: float, df1: float, df2: float, p: float) -> str:
    """``F(df1, df2) = f, p ...``; corrected (non-integer) degrees of freedom keep 2 decimals.

    Examples
    --------
    >>> f_test(104.9312, 2, 30, 2e-14)
    'F(2, 30) = 104.93, p < .001'
    >>> f_test(6.119, 1.46, 14.6, 0.0183)
    'F(1.46, 14.60) = 6.12, p = .018'
    """
    return f"F({_df(df1)}, {_df(df2)}) = {_number(f)}, {p_value(p)}"


def chi2_test(chi2: float, df: float, p: float) -> str:
    """``χ²(df) = chi2, p ...``.

    Examples
    --------
    >>> chi2_test(7.2986, 2, 0.026)
    'χ²(2) = 7.30, p = .026'
    """
    return f"χ²({_df(df)}) = {_number(chi2)}, {p_value(p)}"


def result(row: pd.Series) -> str:
    """One row of the stats table as an APA result; a skipped test says why.

    Parameters
    ----------
    row : pandas.Series
        A row of :func:`casa_core.stats.analyze_study` (columns
        :data:`casa_core.stats.study.STATS_COLUMNS`).

    Returns
    -------
    str
        E.g. ``F(2, 30) = 104.93, p < .001, ηp² = .87`` or ``skipped: <the note>``.

    Examples
    --------
    >>> row = pd.Series({"analysis": "anova", "statistic": 41.19, "df1": 2.0, "df2": 9.0,
    ...                  "p": 3.0e-5, "effect_size": 0.9015, "note": ""})
    >>> result(row)
    'F(2, 9) = 41.19, p < .001, ηp² = .90'
    >>> skipped = row.copy()
    >>> skipped["statistic"], skipped["note"] = float("nan"), "zero variance"
    >>> result(skipped)
    'skipped: zero variance'
    """
    kind = row["analysis"]
    if kind in (
        "anova",
        "ancova",
        "rm_anova",
        "mixedlm",
        "mixedlm_lrt",
        "friedman",
    ) and not np.isfinite(row["statistic"]):
        return f"skipped: {row['note']}"
    if kind in ("anova", "ancova"):
        return f"{f_test(row.statistic, row.df1, row.df2, row.p)}, ηp² = " + proportion(
            row.effect_size
        )
    if kind == "rm_anova":
        return f"{f_test(row.statistic, row.df1, row.df2, row.p)}, ηG² = " + proportion(
            row.effect_size
        )
    if kind == "mixedlm":
        return f_test(row.statistic, row.df1, row.df2, row.p)
    if kind == "mixedlm_lrt":
        return chi2_test(row.statistic, row.df1, row.p)
    if kind == "friedman":
        return f"{chi2_test(row.statistic, row.df1, row.p)}, W = " + proportion(row.effect_size)
    if (
        not np.isfinite(row["estimate"])
        and kind != "wilcoxon"
        or (kind == "wilcoxon" and not np.isfinite(row["statistic"]))
    ):
        return f"skipped: {row['note']}"
    if kind == "tukey":
        return (
            f"diff = {row.estimate:.3g}, 95% CI [{row.ci_low:.3g}, {row.ci_high:.3g}], "
            f"{p_value(row.p)}"
        )
    if kind == "noninferiority_ratio":
        bound = f"{row.ci_high:.3g}" if np.isfinite(row.ci_high) else "unbounded"
        text = f"ratio = {row.estimate:.3g}, one-sided Fieller bound = {bound}"
        verdict = "non-inferior" if row["noninferior"] else "not shown non-inferior"
        return text + f"; margin {row.margin:.3g}: {verdict}, {p_value(row.p)}"
    if kind == "noninferiority":
        text = f"diff = {row.estimate:.3g}, one-sided bound = {row.ci_high:.3g}"
        if np.isfinite(row["margin"]):
            verdict = "non-inferior" if row["noninferior"] else "not shown non-inferior"
            text += f"; margin {row.margin:.3g}: {verdict}, {p_value(row.p)}"
        return text
    if kind == "wilcoxon":
        return f"V = {row.statistic:.4g}, {p_value(row.p)} (Holm), r = " + proportion(
            row.effect_size
        )
    return ""


def interaction_lines(rows: pd.DataFrame) -> list[str]:
    """``[sentence, ""]`` naming the metrics whose pooled method x task term is significant.

    The pooled comparisons of method then average effects that differ by task; the
    simple effects per task (the per-task rows) are what H2 and H3 ask.

    Examples
    --------
    >>> rows = pd.DataFrame({"analysis": ["ancova", "rm_anova"], "task": ["a+b"] * 2,
    ...     "metric": ["error"] * 2, "term": ["method x task", "method * task"],
    ...     "p": [0.006, 0.2]})
    >>> print(interaction_lines(rows)[0])  # doctest: +ELLIPSIS
    Method x task is significant on the pooled tasks for error (ANCOVA p = .006): ...
    """
    terms = {"ancova": "method x task", "rm_anova": "method * task"}
    said = []
    for metric in dict.fromkeys(rows["metric"]):
        found = [
            f"{ANALYSIS_NAMES[analysis].split(' (')[0]} {p_value(line.p)}"
            for analysis, term in terms.items()
            for line in rows[
                (rows["metric"] == metric)
                & (rows["analysis"] == analysis)
                & (rows["term"] == term)
                & rows["task"].astype(str).str.contains("+", regex=False)
            ].itertuples()
            if line.p < SIGNIFICANCE
        ]
        if found:
            said.append(f"{metric} ({', '.join(found)})")
    if not said:
        return []
    return [
        f"Method x task is significant on the pooled tasks for {'; '.join(said)}: the "
        "pooled comparisons of method average effects that differ by task, so the simple "
        "effects of method per task (the rows of each task below) are what the hypothesis "
        "asks, and results.md judges it by them.",
        "",
    ]


def report_markdown(
    table: pd.DataFrame, *, trials: pd.DataFrame | None = None, left_out: str = ""
) -> str:
    """An APA-style Markdown report of the stats table from :func:`analyze_study`.

    One section per hypothesis (:data:`TITLES`), one table row per test, e.g.
    ``F(2, 30) = 104.93, p < .001, ηp² = .87`` (:func:`result`).

    Parameters
    ----------
    table : pandas.DataFrame
        The output of :func:`casa_core.stats.analyze_study` (or stats.csv read back).
    trials : pandas.DataFrame, optional
        The trials table the statistics were computed from: the report then opens with
        the data's source, the number of participants and the mean ± SD of every metric
        per task and condition (:func:`casa_core.stats.descriptives.data_lines`).
    left_out : str, optional
        What the build left out (:func:`casa_core.stats.descriptives.left_out`), said
        under the title.

    Returns
    -------
    str
        The Markdown text.

    Examples
    --------
    >>> row = dict.fromkeys(STATS_COLUMNS, float("nan")) | {
    ...     "hypothesis": "H1", "analysis": "anova", "task": "known_goal",
    ...     "metric": "error", "term": "method", "comparison": "", "statistic": 41.19,
    ...     "df1": 2.0, "df2": 9.0, "p": 3.0e-5, "effect_size": 0.9015, "note": ""}
    >>> print(report_markdown(pd.DataFrame([row])).split("## ")[1])
    H1: no misspecification (Known Goal)
    <BLANKLINE>
    | Task | Metric | Analysis | Term | Result |
    | --- | --- | --- | --- | --- |
    | known_goal | error | ANOVA | method | F(2, 9) = 41.19, p < .001, ηp² = .90 |
    <BLANKLINE>
    """
    require_columns(table, STATS_COLUMNS, "stats table")
    # stats.csv read back with pandas turns empty text into NaN.
    table = table.fillna({"note": "", "comparison": "", "term": ""})
    lines = ["# CASA user study: statistics", ""]
    lines += [left_out, ""] if left_out else []
    if trials is not None:
        lines += data_lines(trials)
    lines.append(_INTRODUCTION)
    for hypothesis, title in TITLES.items():
        part = table[table["hypothesis"] == hypothesis]
        if part.empty:
            continue
        lines += [
            "",
            f"## {title}",
            "",
            *model_output_lines(part),
            *(interaction_lines(part) if hypothesis in ("H2", "H3") else []),
            "| Task | Metric | Analysis | Term | Result |",
            "| --- | --- | --- | --- | --- |",
        ]
        for _, row in part.iterrows():
            term = row["comparison"] or row["term"]
            noninferiority = row["analysis"].startswith("noninferiority")
            if noninferiority and "paired" in str(row["note"]):
                term += " (paired)"
            elif noninferiority and "Welch" in str(row["note"]):
                term += " (Welch)"
            cells = [
                row["task"],
                row["metric"],
                ANALYSIS_NAMES.get(row["analysis"], ""),
                term,
                result(row),
            ]
            lines.append("| " + " | ".join(str(c).replace("|", "/") for c in cells) + " |")
    return "\n".join(lines) + "\n"
