"""Non-inferiority of one condition against another (Lesaffre 2008), as a t-test.

The paper reports, per metric, the smallest margin at which CASA is non-inferior: the
one-sided upper confidence bound of the difference. Given a margin the test itself is
performed. Three forms: independent samples with pooled variance (the paper's),
independent samples with Welch's unequal-variance t, and paired by participant (the
within-subjects design's).

A margin set at a fraction ``f`` of the reference mean is itself an estimate; the ratio
form (:func:`ratio_non_inferiority`) tests ``mu_new - (1 + f) mu_ref`` instead, with the
reference's sampling error in the test, and bounds the ratio ``mu_new / mu_ref`` by
Fieller's method (Laster and Johnson 2003; Hauschke et al. 1999).
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


def ratio_non_inferiority(
    data: pd.DataFrame,
    dv: str,
    between: str,
    new: str,
    reference: str,
    *,
    fraction: float,
    lower_is_better: bool = True,
    alpha: float = 0.05,
    subject: str | None = None,
) -> pd.DataFrame:
    """Non-inferiority within a fraction of the reference mean: ``mu_new / mu_ref``.

    For a lower-is-better metric ``new`` is non-inferior when ``mu_new < (1 + f) mu_ref``,
    i.e. when the one-sided test of ``H0: mu_new - (1 + f) mu_ref >= 0`` rejects at
    ``alpha``: a t-test of ``new - (1 + f) reference``, paired by ``subject`` (one-sample
    t of the participants' differences) or, for independent samples, Welch's t of
    ``new`` against ``(1 + f) reference``. The bound is Fieller's one-sided ``(1 - alpha)``
    upper confidence bound of the ratio: the ratio ``r`` at which the test of ``new -
    r reference`` has p = alpha, the smallest ratio margin at which ``new`` is
    non-inferior. A higher-is-better metric is tested against ``1 - f``, with the lower
    bound. Both means must be positive.

    Parameters
    ----------
    data, dv, between, new, reference, lower_is_better, alpha
        As in :func:`non_inferiority`.
    fraction : float
        The margin ``f > 0`` as a fraction of the reference mean.
    subject : str, optional
        Column identifying participants: the paired form; without it, Welch's.

    Returns
    -------
    pandas.DataFrame
        One row, the columns of :func:`non_inferiority`: ``estimate`` is the ratio of
        the means, ``bound`` Fieller's bound (infinite when the reference mean is not
        significantly above 0), ``margin`` the ratio ``1 + f`` (``1 - f``), ``t`` and ``p``
        the test at it, ``se`` that of ``mean(new) - margin x mean(reference)``.

    Examples
    --------
    >>> data = pd.DataFrame({"method": ["new"] * 4 + ["old"] * 4, "s": list("abcd") * 2,
    ...                      "error": [1.0, 1.2, 0.9, 1.1, 1.3, 1.5, 1.2, 1.4]})
    >>> row = ratio_non_inferiority(data, "error", "method", "new", "old", fraction=0.05,
    ...                             subject="s").iloc[0]
    >>> print(round(row["estimate"], 3), round(row["bound"], 3), row["margin"], row["noninferior"])
    0.778 0.8 1.05 True
    """
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"ratio_non_inferiority: alpha must be in (0, 1), got {alpha!r}")
    if not (np.isfinite(fraction) and fraction > 0):
        raise ValueError(f"ratio_non_inferiority: fraction must be positive, got {fraction!r}")
    ratio_margin = 1.0 + fraction if lower_is_better else 1.0 - fraction
    frame = clean(data, dv, [between] + ([subject] if subject else []), "ratio_non_inferiority")
    known = {"new": new, "reference": reference, "margin": ratio_margin}
    try:
        a, b, note = _two_samples(frame, dv, between, new, reference, subject)
        if not (np.mean(a) > 0 and np.mean(b) > 0):
            raise Skipped("a ratio margin needs positive means of both conditions")
    except Skipped as why:
        return skipped_row(NONINFERIORITY_COLUMNS, str(why), **known)
    alternative = "less" if lower_is_better else "greater"

    def test(r):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            if subject:
                return stats.ttest_1samp(a - r * b, 0.0, alternative=alternative)
            return stats.ttest_ind(a, r * b, alternative=alternative, equal_var=False)

    at_margin = test(ratio_margin)
    estimate = float(np.mean(a) / np.mean(b))
    bound = _fieller_bound(lambda r: float(test(r).pvalue), estimate, alpha, lower_is_better)
    row = known | {
        "estimate": estimate,
        "se": float((np.mean(a) - ratio_margin * np.mean(b)) / at_margin.statistic),
        "df": float(at_margin.df),
        "bound": bound,
        "t": float(at_margin.statistic),
        "p": float(at_margin.pvalue),
        "noninferior": bool(at_margin.pvalue < alpha),
        "n_new": len(a),
        "n_reference": len(b),
        "note": note,
    }
    if not np.isfinite(bound):
        unbounded = "the reference mean is not significantly above 0: Fieller's bound is unbounded"
        row["note"] = "; ".join(x for x in (note, unbounded) if x)
    return pd.DataFrame([row], columns=[*NONINFERIORITY_COLUMNS, "note"])


def _fieller_bound(p_of, estimate: float, alpha: float, lower_is_better: bool) -> float:
    """The ratio at which the one-sided test's p equals ``alpha``, found from the estimate
    (p = 1/2) outward; infinite (lower is better) or 0 when no ratio reaches ``alpha``."""
    from scipy.optimize import brentq

    step, far = max(abs(estimate), 1.0), None
    for _ in range(60):
        candidate = estimate + step if lower_is_better else max(estimate - step, 0.0)
        if p_of(candidate) < alpha:
            far = candidate
            break
        if not lower_is_better and candidate == 0.0:
            break
        step *= 2.0
    if far is None:
        return float(np.inf) if lower_is_better else 0.0
    low, high = min(estimate, far), max(estimate, far)
    return float(brentq(lambda r: p_of(r) - alpha, low, high, xtol=1e-13))


__all__ = ["NONINFERIORITY_COLUMNS", "non_inferiority", "ratio_non_inferiority"]
