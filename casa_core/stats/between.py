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
    ZERO_SS,
    Skipped,
    clean,
    equal_to_rounding,
    levels,
    require_representable,
    skipped_row,
)
from casa_core.stats.noninferiority import NONINFERIORITY_COLUMNS, non_inferiority

ANOVA_COLUMNS = ["term", "F", "df1", "df2", "p", "np2", "n"]
TUKEY_COLUMNS = ["A", "B", "diff", "p", "ci_low", "ci_high", "n_A", "n_B"]


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
    if fit.ssr <= ZERO_SS * total_ss:
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


__all__ = ["anova", "ancova", "tukey_hsd", "non_inferiority", "NONINFERIORITY_COLUMNS"]
