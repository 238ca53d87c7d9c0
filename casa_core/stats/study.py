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

import functools
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from casa_core.io.contract import CONDITION_KEYS, SURVEY_COLUMNS
from casa_core.io.tables import numeric_column, require_columns
from casa_core.stats import between, noninferiority, posthoc, within
from casa_core.stats._rows import LEVEL_NOTE, STATS_COLUMNS, Rows, significant
from casa_core.stats.margins import Margins
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
#: Effort on a log scale, log(effort + 1) per trial, analysed with participant effects
#: only (rm_anova, mixedlm): the participant's own scale, without NA's constant 1.
LOG_EFFORT = "log_effort"
#: On the relative-effort rows that compare with NA (NA's is 1 by construction).
ONE_SAMPLE_NOTE = (
    "relative effort is 1 under NA by construction (effort over NA's), so NA has no "
    "variance and a comparison with NA is a one-sample test of the other condition in "
    "disguise (unequal variances: Levene's test rejects); see the log_effort rows"
)
#: The analyses over both misspecified tasks name their task so.
POOLED = "+".join(UNKNOWN_TASKS)
#: Level order: the CASA family first, so Tukey pairs and comparisons read "CASA vs NA".
CONDITION_ORDER = sorted(CONDITIONS, key=lambda c: not c.startswith("CASA"))
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
    require_columns(table, CONDITION_KEYS, what)
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


def _objective(
    out: Rows, hyp, task_label, metric, data, conditions, covariate, margins, noninf=None, **how
) -> None:
    """The paper's test and its repeated-measures counterparts on one subset of cells."""
    key = {"hypothesis": hyp, "task": task_label, "metric": metric}
    first = len(out.rows)
    _objective_rows(out, key, metric, data, conditions, covariate, margins, noninf, **how)
    if metric == "relative_effort" and _constant(data, "NA", metric):
        for row in out.rows[first:]:
            if row["analysis"] != "noninferiority":  # non_inferiority says so itself
                row["note"] = "; ".join(x for x in (row["note"], ONE_SAMPLE_NOTE) if x)
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


def _constant(data: pd.DataFrame, condition: str, metric: str) -> bool:
    values = data.loc[data["method"] == condition, metric].to_numpy(dtype=float)
    return len(values) > 1 and float(np.ptp(values)) == 0.0


def _objective_rows(out, key, metric, data, conditions, covariate, margins, noninf, **how):
    task_label = key["task"]
    if metric == LOG_EFFORT:
        _within_rows(out, key, metric, data, covariate, **how)
        return
    if covariate:
        ancova = key | {"analysis": "ancova"}
        out.terms(ancova, between.ancova(data, metric, "method", "task"), "F", "np2")
        out.terms(ancova, posthoc.interaction(data, metric, "method", "task"), "F", "np2")
    else:
        out.terms(key | {"analysis": "anova"}, between.anova(data, metric, "method"), "F", "np2")
    if len(conditions) > 2:
        # Pooled tasks: the pairs come from the ANCOVA model, whose residual excludes task.
        pairs = (
            posthoc.model_contrasts(data, metric, "method", "task")
            if covariate
            else between.tukey_hsd(data, metric, "method")
        )
        out.tukey(key | {"analysis": "tukey"}, pairs)
    _within_rows(out, key, metric, data, covariate, **how)
    if noninf is not None:
        new, reference = noninf
        # No margins: Margins() sets none, so the rows report the bound only.
        margin, why = (margins or Margins()).margin_in(data, task_label, metric, reference)
        alpha = margins.alpha if margins is not None else ALPHA
        level = LEVEL_NOTE.format(alpha)
        # The paper's pooled test first: stats.claims reads the first independent row.
        for paired, welch in ((False, False), (False, True), (True, False)):
            table = between.non_inferiority(
                data,
                metric,
                "method",
                new,
                reference,
                lower_is_better=True,
                alpha=alpha,
                margin=margin,
                subject="participant" if paired else None,
                welch=welch,
            )
            extra = "; ".join(x for x in (why, level) if x)
            out.noninferiority(key | {"analysis": "noninferiority"}, table, paired, welch, extra)
        fraction = margins.fraction_for(task_label, metric) if why else None
        if fraction is not None:
            # The margin is a fraction of an estimated mean: the ratio form counts its error.
            for paired in (False, True):
                table = noninferiority.ratio_non_inferiority(
                    data, metric, "method", new, reference, fraction=fraction, alpha=alpha,
                    subject="participant" if paired else None,
                )  # fmt: skip
                # stats.csv holds finite numbers: an unbounded bound is NaN, the note says so.
                table["bound"] = table["bound"].where(np.isfinite(table["bound"]))
                ratio = f"ratio margin 1 + {fraction:g}, Fieller bound; {level}"
                out.noninferiority(
                    key | {"analysis": "noninferiority_ratio"}, table, paired, not paired, ratio
                )


