"""Analyses of the ANCOVA form beyond its F tests: the factor x covariate interaction and
pairwise comparisons of the factor's levels taken from the model that holds the covariate.

The paper pools the two misspecified tasks with task as a covariate; a one-way Tukey test
on the pooled cells would then compare methods in a model that ignores task, whose
residual holds the task effect. :func:`model_contrasts` compares the levels in the ANCOVA
model itself (``dv ~ C(between) + C(covariate)``), as R's ``emmeans(fit, pairwise ~ between)``
does, and :func:`interaction` tests whether the methods differ differently per task.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import statsmodels.formula.api as smf
from scipy import stats

from casa_core.stats import _tables
from casa_core.stats._tables import ZERO_SS, Skipped
from casa_core.stats.between import ANOVA_COLUMNS

CONTRAST_COLUMNS = ["A", "B", "diff", "se", "df", "t", "p", "ci_low", "ci_high", "n_A", "n_B"]


def _model_frame(data, dv, between, covariate, what) -> pd.DataFrame:
    frame = _tables.clean(data, dv, [between, covariate], what)
    found = _tables.levels(frame[between])
    if len(found) < 2:
        raise Skipped(f"needs at least 2 levels of {between!r}, found {found}")
    if frame[covariate].nunique() < 2:
        raise Skipped(f"the covariate {covariate!r} takes a single value")
    y = frame[dv].to_numpy(dtype=float)
    _tables.require_representable(y, dv)
    if _tables.equal_to_rounding(y):
        raise Skipped(f"zero variance: every value of {dv!r} is the same")
    out = pd.DataFrame({"y": y, "a": frame[between].astype(str), "c": frame[covariate]})
    out["c"] = out["c"].astype(str)
    return out


def _fit(model_frame: pd.DataFrame, formula: str):
    with warnings.catch_warnings():
        # An empty cell makes the factorial design rank-deficient; the fit's df say so.
        warnings.simplefilter("ignore")
        fit = smf.ols(formula, data=model_frame).fit()
    if fit.df_resid < 1:
        raise Skipped(f"no residual degrees of freedom ({len(model_frame)} observations)")
    total = float(np.sum((model_frame["y"] - model_frame["y"].mean()) ** 2))
    if fit.ssr <= ZERO_SS * total:
        raise Skipped("zero residual variance: the test is undefined")
    return fit


def model_contrasts(
    data: pd.DataFrame, dv: str, between: str, covariate: str, *, adjust: str = "tukey"
) -> pd.DataFrame:
    """Pairwise differences of ``between``'s levels in the model ``dv ~ between + covariate``.

    Each difference is a linear contrast of the fitted coefficients (``t_test``); with the
    additive model it is the same at every level of the covariate, and on balanced data it
    equals the difference of the marginal means. Its standard error comes from the
    model's residual variance and ``df`` is the model's residual degrees of freedom.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation.
    dv, between, covariate : str
        The dependent variable, the factor compared (method) and the categorical covariate
        (task).
    adjust : {"tukey", "holm"}
        Family-wise adjustment over all pairs: Tukey's studentized range on the model's
        residual degrees of freedom (R emmeans' default for pairwise comparisons), or Holm.
        The intervals are Tukey's simultaneous 95 % intervals, or unadjusted 95 % with Holm.

    Returns
    -------
    pandas.DataFrame
        One row per pair ``A < B`` in level order, columns ``A, B, diff, se, df, t, p,
        ci_low, ci_high, n_A, n_B, note`` with ``diff`` = A - B.

    Examples
    --------
    >>> data = pd.DataFrame({"method": list("abcabcabcabc"),
    ...                      "task": ["x"] * 6 + ["y"] * 6,
    ...                      "y": [1.0, 1.6, 2.1, 1.4, 1.5, 2.9, 2.0, 3.2, 3.0, 2.6, 2.4, 4.2]})
    >>> table = model_contrasts(data, "y", "method", "task")
    >>> table[["A", "B", "diff", "se", "df", "p"]].round(3)
       A  B   diff    se   df      p
    0  a  b -0.425  0.32  8.0  0.420
    1  a  c -1.300  0.32  8.0  0.009
    2  b  c -0.875  0.32  8.0  0.060
    """
    if adjust not in ("tukey", "holm"):
        raise ValueError(f"model_contrasts: adjust must be 'tukey' or 'holm', got {adjust!r}")
    try:
        model_frame = _model_frame(data, dv, between, covariate, "model_contrasts")
        found = _tables.levels(
            _tables.clean(data, dv, [between, covariate], "model_contrasts")[between]
        )
        found = [str(level) for level in found]
        model_frame["a"] = pd.Categorical(model_frame["a"], categories=found)
        fit = _fit(model_frame, "y ~ C(a) + C(c)")
    except Skipped as why:
        return _tables.skipped_row(CONTRAST_COLUMNS, str(why))
    names = list(fit.params.index)
    df = float(fit.df_resid)
    counts = model_frame["a"].value_counts()
    rows = []
    for i in range(len(found)):
        for j in range(i + 1, len(found)):
            contrast = np.zeros(len(names))
            # Treatment coding: the first level is the intercept's, the others a coefficient.
            for level, sign in ((found[i], 1.0), (found[j], -1.0)):
                if level != found[0]:
                    contrast[names.index(f"C(a)[T.{level}]")] += sign
            test = fit.t_test(contrast)
            diff, se = float(np.squeeze(test.effect)), float(np.squeeze(test.sd))
            rows.append(
                {
                    "A": found[i],
                    "B": found[j],
                    "diff": diff,
                    "se": se,
                    "df": df,
                    "t": diff / se,
                    "p": float(np.squeeze(test.pvalue)),
                    "n_A": int(counts[found[i]]),
                    "n_B": int(counts[found[j]]),
                    "note": f"from the model {dv} ~ {between} + {covariate}",
                }
            )
    table = pd.DataFrame(rows, columns=[*CONTRAST_COLUMNS, "note"])
    k = len(found)
    if adjust == "tukey":
        # Tukey: |t| sqrt(2) against the studentized range of k means on df.
        table["p"] = stats.studentized_range.sf(np.abs(table["t"]) * np.sqrt(2.0), k, df)
        half = float(stats.studentized_range.ppf(0.95, k, df)) / np.sqrt(2.0)
        table["note"] += ", Tukey-adjusted"
    else:
        from casa_core.stats.ranks import holm

        table["p"] = holm(table["p"].to_numpy())
        half = float(stats.t.ppf(0.975, df))
        table["note"] += ", Holm-adjusted (interval unadjusted)"
    table["ci_low"] = table["diff"] - half * table["se"]
    table["ci_high"] = table["diff"] + half * table["se"]
    return table


def interaction(data: pd.DataFrame, dv: str, between: str, covariate: str) -> pd.DataFrame:
    """F test of the ``between x covariate`` interaction in ``dv ~ between * covariate``.

    The interaction's sum of squares is the reduction in residual sum of squares from
    the additive model to the full factorial one (the same under type II and III sums of
    squares, as the highest-order term), on as many degrees of freedom as the observed
    cells add; the F uses the full model's residual.

    Returns
    -------
    pandas.DataFrame
        One row, columns ``term, F, df1, df2, p, np2, n, note`` with ``term`` =
        ``"<between> x <covariate>"``.

    Examples
    --------
    >>> data = pd.DataFrame({"method": list("abab") * 2, "task": ["x"] * 4 + ["y"] * 4,
    ...                      "y": [1.0, 2.0, 1.2, 2.2, 2.0, 2.1, 2.3, 2.0]})
    >>> interaction(data, "y", "method", "task")[["term", "F", "df1", "df2"]].round(2)
                term      F  df1  df2
    0  method x task  26.89  1.0  4.0
    """
    term = f"{between} x {covariate}"
    try:
        model_frame = _model_frame(data, dv, between, covariate, "interaction")
        full = _fit(model_frame, "y ~ C(a) * C(c)")
        additive = _fit(model_frame, "y ~ C(a) + C(c)")
        # A model comparison, as R's anova(additive, full): with an empty method-task cell
        # the interaction keeps the degrees of freedom the observed cells can estimate.
        df1 = float(full.df_model - additive.df_model)
        if df1 < 1:
            raise Skipped("the interaction is not estimable (each method seen in one task only)")
        f_value, p, _ = full.compare_f_test(additive)
    except Skipped as why:
        return _tables.skipped_row(ANOVA_COLUMNS, str(why), term=term)
    ss = float(additive.ssr - full.ssr)
    row = {
        "term": term,
        "F": float(f_value),
        "df1": df1,
        "df2": float(full.df_resid),
        "p": float(p),
        "np2": ss / (ss + float(full.ssr)),
        "n": len(model_frame),
        "note": f"from the model {dv} ~ {between} * {covariate}",
    }
    return pd.DataFrame([row], columns=[*ANOVA_COLUMNS, "note"])


__all__ = ["interaction", "model_contrasts"]
