"""Between-subjects analyses, as the paper ran them: ANOVA, ANCOVA, Tukey HSD, non-inferiority.

The paper treats every participant-condition as an independent observation (see
docs/departures.md); these functions do exactly that.  ``casa_core.stats.within`` holds the
analyses that respect the within-subjects design.  Every function takes a tidy table (one row
per observation) and returns a tidy table; degenerate data give NaN statistics and a
``note`` (see ``_tables``).
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd
import statsmodels.formula.api as smf
from scipy import stats
from statsmodels.stats.anova import anova_lm

from casa_core.stats._tables import (
    Skipped,
    clean,
    equal_to_rounding,
    levels,
    require_representable,
    skipped_row,
)

ANOVA_COLUMNS = ["term", "F", "df1", "df2", "p", "np2", "n"]
TUKEY_COLUMNS = ["A", "B", "diff", "p", "ci_low", "ci_high", "n_A", "n_B"]
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

# Relative size below which a sum of squares counts as zero (floating-point noise).
_ZERO_SS = 1e-12


def anova(data: pd.DataFrame, dv: str, between: str | Sequence[str]) -> pd.DataFrame:
    """Between-subjects ANOVA (type II sums of squares), one row per term.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation.
    dv : str
        Column of the dependent variable (numeric).
    between : str or sequence of str
        Factor column(s).  With one factor this is the classic one-way ANOVA, identical to
        R's ``anova(lm(dv ~ between))``; several factors enter additively (main effects
        only, no interaction).

    Returns
    -------
    pandas.DataFrame
        Columns ``term, F, df1, df2, p, np2, n, note``: F ratio, its degrees of freedom,
        p-value, partial eta squared ``SS_term / (SS_term + SS_residual)``, the number of
        observations used, and why the test was skipped (empty when it ran).

    Examples
    --------
    >>> data = pd.DataFrame({"group": ["a", "a", "b", "b", "c", "c"],
    ...                      "y": [1.0, 1.2, 2.1, 1.9, 3.2, 2.8]})
    >>> anova(data, "y", "group")[["term", "F", "df1", "df2", "p", "np2"]].round(3)
        term       F  df1  df2      p    np2
    0  group  45.167  2.0  3.0  0.006  0.968
    """
    factors = [between] if isinstance(between, str) else list(between)
    return _linear_model_table(data, dv, factors, covariate=None, what="anova")


def ancova(data: pd.DataFrame, dv: str, between: str, covariate: str) -> pd.DataFrame:
    """ANCOVA: a factor plus a covariate, type II sums of squares, one row per term.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation.
    dv : str
        Column of the dependent variable.
    between : str
        The factor (the paper's assistance method).
    covariate : str
        The covariate.  A numeric column enters linearly (1 degree of freedom); a text or
        categorical column (the paper's task) enters as a factor with ``levels - 1`` degrees
        of freedom, which for two tasks is the same single degree of freedom.

    Returns
    -------
    pandas.DataFrame
        Same columns as :func:`anova`, a row for ``between`` then one for ``covariate``.

    Examples
    --------
    >>> data = pd.DataFrame({"group": ["a"] * 3 + ["b"] * 3,
    ...                      "x": [1.0, 2.0, 3.0, 1.5, 2.5, 3.5],
    ...                      "y": [1.1, 1.9, 3.2, 2.4, 3.1, 4.4]})
    >>> ancova(data, "y", "group", "x")[["term", "F", "df1", "df2", "p"]].round(3)
        term        F  df1  df2      p
    0  group   20.523  1.0  3.0  0.020
    1      x  121.032  1.0  3.0  0.002
    """
    return _linear_model_table(data, dv, [between], covariate=covariate, what="ancova")


def _linear_model_table(data, dv, factors, covariate, what) -> pd.DataFrame:
    terms = [*factors, *([covariate] if covariate else [])]
    frame = clean(data, dv, terms, what)
    try:
        return _fit_linear_model(frame, dv, factors, covariate)
    except Skipped as why:
        rows = [skipped_row(ANOVA_COLUMNS, str(why), term=t, n=len(frame)) for t in terms]
        return pd.concat(rows, ignore_index=True)


def _fit_linear_model(frame, dv, factors, covariate) -> pd.DataFrame:
    # Safe internal names keep the formula independent of user column names.
    names = {dv: "y"} | {f: f"f{i}" for i, f in enumerate(factors)}
    parts = [f"C({names[f]})" for f in factors]
    if covariate is not None:
        names[covariate] = "cov"
        numeric = pd.api.types.is_numeric_dtype(frame[covariate])
        parts.append("cov" if numeric else "C(cov)")
    model_frame = frame.rename(columns=names)
    for factor in factors:
        found = levels(frame[factor])
        if len(found) < 2:
            raise Skipped(f"needs at least 2 levels of {factor!r}, found {found}")
    if covariate is not None and frame[covariate].nunique() < 2:
        raise Skipped(f"the covariate {covariate!r} takes a single value")
    y = model_frame["y"].to_numpy()
    require_representable(y, dv)
    total_ss = float(np.sum((y - y.mean()) ** 2))
    if equal_to_rounding(y):
        raise Skipped(f"zero variance: every value of {dv!r} equals {y[0]!r}")
    fit = smf.ols("y ~ " + " + ".join(parts), data=model_frame).fit()
    if fit.df_resid < 1:
        raise Skipped(f"no residual degrees of freedom ({len(y)} observations)")
    if fit.ssr <= _ZERO_SS * total_ss:
        raise Skipped("zero residual variance: F is undefined")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        table = anova_lm(fit, typ=2)
    rows = []
    for original, part in zip([*factors, *([covariate] if covariate else [])], parts, strict=True):
        term = table.loc[part]
        ss = float(term["sum_sq"])
        rows.append(
            {
                "term": original,
                "F": float(term["F"]),
                "df1": float(term["df"]),
                "df2": float(fit.df_resid),
                "p": float(term["PR(>F)"]),
                "np2": ss / (ss + float(fit.ssr)),
                "n": len(y),
                "note": "",
            }
        )
    return pd.DataFrame(rows, columns=[*ANOVA_COLUMNS, "note"])


def tukey_hsd(data: pd.DataFrame, dv: str, between: str) -> pd.DataFrame:
    """Tukey's honestly significant difference test on all pairs of levels of ``between``.

    Unequal group sizes use the Tukey-Kramer standard error (``scipy.stats.tukey_hsd``), as
    R's ``TukeyHSD(aov(dv ~ between))`` does.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation.
    dv, between : str
        Columns of the dependent variable and of the factor.

    Returns
    -------
    pandas.DataFrame
        One row per pair ``A < B`` in level order, columns ``A, B, diff, p, ci_low, ci_high,
        n_A, n_B, note`` with ``diff = mean(A) - mean(B)``, the family-wise adjusted p-value
        and the 95 % simultaneous confidence interval of ``diff``.

    Examples
    --------
    >>> data = pd.DataFrame({"y": [1.0, 1.2, 2.1, 1.9, 3.2, 2.8], "group": list("aabbcc")})
    >>> tukey_hsd(data, "y", "group")[["A", "B", "diff", "p"]].round(3)
       A  B  diff      p
    0  a  b  -0.9  0.041
    1  a  c  -1.9  0.005
    2  b  c  -1.0  0.031
    """
    frame = clean(data, dv, [between], "tukey_hsd")
    found = levels(frame[between])
    groups = [frame.loc[frame[between] == level, dv].to_numpy() for level in found]
    try:
        if len(found) < 2:
            raise Skipped(f"needs at least 2 levels of {between!r}, found {found}")
        if len(frame) - len(found) < 1:
            raise Skipped(f"no residual degrees of freedom ({len(frame)} observations)")
        single = [str(level) for level, g in zip(found, groups, strict=True) if len(g) < 2]
        if single:
            # scipy's tukey_hsd refuses groups of one observation.
            raise Skipped(f"needs at least 2 observations per group; one only: {', '.join(single)}")
        require_representable(frame[dv], dv)
        within_ss = sum(float(np.sum((g - g.mean()) ** 2)) for g in groups)
        if within_ss <= 0.0:
            raise Skipped("zero within-group variance: the studentized range is undefined")
    except Skipped as why:
        return skipped_row(TUKEY_COLUMNS, str(why))
    result = stats.tukey_hsd(*groups)
    # The interval is scipy's own formula, diff +- q(0.95; k, df) / sqrt(2) * SE_ij, with the
    # studentized-range quantile cached: scipy recomputes it (slowly) on every call.
    df = len(frame) - len(found)
    mse = within_ss / df
    half_q = _studentized_range_quantile(0.95, len(found), df) / np.sqrt(2.0)
    rows = []
    for i in range(len(found)):
        for j in range(i + 1, len(found)):
            rows.append(
                {
                    "A": found[i],
                    "B": found[j],
                    "diff": float(result.statistic[i, j]),
                    "p": float(result.pvalue[i, j]),
                    "ci_low": float(result.statistic[i, j]) - half_q * _se(mse, groups, i, j),
                    "ci_high": float(result.statistic[i, j]) + half_q * _se(mse, groups, i, j),
                    "n_A": len(groups[i]),
                    "n_B": len(groups[j]),
                    "note": "",
                }
            )
    return pd.DataFrame(rows, columns=[*TUKEY_COLUMNS, "note"])


def _se(mse: float, groups, i: int, j: int) -> float:
    """Tukey-Kramer standard error of a difference of two group means."""
    return float(np.sqrt(mse * (1.0 / len(groups[i]) + 1.0 / len(groups[j]))))


@functools.lru_cache(maxsize=64)
def _studentized_range_quantile(level: float, k: int, df: int) -> float:
    return float(stats.studentized_range.ppf(level, k, df))


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
    test = stats.ttest_rel if subject else stats.ttest_ind
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
        return a, b, ""
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
    if np.var(a - b) == 0.0:
        raise Skipped("zero variance of the paired differences: the bound is undefined")
    return a, b, note


__all__ = ["anova", "ancova", "tukey_hsd", "non_inferiority"]