def _within_rows(out, key, metric, data, covariate, *, mixed_models: bool = True) -> None:
    """The within-subjects tests: repeated-measures ANOVA and the mixed model."""
    factors = ["method", "task"] if covariate else "method"
    out.repeated(
        key | {"analysis": "rm_anova"}, within.rm_anova(data, metric, factors, "participant")
    )
    if not mixed_models:
        return
    mixed = within.mixedlm(data, metric, factors, "participant")
    out.terms(key | {"analysis": "mixedlm"}, mixed, "F", "none")
    # The likelihood ratio of the same model, beside the reported small-sample F.
    lrt = mixed.drop(columns=["df1", "df2", "p"]).rename(columns={"lrt_df": "df1", "p_lrt": "p"})
    out.terms(key | {"analysis": "mixedlm_lrt"}, lrt, "chi2", "none")


def analyze_study(
    trials: pd.DataFrame,
    likert: pd.DataFrame | None = None,
    *,
    margins: Margins | Mapping[str, float] | None = None,
    metrics: Sequence[str] = tuple(METRICS),
    mixed_models: bool = True,
) -> pd.DataFrame:
    """Every analysis of hypotheses H1-H4, in the paper's form and the within-subjects form.

    Parameters
    ----------
    trials : pandas.DataFrame
        The processed trials table (columns ``participant, task, method, phase`` and the
        metrics ``error, efficiency, relative_effort, effort``; all lower is better).
    likert : pandas.DataFrame, optional
        The processed Likert table (``participant, task, method, phase, question, score``).
    margins : Margins or mapping, optional
        Non-inferiority margins (:class:`casa_core.stats.margins.Margins`, e.g. from the
        config's ``statistics`` section); a plain mapping is taken as absolute margins
        keyed by ``"task:metric"`` or by ``metric``.  Without a margin the
        non-inferiority rows report the bound only (the paper's numbers).
    metrics : sequence of str
        The trials-table columns to analyse, by default all four (each must exist).
    mixed_models : bool
        Fit the mixed models (the ``mixedlm`` and ``mixedlm_lrt`` rows). False leaves
        those rows out, for a caller that reads none of them: the power target's
        detections (:mod:`casa_core.stats.power`), where they are most of the time.

    Returns
    -------
    pandas.DataFrame
        The stats.csv table, columns :data:`STATS_COLUMNS`.  ``statistic`` is F (anova,
        ancova, rm_anova), the Kenward-Roger F (mixedlm), the likelihood-ratio chi-square
        (mixedlm_lrt), t (tukey rows of the
        pooled tasks, from the ANCOVA model), t at the margin (noninferiority),
        Friedman's chi-square (friedman) or V (wilcoxon); ``effect_size`` is partial eta
        squared (anova, ancova), generalized eta squared (rm_anova), Kendall's W (friedman)
        or the rank-biserial correlation (wilcoxon); on non-inferiority rows ``ci_high`` is
        the one-sided upper bound of ``estimate = mean(CASA) - mean(reference)`` at the
        margins' level (``Margins.alpha``, named in the note; the paper's 95 %); on
        ``noninferiority_ratio`` rows (a margin that is a fraction f of the reference
        mean) ``estimate`` is the ratio of the means, ``ci_high`` Fieller's bound and
        ``margin`` 1 + f, in Welch's and the paired form.
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
    covariate, the method x task interaction, and Tukey-adjusted comparisons from the
    ANCOVA model; per task ANOVA, Tukey and non-inferiority CASA before learning vs NA.
    H3: ANCOVA NA vs CASA after learning with task as covariate and the interaction; per
    task ANOVA. Each with a repeated-measures ANOVA (method, or method x task;
    Greenhouse-Geisser corrected, Mauchly's test reported) and a mixed model
    (likelihood-ratio tests, the interaction where tasks are pooled); effort also on a
    log scale, ``log_effort``, with these two only.
    H4: per task and question, Friedman over the conditions and Wilcoxon signed-rank tests
    of CASA (after learning, for the misspecified tasks) against each other condition,
    Holm-corrected.

    Examples
    --------
    Four participants of the Known Goal task; the other hypotheses keep skipped rows.
    The repeated-measures row is Greenhouse-Geisser corrected (df times epsilon); the
    mixed model's Kenward-Roger F is the uncorrected repeated-measures F, its likelihood
    ratio beside it; the non-inferiority rows are the independent (paper, pooled
    variance) test, Welch's, then the paired one.

    >>> errors = {"NA": [3.0, 3.4, 2.9, 3.7], "PBA": [2.1, 2.6, 2.4, 2.3],
    ...           "CASA": [1.2, 1.9, 1.4, 1.3]}
    >>> trials = pd.DataFrame(
    ...     [{"participant": f"P{i}", "task": "known_goal", "method": method,
    ...       "phase": "no_misspecification", "error": value}
    ...      for method, values in errors.items() for i, value in enumerate(values)])
    >>> table = analyze_study(trials, metrics=["error"])
    >>> h1 = table[table["hypothesis"] == "H1"]
    >>> h1[["analysis", "comparison", "statistic", "df1", "df2", "estimate"]].round(2)
             analysis   comparison  statistic   df1   df2  estimate
    0           anova                   35.13  2.00  9.00       NaN
    1           tukey   CASA vs NA        NaN   NaN   NaN      -1.8
    2           tukey  CASA vs PBA        NaN   NaN   NaN      -0.9
    3           tukey    NA vs PBA        NaN   NaN   NaN       0.9
    4        rm_anova                   57.18  1.16  3.49       NaN
    5         mixedlm                   57.18  2.00  6.00       NaN
    6     mixedlm_lrt                   27.72  2.00   NaN       NaN
    7  noninferiority  CASA vs PBA        NaN  6.00   NaN      -0.9
    8  noninferiority  CASA vs PBA        NaN  5.24   NaN      -0.9
    9  noninferiority  CASA vs PBA        NaN  3.00   NaN      -0.9
    >>> print(table[table["hypothesis"] == "H3"]["note"].iloc[0])  # doctest: +ELLIPSIS
    no trials of unknown_goal+unknown_skill in conditions CASA after learning, NA; ...
    """
    if margins is not None and not isinstance(margins, Margins):
        margins = Margins(absolute=dict(margins))
    cells_by_metric = _prepare_trials(trials, list(metrics))
    out = Rows()
    objective = functools.partial(_objective, mixed_models=mixed_models)
    for metric, cells in cells_by_metric.items():
        known = [KNOWN_TASK]
        h1 = sorted(TASK_CONDITIONS[KNOWN_TASK])
        objective(
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
        objective(out, "H2", POOLED, metric, _subset(cells, misspecified, h2), h2, True, margins)
        for task in misspecified:
            objective(
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
        objective(out, "H3", POOLED, metric, _subset(cells, misspecified, h3), h3, True, margins)
        for task in misspecified:
            objective(out, "H3", task, metric, _subset(cells, [task], h3), h3, False, margins)
    if likert is not None:
        first = len(out.rows)
        _subjective(out, likert)
        if answered_by_model(likert):
            for row in out.rows[first:]:
                row["note"] = "; ".join(x for x in (row["note"], MODEL_OUTPUT_NOTE) if x)
    table = significant(pd.DataFrame(out.rows, columns=STATS_COLUMNS))
    table["noninferior"] = table["noninferior"].astype("boolean")
    table["n"] = table["n"].astype("Int64")
    return table


def _prepare_trials(trials: pd.DataFrame, metrics: list[str]) -> dict[str, pd.DataFrame]:
    require_columns(trials, [*CONDITION_KEYS, *metrics], "trials table")
    frame = _conditions(trials, "trials table")
    for metric in metrics:
        frame[metric] = numeric_column(frame, metric, "trials table")
    if "effort" in metrics:
        # Per trial, before averaging: a participant's cell mean of logs.
        with np.errstate(invalid="ignore", divide="ignore"):
            frame[LOG_EFFORT] = np.log1p(frame["effort"].where(frame["effort"] >= 0))
        metrics = [*metrics, LOG_EFFORT]
    return {metric: _cell_means(frame, metric) for metric in metrics}


def _subjective(out: Rows, likert: pd.DataFrame) -> None:
    require_columns(likert, SURVEY_COLUMNS, "likert table")
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
