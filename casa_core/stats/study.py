"""The user study's analysis (paper Section "Analysis", hypotheses H1-H4) as one tidy table.

Every analysis the paper reports is reproduced in the paper's form -- each
participant-condition an independent observation, which gives its F(2, 30), F(2, 62) and
F(1, 41) with 11 participants -- and beside it in the form the within-subjects design
deserves (repeated-measures ANOVA, a mixed model with a participant random intercept,
paired non-inferiority); see docs/departures.md.

Conditions follow the paper's words (:data:`casa_core.vocabulary.CONDITIONS`): NA, PBA,
CASA (Known Goal), "CASA before learning" and "CASA after learning" (Unknown Goal and
Unknown Skill).  Several trials of one participant in one condition are averaged first, so
a participant-condition is one observation.  :mod:`casa_core.stats.apa` renders the table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from casa_core.stats import between, within
from casa_core.stats._rows import STATS_COLUMNS, Rows
from casa_core.tables import numeric_column, require_columns
from casa_core.vocabulary import (
    ANSWERED_BY,
    CASA_AFTER_LEARNING,
    CASA_BEFORE_LEARNING,
    CONDITIONS,
    KNOWN_TASK,
    METHODS,
    TASK_CONDITIONS,
    UNKNOWN_TASKS,
    condition_of,
)

METRICS = ["error", "efficiency", "relative_effort", "effort"]
#: The analyses over both misspecified tasks name their task so.
POOLED = "+".join(UNKNOWN_TASKS)
#: Level order: the CASA family first, so Tukey pairs and comparisons read "CASA vs NA".
CONDITION_ORDER = sorted(CONDITIONS, key=lambda c: not c.startswith("CASA"))
TRIAL_KEYS = ["participant", "task", "method", "phase"]
LIKERT_KEYS = [*TRIAL_KEYS, "question", "score"]
ALPHA = 0.05
#: Appended to the note of every H4 row computed from a model's answers.
MODEL_OUTPUT_NOTE = "answers are model output (simulated participants), not people's ratings"


def answered_by_model(likert: pd.DataFrame | None) -> bool:
    """Whether any Likert answer is a model's output (a simulated participant's).

    ``answered_by`` says so (``model``); a table without it, a ``source`` ``simulated``.

    Examples
    --------
    >>> answered_by_model(pd.DataFrame({"source": ["human", "simulated"]}))
    True
    >>> answered_by_model(pd.DataFrame({"answered_by": ["participant"]}))
    False
    """
    if likert is None or likert.empty:
        return False
    if "answered_by" in likert.columns:
        return bool((likert["answered_by"] == ANSWERED_BY["simulated"]).any())
    return "source" in likert.columns and bool((likert["source"] == "simulated").any())


def _condition(method, phase, row, what: str) -> str | None:
    """:func:`casa_core.vocabulary.condition_of`, its error naming the table and row."""
    try:
        return condition_of(method, phase)
    except ValueError:
        hint = (
            " (a missing method: was the text NA read as missing? use "
            "pandas.read_csv(..., keep_default_na=False))"
            if pd.isna(method)
            else ""
        )
        raise ValueError(
            f"{what}: row {row}: method {method!r} in phase {phase!r} is not one of "
            f"{', '.join(METHODS)}{hint}"
        ) from None


def _conditions(table: pd.DataFrame, what: str) -> pd.DataFrame:
    """``table`` with ``method`` replaced by the condition label, unanalysed phases dropped."""
    require_columns(table, TRIAL_KEYS, what)
    out = table.copy()
    labels = [
        _condition(method, phase, row, what)
        for row, method, phase in zip(out.index, out["method"], out["phase"], strict=True)
    ]
    out["method"] = pd.Categorical(labels, categories=CONDITION_ORDER)
    out = out[out["method"].notna()]
    out["participant"] = out["participant"].astype(str)
    return out


def _cell_means(trials: pd.DataFrame, metric: str) -> pd.DataFrame:
    """One observation per participant, task and condition: the mean over repeated trials."""
    frame = trials[["participant", "task", "method", metric]].dropna(subset=[metric])
    keys = ["participant", "task", "method"]
    means = frame.groupby(keys, observed=True, as_index=False)[metric].mean()
    overflow = ~np.isfinite(means[metric].to_numpy(dtype=float))
    if overflow.any():
        # Sums of values near the float maximum overflow; the means of scaled values do not.
        scale = float(frame[metric].abs().max())
        scaled = frame.assign(**{metric: frame[metric] / scale})
        again = scaled.groupby(keys, observed=True, as_index=False)[metric].mean()
        means.loc[overflow, metric] = again.loc[overflow, metric] * scale
    return means


def _subset(cells: pd.DataFrame, tasks: list[str], conditions: list[str]) -> pd.DataFrame:
    chosen = cells[cells["task"].isin(tasks) & cells["method"].isin(conditions)].copy()
    chosen["method"] = chosen["method"].cat.set_categories(conditions)
    return chosen


def _gg_note(line) -> str:
    return f"Greenhouse-Geisser p = {line['p_gg']:.4g}" if np.isfinite(line["p_gg"]) else ""


def _margin_for(margins: Mapping[str, float] | None, task: str, metric: str) -> float | None:
    if not margins:
        return None
    return margins.get(f"{task}:{metric}", margins.get(metric))


def _objective(
    out: Rows, hyp, task_label, metric, data, conditions, covariate, margins, noninf=None
) -> None:
    """The paper's test and its repeated-measures counterparts on one subset of cells."""
    key = {"hypothesis": hyp, "task": task_label, "metric": metric}
    first = len(out.rows)
    _objective_rows(out, key, metric, data, conditions, covariate, margins, noninf)
    # Say plainly what is missing: an absent task or condition explains skipped tests.
    absent = [c for c in conditions if not (data["method"] == c).any()]
    if data.empty:
        remark = f"no trials of {task_label} in conditions {', '.join(conditions)}"
    elif absent:
        remark = f"missing condition(s): {', '.join(absent)}"
    else:
        return
    for row in out.rows[first:]:
        row["note"] = "; ".join(x for x in (remark, row["note"]) if x)


