"""The user study's analysis (paper Section "Analysis", hypotheses H1-H4) as one tidy table.

Every analysis the paper reports is reproduced in the paper's form -- each
participant-condition an independent observation, which gives its F(2, 30), F(2, 62) and
F(1, 41) with 11 participants (NOTES section 2) -- and beside it in the form the
within-subjects design deserves (repeated-measures ANOVA, a mixed model with a participant
random intercept, paired non-inferiority).

Conditions follow the paper's words: NA, PBA, CASA (Known Goal), "CASA before learning" and
"CASA after learning" (Unknown Goal and Unknown Skill).  Several trials of one participant in
one condition are averaged first, so a participant-condition is one observation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from casa_core.stats import apa, between, within
from casa_core.stats._tables import numeric_column, require_columns
from casa_core.study.protocol import condition_of

STATS_COLUMNS = [
    "hypothesis",
    "analysis",
    "task",
    "metric",
    "term",
    "comparison",
    "statistic",
    "df1",
    "df2",
    "p",
    "effect_size",
    "estimate",
    "ci_low",
    "ci_high",
    "margin",
    "noninferior",
    "n",
    "note",
]
METRICS = ["error", "efficiency", "relative_effort", "effort"]
KNOWN = "known_goal"
MISSPECIFIED = ["unknown_goal", "unknown_skill"]
POOLED = "+".join(MISSPECIFIED)
CASA_BEFORE, CASA_AFTER = "CASA before learning", "CASA after learning"
# Level order: CASA first, so Tukey pairs and comparisons read "CASA vs NA".
CONDITION_ORDER = [
    "CASA",
    CASA_BEFORE,
    CASA_AFTER,
    "NA",
    "PBA",
    "NA after learning",
    "PBA after learning",
]
TRIAL_KEYS = ["participant", "task", "method", "phase"]
LIKERT_KEYS = [*TRIAL_KEYS, "question", "score"]
ALPHA = 0.05


def _conditions(table: pd.DataFrame, what: str) -> pd.DataFrame:
    """``table`` with ``method`` replaced by the condition label, unanalysed phases dropped."""
    require_columns(table, TRIAL_KEYS, what)
    out = table.copy()
    labels = [condition_of(m, p) for m, p in zip(out["method"], out["phase"], strict=True)]
    unknown = pd.Series(
        [lbl is not None and lbl not in CONDITION_ORDER for lbl in labels], out.index
    )
    if unknown.any():
        row = unknown.idxmax()
        raise ValueError(
            f"{what}: row {row}: method {table['method'][row]!r} in phase "
            f"{table['phase'][row]!r} is not one of NA, PBA, CASA"
            + (
                " (a missing method: was the text NA read as missing? use "
                "pandas.read_csv(..., keep_default_na=False))"
                if pd.isna(table["method"][row])
                else ""
            )
        )
    out["method"] = pd.Categorical(labels, categories=CONDITION_ORDER)
    out = out[out["method"].notna()]
    out["participant"] = out["participant"].astype(str)
    return out


def _cell_means(trials: pd.DataFrame, metric: str) -> pd.DataFrame:
    """One observation per participant, task and condition: the mean over repeated trials."""
    frame = trials[["participant", "task", "method", metric]].dropna(subset=[metric])
    return frame.groupby(["participant", "task", "method"], observed=True, as_index=False)[
        metric
    ].mean()


def _subset(cells: pd.DataFrame, tasks: list[str], conditions: list[str]) -> pd.DataFrame:
    chosen = cells[cells["task"].isin(tasks) & cells["method"].isin(conditions)].copy()
    chosen["method"] = chosen["method"].cat.set_categories(conditions)
    return chosen


class _Rows:
    """Collects rows of the stats table for one hypothesis, task and metric."""

    def __init__(self) -> None:
        self.rows: list[dict] = []

    def add(self, **values) -> None:
        row = {column: np.nan for column in STATS_COLUMNS}
        row.update({"comparison": "", "note": ""})
        row.update({k: v for k, v in values.items() if k in STATS_COLUMNS})
        self.rows.append(row)

    def terms(self, key: dict, table: pd.DataFrame, stat: str, effect: str, extra=None):
        for _, line in table.iterrows():
            note = line["note"]
            if extra is not None:
                note = "; ".join(x for x in (note, extra(line)) if x)
            self.add(
                **key,
                term=str(line["term"]),
                statistic=line[stat],
                df1=line["df1"],
                df2=line.get("df2", np.nan),
                p=line["p"],
                effect_size=line.get(effect, np.nan),
                n=line["n"],
                note=note,
            )

    def tukey(self, key: dict, table: pd.DataFrame) -> None:
        for _, line in table.iterrows():
            self.add(
                **key,
                term="method",
                comparison="" if pd.isna(line["A"]) else _versus(line["A"], line["B"]),
                p=line["p"],
                estimate=line["diff"],
                ci_low=line["ci_low"],
                ci_high=line["ci_high"],
                n=line["n_A"] + line["n_B"],
                note=line["note"],
            )

    def noninferiority(self, key: dict, table: pd.DataFrame, paired: bool) -> None:
        line = table.iloc[0]
        design = "paired by participant" if paired else "independent samples, as the paper"
        note = "; ".join(x for x in (line["note"], design) if x)
        verdict = line["noninferior"]
        self.add(
            **key,
            term="method",
            comparison=_versus(line["new"], line["reference"]),
            statistic=line["t"],
            df1=line["df"],
            p=line["p"],
            estimate=line["estimate"],
            ci_high=line["bound"],
            margin=line["margin"],
            noninferior=verdict if not pd.isna(verdict) else pd.NA,
            n=line["n_new"] + (0 if paired else line["n_reference"]),
            note=note,
        )


def _versus(a, b) -> str:
    return f"{a} vs {b}"


def _gg_note(line) -> str:
    return f"Greenhouse-Geisser p = {line['p_gg']:.4g}" if np.isfinite(line["p_gg"]) else ""


def _margin_for(margins: Mapping[str, float] | None, task: str, metric: str) -> float | None:
    if not margins:
        return None
    return margins.get(f"{task}:{metric}", margins.get(metric))


def _objective(
    out: _Rows, hyp, task_label, metric, data, conditions, covariate, margins, noninf=None
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
    """
    cells_by_metric = _prepare_trials(trials, list(metrics))
    out = _Rows()
    for metric, cells in cells_by_metric.items():
        known = [KNOWN]
        h1 = ["CASA", "NA", "PBA"]
        _objective(
            out,
            "H1",
            KNOWN,
            metric,
            _subset(cells, known, h1),
            h1,
            False,
            margins,
            noninf=("CASA", "PBA"),
        )
        h2 = [CASA_BEFORE, "NA", "PBA"]
        _objective(out, "H2", POOLED, metric, _subset(cells, MISSPECIFIED, h2), h2, True, margins)
        for task in MISSPECIFIED:
            _objective(
                out,
                "H2",
                task,
                metric,
                _subset(cells, [task], h2),
                h2,
                False,
                margins,
                noninf=(CASA_BEFORE, "NA"),
            )
        h3 = [CASA_AFTER, "NA"]
        _objective(out, "H3", POOLED, metric, _subset(cells, MISSPECIFIED, h3), h3, True, margins)
        for task in MISSPECIFIED:
            _objective(out, "H3", task, metric, _subset(cells, [task], h3), h3, False, margins)
    if likert is not None:
        _subjective(out, likert)
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


