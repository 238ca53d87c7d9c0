"""The checks behind hypothesis H4 in :mod:`casa_core.stats.claims`, read from stats.csv.

Per misspecified task and question: in the paper's form, CASA after learning has the
highest mean score; within subjects, Friedman's test and the Holm-corrected Wilcoxon
tests of CASA after learning against each other condition favour it. Checks as in
:mod:`casa_core.stats._claim_tests`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.io.tables import numeric_column
from casa_core.stats._claim_tests import (
    OPPOSITE,
    Check,
    Part,
    _combine,
    _outcome,
    _rows,
    _significant,
    _text,
)
from casa_core.stats.study import _conditions
from casa_core.vocabulary import CASA_AFTER_LEARNING, UNKNOWN_TASKS


def likert_checks(stats: pd.DataFrame, likert: pd.DataFrame) -> list[Check]:
    """H4: per misspecified task and question, CASA after learning rated above the rest."""
    stats = _text(stats)
    frame = _conditions(likert, "likert table")
    frame["score"] = numeric_column(frame, "score", "likert table")
    checks = []
    for task in UNKNOWN_TASKS:
        for question in sorted(frame.loc[frame["task"] == task, "question"].unique()):
            part = frame[(frame["task"] == task) & (frame["question"] == question)]
            means = part.groupby("method", observed=True)["score"].mean()
            name = f"{task} {question}"
            if CASA_AFTER_LEARNING not in means.index or len(means) < 2:
                text = f"{name}: too few conditions: {_outcome(None, 'too few conditions')}"
                checks.append(Check(None, text, reason="too few conditions"))
            else:
                others = means.drop(CASA_AFTER_LEARNING)
                best = bool(means[CASA_AFTER_LEARNING] > others.max())
                text = f"mean {means[CASA_AFTER_LEARNING]:.2f} vs at most {others.max():.2f}"
                why = f"not rated highest ({others.idxmax()} {others.max():.2f})"
                reason = "" if best else "not rated highest"
                outcome = _outcome(best, why)
                checks.append(Check(best, f"{name} (paper): {text}: {outcome}", reason=reason))
            checks.append(_likert_within(stats, task, question, name))
    return checks


def _likert_within(stats, task, question, name) -> Check:
    parts = [_significant(_rows(stats, "H4", task, question, "friedman"), "Friedman")]
    wilcoxon = _rows(stats, "H4", task, question, "wilcoxon")
    wilcoxon = wilcoxon[wilcoxon["comparison"].str.startswith(f"{CASA_AFTER_LEARNING} vs ")]
    if wilcoxon.empty:
        parts.append(Part(None, "no Wilcoxon tests", "no Wilcoxon tests", "no Wilcoxon tests"))
    for index, row in wilcoxon.iterrows():
        other = row["comparison"].removeprefix(f"{CASA_AFTER_LEARNING} vs ")
        test = _significant(wilcoxon.loc[[index]], f"vs {other}")
        text = f"{test.text} (difference {row['estimate']:.3g})"
        if not np.isfinite(row["estimate"]):
            parts.append(Part(None, text, "no difference computed", f"vs {other} no difference"))
        elif test.passed is not None and row["estimate"] <= 0:
            # The paper's direction here: CASA after learning rated above the other.
            found = OPPOSITE if row["estimate"] < 0 else "no difference"
            reason = f"{'significant, but' if test.passed else 'not significant, and'} {found}"
            side = "below" if row["estimate"] < 0 else "equal to"
            why = f"vs {other} {reason} ({CASA_AFTER_LEARNING} {side} {other})"
            parts.append(Part(False, text, reason, why))
        else:
            parts.append(test._replace(text=text))
    return _combine("within", name, parts)