def _objective_rows(out, key, metric, data, conditions, covariate, margins, noninf) -> None:
    task_label = key["task"]
    if covariate:
        out.terms(
            key | {"analysis": "ancova"}, between.ancova(data, metric, "method", "task"), "F", "np2"
        )
    else:
        out.terms(key | {"analysis": "anova"}, between.anova(data, metric, "method"), "F", "np2")
    if len(conditions) > 2:
        out.tukey(key | {"analysis": "tukey"}, between.tukey_hsd(data, metric, "method"))
    factors = ["method", "task"] if covariate else "method"
    out.terms(
        key | {"analysis": "rm_anova"},
        within.rm_anova(data, metric, factors, "participant"),
        "F",
        "ng2",
        _gg_note,
    )
    out.terms(
        key | {"analysis": "mixedlm"},
        within.mixedlm(data, metric, factors, "participant"),
        "chi2",
        "none",
    )
    if noninf is not None:
        new, reference = noninf
        margin = _margin_for(margins, task_label, metric)
        for paired in (False, True):
            table = between.non_inferiority(
                data,
                metric,
                "method",
                new,
                reference,
                lower_is_better=True,
                alpha=ALPHA,
                margin=margin,
                subject="participant" if paired else None,
            )
            out.noninferiority(key | {"analysis": "noninferiority"}, table, paired)