def _subjective(out: _Rows, likert: pd.DataFrame) -> None:
    require_columns(likert, LIKERT_KEYS, "likert table")
    frame = _conditions(likert, "likert table")
    frame["score"] = numeric_column(frame, "score", "likert table")
    questions = sorted(frame["question"].dropna().unique(), key=str)
    for task in [KNOWN, *MISSPECIFIED]:
        wanted = ["CASA", "NA", "PBA"] if task == KNOWN else [CASA_AFTER, CASA_BEFORE, "NA", "PBA"]
        target = "CASA" if task == KNOWN else CASA_AFTER
        for question in questions:
            data = frame[(frame["task"] == task) & (frame["question"] == question)]
            data = _subset(data, [task], wanted)
            key = {"hypothesis": "H4", "task": task, "metric": question}
            line = within.friedman(data, "score", "method", "participant").iloc[0]
            out.add(
                **key,
                analysis="friedman",
                term="method",
                statistic=line["Q"],
                df1=line["df1"],
                p=line["p"],
                effect_size=line["W"],
                n=line["n"],
                note=line["note"],
            )
            table = within.wilcoxon_holm(
                data, "score", "method", "participant", target, [c for c in wanted if c != target]
            )
            family = int(table["p_unc"].notna().sum())
            for _, row in table.iterrows():
                note = row["note"]
                if np.isfinite(row["p_unc"]):
                    note = f"p Holm-adjusted over {family}; unadjusted p = {row['p_unc']:.4g}"
                    note = "; ".join(x for x in (note, row["note"]) if x)
                out.add(
                    **key,
                    analysis="wilcoxon",
                    term="method",
                    comparison=_versus(row["A"], row["B"]),
                    statistic=row["V"],
                    p=row["p"],
                    effect_size=row["rbc"],
                    estimate=row["median_diff"],
                    n=row["n"],
                    note=note,
                )


