"""Non-inferiority of one condition against another (Lesaffre 2008), as a t-test.

The paper reports, per metric, the smallest margin at which CASA is non-inferior: the
one-sided upper confidence bound of the difference. Given a margin the test itself is
performed. Three forms: independent samples with pooled variance (the paper's),
independent samples with Welch's unequal-variance t, and paired by participant (the
within-subjects design's).
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from scipy import stats

from casa_core.stats._tables import Skipped, clean, require_representable, skipped_row

NONINFERIORITY_COLUMNS = [
    "new",
    "reference",
    "estimate",
    "se",
    "df",
    "bound",
    "margin",
    "t",
    "p",
    "noninferior",
    "n_new",
    "n_reference",
]


def non_inferiority(
    data: pd.DataFrame,
    dv: str,
    between: str,
    new: str,
    reference: str,
    *,
    lower_is_better: bool = True,
    alpha: float = 0.05,
    margin: float | None = None,
    subject: str | None = None,
    welch: bool = False,
) -> pd.DataFrame:
    """Non-inferiority of ``new`` against ``reference`` (Lesaffre 2008), a t-test.

    With ``d = mean(new) - mean(reference)`` and a lower-is-better metric, ``new`` is
    non-inferior within a margin ``delta > 0`` when the one-sided test of
    ``H0: d >= delta`` rejects at level ``alpha``, i.e. when the one-sided ``(1 - alpha)``
    upper confidence bound ``d + t(1 - alpha, df) SE`` lies below ``delta``.  That bound is
    the smallest margin at which ``new`` is non-inferior, the number the paper reports
    (see docs/paper-to-code.md).  For a higher-is-better metric the bound is the lower one,
    ``d - t(1 - alpha, df) SE``, and the test is against ``-delta``.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation.
    dv, between : str
        Dependent-variable and group columns.
    new, reference : str
        The two levels of ``between`` compared (the paper: CASA against PBA or NA).
    lower_is_better : bool
        Direction of the metric (error, efficiency cost and effort: lower is better).
    alpha : float
        One-sided significance level, in (0, 1).
    margin : float, optional
        The non-inferiority margin ``delta > 0``.  Without it ``p`` and ``noninferior`` are
        missing and only the bound is reported.
    subject : str, optional
        Column identifying participants.  Without it the groups are independent samples
        (pooled-variance Student t, ``df = n_new + n_reference - 2``), as in the paper; with
        it the test is on per-participant paired differences (``df = pairs - 1``), which is
        what the within-subjects design calls for.
    welch : bool
        Independent samples only: Welch's t with the Welch-Satterthwaite degrees of
        freedom instead of the pooled variance, for groups whose variances differ (as
        relative effort, identically 1 under NA, against any other condition).

    Returns
    -------
    pandas.DataFrame
        One row: ``new, reference, estimate, se, df, bound, margin, t, p, noninferior,
        n_new, n_reference, note``; ``t`` and ``p`` are for the margin.

    Examples
    --------
    >>> data = pd.DataFrame({"method": ["new"] * 4 + ["old"] * 4,
    ...                      "error": [1.0, 1.2, 0.9, 1.1, 1.3, 1.5, 1.2, 1.4]})
    >>> row = non_inferiority(data, "error", "method", "new", "old", margin=0.2).iloc[0]
    >>> print(round(row["estimate"], 2), round(row["bound"], 3), row["noninferior"])
    -0.3 -0.123 True
    """
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"non_inferiority: alpha must be in (0, 1), got {alpha!r}")
    if margin is not None and not (np.isfinite(margin) and margin > 0):
        raise ValueError(f"non_inferiority: margin must be a positive number, got {margin!r}")
    factors = [between] + ([subject] if subject else [])
    frame = clean(data, dv, factors, "non_inferiority")
    known = {"new": new, "reference": reference, "margin": np.nan if margin is None else margin}
    try:
        a, b, note = _two_samples(frame, dv, between, new, reference, subject)
    except Skipped as why:
        return skipped_row(NONINFERIORITY_COLUMNS, str(why), **known)
    # One-sided alternative towards "new is better"; its (1 - alpha) interval has one
    # finite end, the bound.
    alternative = "less" if lower_is_better else "greater"
    if welch and subject:
        raise ValueError("non_inferiority: welch applies to independent samples, not paired")

    def test(x, y, alternative):
        with warnings.catch_warnings():
            # A constant group (relative effort under NA) is a case the note names.
            warnings.simplefilter("ignore", RuntimeWarning)
            if subject:
                return stats.ttest_rel(x, y, alternative=alternative)
            return stats.ttest_ind(x, y, alternative=alternative, equal_var=not welch)

    result = test(a, b, alternative=alternative)
    interval = result.confidence_interval(confidence_level=1.0 - alpha)
    bound = float(interval.high if lower_is_better else interval.low)
    estimate = float(np.mean(a) - np.mean(b))
    # The bound is estimate +- t(1 - alpha, df) SE; read SE back from scipy's interval.
    se = abs(bound - estimate) / float(stats.t.ppf(1.0 - alpha, result.df))
    row = known | {
        "estimate": estimate,
        "se": se,
        "df": float(result.df),
        "bound": bound,
        "t": np.nan,
        "p": np.nan,
        "noninferior": pd.NA,
        "n_new": len(a),
        "n_reference": len(b),
        "note": note,
    }
    if margin is not None:
        # Shifting the new group by the margin turns H0: d >= delta into H0: d' >= 0.
        shift = -margin if lower_is_better else margin
        shifted = test(a + shift, b, alternative=alternative)
        row["t"] = float(shifted.statistic)
        row["p"] = float(shifted.pvalue)
        row["noninferior"] = bool(shifted.pvalue < alpha)
    return pd.DataFrame([row], columns=[*NONINFERIORITY_COLUMNS, "note"])


def _two_samples(frame, dv, between, new, reference, subject):
    """The two samples to compare (paired by ``subject`` when given) and a note."""
    for level in (new, reference):
        if not (frame[between] == level).any():
            raise Skipped(f"no observations of {between} = {level!r}")
    if subject is None:
        a = frame.loc[frame[between] == new, dv].to_numpy()
        b = frame.loc[frame[between] == reference, dv].to_numpy()
        if min(len(a), len(b)) < 2:
            raise Skipped(f"needs at least 2 observations per group, got {len(a)} and {len(b)}")
        require_representable(np.concatenate([a, b]), dv)
        if np.var(a) == 0.0 and np.var(b) == 0.0:
            raise Skipped("zero variance in both groups: the confidence bound is undefined")
        return a, b, _constant_note(b, reference, new)
    cells = frame[frame[between].isin([new, reference])]
    wide = cells.pivot_table(index=subject, columns=between, values=dv, aggfunc="mean")
    complete = wide.dropna()
    note = ""
    if len(complete) < len(wide):
        note = f"{len(wide) - len(complete)} participant(s) without both conditions dropped"
    if len(complete) < 2:
        raise Skipped(f"needs at least 2 participants with both conditions, got {len(complete)}")
    a, b = complete[new].to_numpy(), complete[reference].to_numpy()
    require_representable(np.concatenate([a, b]), dv)
    note = "; ".join(x for x in (note, _constant_note(b, reference, new)) if x)
    if np.var(a - b) == 0.0:
        raise Skipped("zero variance of the paired differences: the bound is undefined")
    return a, b, note


def _constant_note(reference_values, reference, new) -> str:
    """Say so when the reference is a constant: the test is then a one-sample test."""
    if len(reference_values) == 0 or np.ptp(reference_values) != 0.0:
        return ""
    return (
        f"every {reference} value equals {reference_values[0]:g}: a one-sample test of "
        f"{new} against that constant in disguise (its information: {new}'s observations "
        "only)"
    )


__all__ = ["NONINFERIORITY_COLUMNS", "non_inferiority"]