def analyze_study(
    trials: pd.DataFrame,
    likert: pd.DataFrame | None = None,
    *,
    margins: Mapping[str, float] | None = None,
    metrics: Sequence[str] = tuple(METRICS),
) -> pd.DataFrame:
    """Every analysis of hypotheses H1-H4, in the paper's form and the within-subjects form.

    Parameters
    ----------
    trials : pandas.DataFrame
        The processed trials table (columns ``participant, task, method, phase`` and the
        metrics ``error, efficiency, relative_effort, effort``; all lower is better).
    likert : pandas.DataFrame, optional
        The processed Likert table (``participant, task, method, phase, question, score``).
    margins : mapping, optional
        Non-inferiority margins, keyed by ``"task:metric"`` or by ``metric``.  Without a
        margin the non-inferiority rows report the bound only (the paper's numbers).
    metrics : sequence of str
        The trials-table columns to analyse, by default all four (each must exist).

    Returns
    -------
    pandas.DataFrame
        The stats.csv table, columns :data:`STATS_COLUMNS`.  ``statistic`` is F (anova,
        ancova, rm_anova), the Wald chi-square (mixedlm), t at the margin (noninferiority),
        Friedman's chi-square (friedman) or V (wilcoxon); ``effect_size`` is partial eta
        squared (anova, ancova), generalized eta squared (rm_anova), Kendall's W (friedman)
        or the rank-biserial correlation (wilcoxon); on non-inferiority rows ``ci_high`` is
        the one-sided 95 % upper bound of ``estimate = mean(CASA) - mean(reference)``.
        Skipped tests keep their row with NaN statistics and the reason in ``note``.

    Raises
    ------
    ValueError
        Naming the column or row: a missing column, a value that is not a number, a
        method that is not one of :data:`casa_core.vocabulary.METHODS`.

    Notes
    -----
    H1, Known Goal: ANOVA over NA, PBA, CASA; Tukey; non-inferiority CASA vs PBA.
    H2, Unknown Goal and Skill: ANCOVA over CASA before learning, NA, PBA with task as
    covariate; Tukey; per task ANOVA, Tukey and non-inferiority CASA before learning vs NA.
    H3: ANCOVA NA vs CASA after learning with task as covariate; per task ANOVA.
    Each with a repeated-measures ANOVA (method, or method x task) and a mixed model.
    H4: per task and question, Friedman over the conditions and Wilcoxon signed-rank tests
    of CASA (after learning, for the misspecified tasks) against each other condition,
    Holm-corrected.

    Examples
    --------
    Four participants of the Known Goal task; the other hypotheses keep skipped rows.
    The non-inferiority rows are the independent (paper) test, then the paired one.

    >>> errors = {"NA": [3.0, 3.4, 2.9, 3.7], "PBA": [2.1, 2.6, 2.4, 2.3],
    ...           "CASA": [1.2, 1.9, 1.4, 1.3]}
    >>> trials = pd.DataFrame(
    ...     [{"participant": f"P{i}", "task": "known_goal", "method": method,
    ...       "phase": "no_misspecification", "error": value}
    ...      for method, values in errors.items() for i, value in enumerate(values)])
    >>> table = analyze_study(trials, metrics=["error"])
    >>> h1 = table[table["hypothesis"] == "H1"]
    >>> h1[["analysis", "comparison", "statistic", "df1", "df2", "estimate"]].round(2)
             analysis   comparison  statistic  df1  df2  estimate
    0           anova                   35.13  2.0  9.0       NaN
    1           tukey   CASA vs NA        NaN  NaN  NaN      -1.8
    2           tukey  CASA vs PBA        NaN  NaN  NaN      -0.9
    3           tukey    NA vs PBA        NaN  NaN  NaN       0.9
    4        rm_anova                   57.18  2.0  6.0       NaN
    5         mixedlm                  114.35  2.0  NaN       NaN
    6  noninferiority  CASA vs PBA        NaN  6.0  NaN      -0.9
    7  noninferiority  CASA vs PBA        NaN  3.0  NaN      -0.9
    >>> print(table[table["hypothesis"] == "H3"]["note"].iloc[0])  # doctest: +ELLIPSIS
    no trials of unknown_goal+unknown_skill in conditions CASA after learning, NA; ...
    """
    cells_by_metric = _prepare_trials(trials, list(metrics))
    out = Rows()
    for metric, cells in cells_by_metric.items():
        known = [KNOWN_TASK]
        h1 = sorted(TASK_CONDITIONS[KNOWN_TASK])
        _objective(
            out,
            "H1",
            KNOWN_TASK,
            metric,
            _subset(cells, known, h1),
            h1,
            False,
            margins,
            noninf=("CASA", "PBA"),
        )
        misspecified = list(UNKNOWN_TASKS)
        h2 = [CASA_BEFORE_LEARNING, "NA", "PBA"]
        _objective(out, "H2", POOLED, metric, _subset(cells, misspecified, h2), h2, True, margins)
        for task in misspecified:
            _objective(
                out,
                "H2",
                task,
                metric,
                _subset(cells, [task], h2),
                h2,
                False,
                margins,
                noninf=(CASA_BEFORE_LEARNING, "NA"),
            )
        h3 = [CASA_AFTER_LEARNING, "NA"]
        _objective(out, "H3", POOLED, metric, _subset(cells, misspecified, h3), h3, True, margins)
        for task in misspecified:
            _objective(out, "H3", task, metric, _subset(cells, [task], h3), h3, False, margins)
    if likert is not None:
        first = len(out.rows)
        _subjective(out, likert)
        if answered_by_model(likert):
            for row in out.rows[first:]:
                row["note"] = "; ".join(x for x in (row["note"], MODEL_OUTPUT_NOTE) if x)
    table = pd.DataFrame(out.rows, columns=STATS_COLUMNS)
    table["noninferior"] = table["noninferior"].astype("boolean")
    table["n"] = table["n"].astype("Int64")
    return table


def _prepare_trials(trials: pd.DataFrame, metrics: list[str]) -> dict[str, pd.DataFrame]:
    require_columns(trials, [*TRIAL_KEYS, *metrics], "trials table")
    frame = _conditions(trials, "trials table")
    for metric in metrics:
        frame[metric] = numeric_column(frame, metric, "trials table")
    return {metric: _cell_means(frame, metric) for metric in metrics}


def _subjective(out: Rows, likert: pd.DataFrame) -> None:
    require_columns(likert, LIKERT_KEYS, "likert table")
    frame = _conditions(likert, "likert table")
    frame["score"] = numeric_column(frame, "score", "likert table")
    questions = sorted(frame["question"].dropna().unique(), key=str)
    for task in [KNOWN_TASK, *UNKNOWN_TASKS]:
        if task == KNOWN_TASK:
            wanted, target = sorted(TASK_CONDITIONS[task]), "CASA"
        else:
            wanted = sorted(TASK_CONDITIONS[task])
            target = CASA_AFTER_LEARNING
        for question in questions:
            data = frame[(frame["task"] == task) & (frame["question"] == question)]
            data = _subset(data, [task], wanted)
            key = {"hypothesis": "H4", "task": task, "metric": question}
            out.friedman(key, within.friedman(data, "score", "method", "participant").iloc[0])
            others = [c for c in wanted if c != target]
            out.wilcoxon(
                key,
                within.wilcoxon_holm(
                    data, "score", "method", "participant", target=target, others=others
                ),
            )