_TITLES = {
    "H1": "H1: no misspecification (Known Goal)",
    "H2": "H2: misspecification, CASA before learning",
    "H3": "H3: misspecification, CASA after learning",
    "H4": "H4: subjective (Likert)",
}
_ANALYSIS_NAMES = {
    "anova": "ANOVA",
    "ancova": "ANCOVA (task as covariate)",
    "tukey": "Tukey HSD",
    "noninferiority": "non-inferiority",
    "rm_anova": "repeated-measures ANOVA",
    "mixedlm": "mixed model (participant intercept)",
    "friedman": "Friedman",
    "wilcoxon": "Wilcoxon signed-rank",
}


def _apa(row: pd.Series) -> str:
    """One result in APA style; skipped tests say why."""
    kind = row["analysis"]
    if kind in ("anova", "ancova", "rm_anova", "mixedlm", "friedman") and not np.isfinite(
        row["statistic"]
    ):
        return f"skipped: {row['note']}"
    if kind in ("anova", "ancova"):
        return f"{apa.f_test(row.statistic, row.df1, row.df2, row.p)}, ηp² = " + apa.proportion(
            row.effect_size
        )
    if kind == "rm_anova":
        return f"{apa.f_test(row.statistic, row.df1, row.df2, row.p)}, ηG² = " + apa.proportion(
            row.effect_size
        )
    if kind == "mixedlm":
        return apa.chi2_test(row.statistic, row.df1, row.p)
    if kind == "friedman":
        return f"{apa.chi2_test(row.statistic, row.df1, row.p)}, W = " + apa.proportion(
            row.effect_size
        )
    if (
        not np.isfinite(row["estimate"])
        and kind != "wilcoxon"
        or (kind == "wilcoxon" and not np.isfinite(row["statistic"]))
    ):
        return f"skipped: {row['note']}"
    if kind == "tukey":
        return (
            f"diff = {row.estimate:.3g}, 95% CI [{row.ci_low:.3g}, {row.ci_high:.3g}], "
            f"{apa.p_value(row.p)}"
        )
    if kind == "noninferiority":
        text = f"diff = {row.estimate:.3g}, one-sided 95% bound = {row.ci_high:.3g}"
        if np.isfinite(row["margin"]):
            verdict = "non-inferior" if row["noninferior"] else "not shown non-inferior"
            text += f"; margin {row.margin:.3g}: {verdict}, {apa.p_value(row.p)}"
        return text
    if kind == "wilcoxon":
        return f"V = {row.statistic:.4g}, {apa.p_value(row.p)} (Holm), r = " + apa.proportion(
            row.effect_size
        )
    return ""


def report_markdown(table: pd.DataFrame) -> str:
    """An APA-style Markdown report of the stats table from :func:`analyze_study`.

    One section per hypothesis, one table row per test, e.g.
    ``F(2, 30) = 104.93, p < .001, ηp² = .87``.

    Parameters
    ----------
    table : pandas.DataFrame
        The output of :func:`analyze_study` (or stats.csv read back).

    Returns
    -------
    str
        The Markdown text.
    """
    require_columns(table, STATS_COLUMNS, "stats table")
    # stats.csv read back with pandas turns empty text into NaN.
    table = table.fillna({"note": "", "comparison": "", "term": ""})
    lines = [
        "# CASA user study: statistics",
        "",
        "Paper form: each participant-condition an independent observation (ANOVA, ANCOVA, "
        "Tukey HSD, independent non-inferiority). Within-subjects form: repeated-measures "
        "ANOVA, a mixed model with a participant random intercept (Wald χ²) and paired "
        "non-inferiority. Non-inferiority reports the one-sided 95% upper bound of "
        "mean(CASA) - mean(reference), the smallest margin at which CASA is non-inferior "
        "(lower is better for every metric).",
    ]
    for hypothesis, title in _TITLES.items():
        part = table[table["hypothesis"] == hypothesis]
        if part.empty:
            continue
        lines += [
            "",
            f"## {title}",
            "",
            "| Task | Metric | Analysis | Term | Result |",
            "| --- | --- | --- | --- | --- |",
        ]
        for _, row in part.iterrows():
            term = row["comparison"] or row["term"]
            if row["analysis"] == "noninferiority" and "paired" in str(row["note"]):
                term += " (paired)"
            cells = [
                row["task"],
                row["metric"],
                _ANALYSIS_NAMES.get(row["analysis"], ""),
                term,
                _apa(row),
            ]
            lines.append("| " + " | ".join(str(c).replace("|", "/") for c in cells) + " |")
    return "\n".join(lines) + "\n"
