"""The results at a glance: per hypothesis, the paper-form test beside the within-subjects one.

A few rows of ``stats.csv`` -- each hypothesis' omnibus test of the method, per measure --
rendered by :mod:`casa_core.stats.apa`, so that the report opens on results and every
number shown is read from the table the pipeline wrote.  ``stats.md`` has every test.
"""

from __future__ import annotations

import pandas as pd

from casa_core.io.tables import require_columns
from casa_core.stats.apa import ANALYSIS_NAMES, TITLES, model_output_lines, result
from casa_core.stats.study import LOG_EFFORT, POOLED, STATS_COLUMNS
from casa_core.vocabulary import KNOWN_TASK, QUESTION_LABELS, TASK_LABELS

#: Per hypothesis: the task label of its rows, the paper's test, the within-subjects test.
#: H2 and H3 pool both misspecified tasks (task as covariate), as the paper does; the
#: Likert tests (H4) are not in the paper.
TESTS = {
    "H1": (KNOWN_TASK, "anova", "rm_anova"),
    "H2": (POOLED, "ancova", "rm_anova"),
    "H3": (POOLED, "ancova", "rm_anova"),
    "H4": (None, None, "friedman"),
}
#: What the summary calls each measure.
MEASURES = {
    "error": "error",
    "efficiency": "efficiency cost",
    "relative_effort": "effort relative to NA",
    "effort": "effort (presses: keys, or device axes leaving the deadzone)",
    LOG_EFFORT: "log(effort + 1), participant effects",
    **{question: f"Likert: {label}" for question, label in QUESTION_LABELS.items()},
}
SUMMARY_COLUMNS = ["hypothesis", "task", "measure", "paper", "within"]
_NOT_IN_PAPER = "not tested in the paper"
_HEADERS = {
    "task": "Task",
    "measure": "Measure",
    "paper": "Paper form",
    "within": "Within subjects",
}


def _task_label(task: str) -> str:
    return " + ".join(TASK_LABELS.get(part, part) for part in str(task).split("+"))


def _test(rows: pd.DataFrame, analysis: str | None) -> str:
    """The method term of ``analysis`` among ``rows`` as "name: APA result"."""
    if analysis is None:
        return _NOT_IN_PAPER
    chosen = rows[(rows["analysis"] == analysis) & (rows["term"] == "method")]
    if chosen.empty:
        return "no such test in stats.csv"
    return f"{ANALYSIS_NAMES[analysis]}: {result(chosen.iloc[0])}"


