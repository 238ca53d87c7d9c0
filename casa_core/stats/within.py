"""Within-subjects analyses: what the study's design (every participant saw every condition)
deserves beside the paper's independent-observation tests.

* :func:`rm_anova` -- repeated-measures ANOVA (pingouin), with Mauchly's test of sphericity
  and Greenhouse-Geisser p-values;
* :func:`mixedlm` (:mod:`casa_core.stats.mixed`) -- linear mixed model with a random
  intercept per participant;
* :func:`friedman` and :func:`wilcoxon_holm` (:mod:`casa_core.stats.ranks`) -- rank tests
  for the Likert answers, Holm-corrected.

Repeated trials of one participant in one cell are averaged first; participants missing a
cell are dropped (complete-case analysis, as R's ``ez``/``afex`` and JASP do) and the note says
how many.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd
import pingouin

from casa_core.stats._tables import (
    Skipped,
    as_list,
    clean,
    complete_cells,
    equal_to_rounding,
    levels,
    no_error_variance,
    participants_needed,
    require_more_participants,
    require_representable,
    skipped_row,
)
from casa_core.stats.mixed import mixedlm
from casa_core.stats.ranks import friedman, holm, wilcoxon_holm

RM_COLUMNS = ["term", "F", "df1", "df2", "p", "p_gg", "eps", "W_spher", "p_spher", "ng2", "n"]


_DV = "__dv__"


def rm_anova(
    data: pd.DataFrame, dv: str, within: str | Sequence[str], subject: str
) -> pd.DataFrame:
    """Repeated-measures ANOVA with one or two within-subject factors.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation (long format).
    dv : str
        Column of the dependent variable.
    within : str or sequence of str
        One or two within-subject factor columns (e.g. method, or method and task).
    subject : str
        Column identifying participants.

    Returns
    -------
    pandas.DataFrame
        One row per term (main effects, then the interaction), columns ``term, F, df1, df2,
        p, p_gg, eps, W_spher, p_spher, ng2, n, note``: the uncorrected degrees of freedom
        and p, the Greenhouse-Geisser corrected p and epsilon, Mauchly's W and the p of
        its test of sphericity (W = p = 1 for a term of one degree of freedom, whose
        sphericity holds by construction), generalized eta squared, and the number of complete
        participants.

    Examples
    --------
    >>> data = pd.DataFrame({"subject": ["s1", "s2", "s3", "s4"] * 3,
    ...                      "condition": ["a"] * 4 + ["b"] * 4 + ["c"] * 4,
    ...                      "y": [1.0, 1.5, 1.2, 1.1, 2.0, 2.2, 2.5, 1.9,
    ...                            3.1, 2.9, 3.6, 3.0]})
    >>> table = rm_anova(data, "y", "condition", "subject")
    >>> table[["term", "F", "df1", "df2", "p_gg", "eps", "p_spher"]].round(3)
            term       F  df1  df2   p_gg   eps  p_spher
    0  condition  79.605  2.0  6.0  0.002  0.57    0.247
    """
    factors = as_list(within)
    if not 1 <= len(factors) <= 2:
        raise ValueError(f"rm_anova: within must name 1 or 2 factors, got {factors}")
    frame = clean(data, dv, [*factors, subject], "rm_anova")
    terms = [*factors, *([" * ".join(factors)] if len(factors) == 2 else [])]
    try:
        cells, note, n = _complete_participants(frame, dv, factors, subject, terms)
        table = _pingouin_rm_anova(cells, dv, factors, subject)
    except Skipped as why:
        return pd.concat(
            [skipped_row(RM_COLUMNS, str(why), term=t) for t in terms], ignore_index=True
        )
    rows = []
    for term, (_, line) in zip(terms, table.iterrows(), strict=True):
        # pingouin leaves out the columns it could not compute (an F of 0 / 0).
        f_value = float(line.get("F", np.nan))
        rows.append(
            {
                "term": term,
                "F": f_value,
                "df1": float(line["ddof1"]),
                "df2": float(line["ddof2"]),
                "p": float(line.get("p_unc", np.nan)),
                "p_gg": float(line.get("p_GG_corr", np.nan)),
                "eps": float(line.get("eps", np.nan)),
                # One degree of freedom: one contrast, W = 1 (pingouin leaves W out).
                "W_spher": 1.0 if line["ddof1"] == 1 else float(line.get("W_spher", np.nan)),
                "p_spher": 1.0 if line["ddof1"] == 1 else float(line.get("p_spher", np.nan)),
                "ng2": float(line.get("ng2", np.nan)),
                "n": n,
                "note": note
                if np.isfinite(f_value)
                else (note + "; " if note else "") + "zero error variance: F is undefined",
            }
        )
    return pd.DataFrame(rows, columns=[*RM_COLUMNS, "note"])


def _complete_participants(
    frame: pd.DataFrame, dv: str, factors: list[str], subject: str, terms: list[str]
) -> tuple[pd.DataFrame, str, int]:
    """The cell means of the participants with every cell, the note, their number.

    Raises :class:`Skipped` where the ANOVA is not defined on them.
    """
    for factor in factors:
        if len(levels(frame[factor])) < 2:
            raise Skipped(f"needs at least 2 levels of {factor!r}, found {levels(frame[factor])}")
    cells, note = complete_cells(frame, dv, factors, subject)
    n = cells[subject].nunique()
    if n < 2:
        # Said with the whole rule, so that the note names the number the test needs.
        needed = participants_needed(frame, factors)
        raise Skipped(f"needs at least {needed} participants with every condition, got {n}")
    require_more_participants(frame, factors, terms, n)
    require_representable(cells[dv], dv)
    if equal_to_rounding(cells[dv]):
        raise Skipped(f"zero variance: every value of {dv!r} is the same")
    if no_error_variance(cells, dv, factors, subject):
        raise Skipped(
            "no error variance: every participant differs between the conditions by the "
            "same amount, so F is undefined"
        )
    return cells, note, n


def _pingouin_rm_anova(
    cells: pd.DataFrame, dv: str, factors: list[str], subject: str
) -> pd.DataFrame:
    """pingouin's table of the cell means: one row per term, sphericity corrected."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pingouin 0.7 triggers pandas 3.1 deprecations
        return pingouin.rm_anova(
            # A private name: pingouin melts the cells into a column named after dv,
            # which fails when dv is also the name of a condition.
            data=cells.rename(columns={dv: _DV}),
            dv=_DV,
            within=factors if len(factors) > 1 else factors[0],
            subject=subject,
            correction=True,
            detailed=False,
        )


__all__ = ["rm_anova", "mixedlm", "friedman", "wilcoxon_holm", "holm"]