def summary_table(stats: pd.DataFrame) -> pd.DataFrame:
    """One row per hypothesis and measure: the paper-form test and the within-subjects test.

    Parameters
    ----------
    stats : pandas.DataFrame
        The stats table (:func:`casa_core.stats.analyze_study`, or ``stats.csv`` read back).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`SUMMARY_COLUMNS`: the hypothesis, the task (display name), the
        measure (:data:`MEASURES`) and the two tests as APA text
        (:func:`casa_core.stats.apa.result`), for the tests of :data:`TESTS`.

    Raises
    ------
    ValueError
        Naming the columns the table lacks.

    Examples
    --------
    >>> row = dict.fromkeys(STATS_COLUMNS, float("nan")) | {
    ...     "hypothesis": "H1", "analysis": "anova", "task": "known_goal", "metric": "error",
    ...     "term": "method", "comparison": "", "statistic": 41.19, "df1": 2.0, "df2": 9.0,
    ...     "p": 3.0e-5, "effect_size": 0.9015, "note": ""}
    >>> within = row | {"analysis": "rm_anova", "statistic": 20.5, "df2": 6.0, "p": 0.002}
    >>> summary = summary_table(pd.DataFrame([row, within]))
    >>> summary.iloc[0].to_dict()  # doctest: +NORMALIZE_WHITESPACE
    {'hypothesis': 'H1', 'task': 'Known Goal', 'measure': 'error',
     'paper': 'ANOVA: F(2, 9) = 41.19, p < .001, ηp² = .90',
     'within': 'repeated-measures ANOVA: F(2, 6) = 20.50, p = .002, ηG² = .90'}
    """
    require_columns(stats, STATS_COLUMNS, "stats table")
    # stats.csv read back turns empty text into NaN (a float column when all are empty).
    text = ["note", "comparison", "term"]
    table = stats.astype(dict.fromkeys(text, object)).fillna(dict.fromkeys(text, ""))
    rows = []
    for hypothesis, (task, paper, within) in TESTS.items():
        part = table[table["hypothesis"] == hypothesis]
        if task is not None:
            part = part[part["task"] == task]
        for (task_name, metric), group in part.groupby(["task", "metric"], sort=False):
            rows.append(
                {
                    "hypothesis": hypothesis,
                    "task": _task_label(task_name),
                    "measure": MEASURES.get(metric, metric),
                    # log effort is analysed within subjects only.
                    "paper": _test(group, None if metric == LOG_EFFORT else paper),
                    "within": _test(group, within),
                }
            )
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def summary_markdown(stats: pd.DataFrame, *, dataset: str, left_out: str = "") -> str:
    """The summary of one dataset's statistics as Markdown: one table per hypothesis.

    Parameters
    ----------
    stats : pandas.DataFrame
        The dataset's stats table.
    dataset : str
        The dataset's name, for the title.
    left_out : str, optional
        As in :func:`casa_core.stats.apa.report_markdown`.

    Returns
    -------
    str
        Markdown: a title, a sentence on what the columns are, then per hypothesis that has
        rows its title (:data:`casa_core.stats.apa.TITLES`) and a table of
        :func:`summary_table`'s rows (the task above it when there is one only).

    Examples
    --------
    >>> row = dict.fromkeys(STATS_COLUMNS, float("nan")) | {
    ...     "hypothesis": "H4", "analysis": "friedman", "task": "known_goal",
    ...     "metric": "useful", "term": "method", "comparison": "", "statistic": 4.79,
    ...     "df1": 2.0, "p": 0.091, "effect_size": 0.22, "note": ""}
    >>> text = summary_markdown(pd.DataFrame([row]), dataset="pilot")
    >>> print(text.split("## ")[1])
    H4: subjective (Likert)
    <BLANKLINE>
    Task: Known Goal.
    <BLANKLINE>
    | Measure | Paper form | Within subjects |
    | --- | --- | --- |
    | Likert: Useful | not tested in the paper | Friedman: χ²(2) = 4.79, p = .091, W = .22 |
    <BLANKLINE>
    """
    summary = summary_table(stats)
    notes = stats.assign(note=stats["note"].astype(object).fillna(""))
    lines = [
        f"# Results of dataset {dataset}",
        "",
        *([left_out, ""] if left_out else []),
        "Per hypothesis and measure, the omnibus test of the method in the paper's form "
        "(each participant-condition an independent observation) and in the "
        "within-subjects form; every test, with the pairwise comparisons and "
        "non-inferiority bounds, is in stats.md.",
    ]
    for hypothesis, title in TITLES.items():
        part = summary[summary["hypothesis"] == hypothesis]
        if part.empty:
            continue
        lines += ["", f"## {title}", ""]
        lines += model_output_lines(notes[notes["hypothesis"] == hypothesis])
        # One task: said once above the table rather than on every row.
        one_task = part["task"].nunique() == 1
        columns = ["measure", "paper", "within"] if one_task else list(SUMMARY_COLUMNS[1:])
        if one_task:
            lines += [f"Task: {part['task'].iloc[0]}.", ""]
        lines.append("| " + " | ".join(_HEADERS[c] for c in columns) + " |")
        lines.append("|" + " --- |" * len(columns))
        for _, row in part.iterrows():
            cells = [str(row[c]).replace("|", "/") for c in columns]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
