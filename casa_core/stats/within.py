"""Within-subjects analyses: what the study's design (every participant saw every condition)
deserves beside the paper's independent-observation tests.

* :func:`rm_anova` -- repeated-measures ANOVA (pingouin), with Greenhouse-Geisser p-values;
* :func:`mixedlm` -- linear mixed model with a random intercept per participant
  (statsmodels, REML), Wald chi-square test per fixed term;
* :func:`friedman` and :func:`wilcoxon_holm` -- rank tests for the Likert answers (scipy),
  Holm-corrected (statsmodels).

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
import statsmodels.formula.api as smf
from scipy import stats
from statsmodels.stats.multitest import multipletests

from casa_core.stats._tables import (
    Skipped,
    clean,
    complete_cells,
    equal_to_rounding,
    levels,
    no_error_variance,
    require_more_participants,
    require_representable,
    skipped_row,
)

RM_COLUMNS = ["term", "F", "df1", "df2", "p", "p_gg", "eps", "ng2", "n"]
MIXED_COLUMNS = ["term", "chi2", "df1", "p", "n", "n_groups"]
FRIEDMAN_COLUMNS = ["Q", "df1", "p", "W", "n"]
WILCOXON_COLUMNS = ["A", "B", "V", "p_unc", "p", "rbc", "median_diff", "n"]


def _as_list(factors: str | Sequence[str]) -> list[str]:
    return [factors] if isinstance(factors, str) else list(factors)


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
        p, p_gg, eps, ng2, n, note``: uncorrected p, Greenhouse-Geisser corrected p and
        epsilon, generalized eta squared, and the number of complete participants.

    Examples
    --------
    >>> data = pd.DataFrame({"subject": ["s1", "s2", "s3", "s4"] * 3,
    ...                      "condition": ["a"] * 4 + ["b"] * 4 + ["c"] * 4,
    ...                      "y": [1.0, 1.5, 1.2, 1.1, 2.0, 2.2, 2.5, 1.9,
    ...                            3.1, 2.9, 3.6, 3.0]})
    >>> table = rm_anova(data, "y", "condition", "subject")
    >>> table[["term", "F", "df1", "df2", "p_gg", "ng2"]].round(3)
            term       F  df1  df2   p_gg    ng2
    0  condition  79.605  2.0  6.0  0.002  0.922
    """
    factors = _as_list(within)
    if not 1 <= len(factors) <= 2:
        raise ValueError(f"rm_anova: within must name 1 or 2 factors, got {factors}")
    frame = clean(data, dv, [*factors, subject], "rm_anova")
    terms = [*factors, *([" * ".join(factors)] if len(factors) == 2 else [])]
    try:
        for factor in factors:
            if len(levels(frame[factor])) < 2:
                raise Skipped(
                    f"needs at least 2 levels of {factor!r}, found {levels(frame[factor])}"
                )
        cells, note = complete_cells(frame, dv, factors, subject)
        n = cells[subject].nunique()
        if n < 2:
            raise Skipped(f"needs at least 2 participants with every condition, got {n}")
        require_more_participants(frame, factors, terms, n)
        require_representable(cells[dv], dv)
        if equal_to_rounding(cells[dv]):
            raise Skipped(f"zero variance: every value of {dv!r} is the same")
        if no_error_variance(cells, dv, factors, subject):
            raise Skipped(
                "no error variance: every participant differs between the conditions by the "
                "same amount, so F is undefined"
            )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pingouin 0.7 triggers pandas 3.1 deprecations
            table = pingouin.rm_anova(
                # A private name: pingouin melts the cells into a column named after dv,
                # which fails when dv is also the name of a condition.
                data=cells.rename(columns={dv: _DV}),
                dv=_DV,
                within=factors if len(factors) > 1 else factors[0],
                subject=subject,
                correction=True,
                detailed=False,
            )
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
                "ng2": float(line.get("ng2", np.nan)),
                "n": n,
                "note": note
                if np.isfinite(f_value)
                else (note + "; " if note else "") + "zero error variance: F is undefined",
            }
        )
    return pd.DataFrame(rows, columns=[*RM_COLUMNS, "note"])


def mixedlm(data: pd.DataFrame, dv: str, fixed: str | Sequence[str], subject: str) -> pd.DataFrame:
    """Linear mixed model ``dv ~ fixed + (1 | subject)`` fitted by REML.

    Each fixed factor is tested with a Wald chi-square test of all its coefficients
    (statsmodels ``wald_test_terms``); on balanced complete data the chi-square divided by
    its degrees of freedom equals the repeated-measures F of an additive model.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation (long format); repeated trials are used as they are.
    dv : str
        Column of the dependent variable.
    fixed : str or sequence of str
        Categorical fixed-effect columns (e.g. method, or method and task).
    subject : str
        Column identifying participants (random intercept).

    Returns
    -------
    pandas.DataFrame
        One row per fixed factor, columns ``term, chi2, df1, p, n, n_groups, note``.

    Examples
    --------
    >>> y = [1.0, 1.5, 1.2, 1.1, 2.0, 2.2, 2.5, 1.9, 3.1, 2.9, 3.6, 3.0]
    >>> data = pd.DataFrame({"y": y, "condition": [c for c in "abc" for _ in range(4)]})
    >>> data["subject"] = [f"s{i % 4 + 1}" for i in range(12)]
    >>> mixedlm(data, "y", "condition", "subject")[["term", "chi2", "df1", "n"]].round(1)
            term   chi2  df1   n
    0  condition  159.2  2.0  12
    """
    factors = _as_list(fixed)
    frame = clean(data, dv, [*factors, subject], "mixedlm")
    try:
        for factor in factors:
            if len(levels(frame[factor])) < 2:
                raise Skipped(
                    f"needs at least 2 levels of {factor!r}, found {levels(frame[factor])}"
                )
        n_groups = frame[subject].nunique()
        if n_groups < 2:
            raise Skipped(f"needs at least 2 participants, got {n_groups}")
        require_representable(frame[dv], dv)
        if frame[dv].var() == 0.0:
            raise Skipped(f"zero variance: every value of {dv!r} is the same")
        names = {dv: "y", subject: "g"} | {f: f"f{i}" for i, f in enumerate(factors)}
        model_frame = frame.rename(columns=names)
        model_frame["g"] = model_frame["g"].astype(str)
        formula = "y ~ " + " + ".join(f"C(f{i})" for i in range(len(factors)))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                fit = smf.mixedlm(formula, model_frame, groups=model_frame["g"]).fit(reml=True)
                tests = fit.wald_test_terms(scalar=True).table
            except (np.linalg.LinAlgError, ValueError) as error:
                raise Skipped(f"the mixed model could not be fitted: {error}") from error
        note = "Wald chi-square, REML, random intercept per participant"
        if any("converge" in str(w.message).lower() for w in caught):
            note += "; fit did not fully converge"
        if float(fit.cov_re.iloc[0, 0]) <= 1e-10:
            note += "; participant variance estimated at 0 (boundary)"
    except Skipped as why:
        return pd.concat(
            [skipped_row(MIXED_COLUMNS, str(why), term=f) for f in factors], ignore_index=True
        )
    rows = []
    for i, factor in enumerate(factors):
        line = tests.loc[f"C(f{i})"]
        rows.append(
            {
                "term": factor,
                "chi2": float(line["statistic"]),
                "df1": float(line["df_constraint"]),
                "p": float(line["pvalue"]),
                "n": len(model_frame),
                "n_groups": n_groups,
                "note": note,
            }
        )
    return pd.DataFrame(rows, columns=[*MIXED_COLUMNS, "note"])


def friedman(data: pd.DataFrame, dv: str, within: str, subject: str) -> pd.DataFrame:
    """Friedman rank test across the levels of ``within`` (R's ``friedman.test``).

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation (long format).
    dv, within, subject : str
        Score column, condition column and participant column.

    Returns
    -------
    pandas.DataFrame
        One row, columns ``Q, df1, p, W, n, note``: the tie-corrected chi-square statistic,
        ``k - 1`` degrees of freedom, p-value, Kendall's ``W = Q / (n (k - 1))`` and the
        number of complete participants.

    Examples
    --------
    Three conditions rated by four participants, one column per condition:

    >>> wide = pd.DataFrame({"a": [1.0, 1.5, 1.2, 1.1], "b": [2.0, 2.2, 2.5, 1.9],
    ...                      "c": [3.1, 2.9, 3.6, 3.0]}, index=["s1", "s2", "s3", "s4"])
    >>> data = wide.rename_axis("subject").reset_index().melt(
    ...     "subject", var_name="condition", value_name="y")
    >>> friedman(data, "y", "condition", "subject")[["Q", "df1", "p", "W", "n"]].round(4)
         Q  df1       p    W  n
    0  8.0    2  0.0183  1.0  4
    """
    frame = clean(data, dv, [within, subject], "friedman")
    try:
        found = levels(frame[within])
        if len(found) < 3:
            raise Skipped(f"needs at least 3 conditions, found {found}")
        cells, note = complete_cells(frame, dv, [within], subject)
        n = cells[subject].nunique()
        if n < 2:
            raise Skipped(f"needs at least 2 participants with every condition, got {n}")
        wide = cells.pivot(index=subject, columns=within, values=dv)[found]
        if (wide.nunique(axis=1) == 1).all():
            raise Skipped("every participant gave the same score to every condition")
        result = stats.friedmanchisquare(*(wide[c].to_numpy() for c in found))
    except Skipped as why:
        return skipped_row(FRIEDMAN_COLUMNS, str(why))
    df1 = len(found) - 1
    q = float(result.statistic)
    row = {"Q": q, "df1": df1, "p": float(result.pvalue), "W": q / (n * df1), "n": n, "note": note}
    return pd.DataFrame([row], columns=[*FRIEDMAN_COLUMNS, "note"])


def holm(pvalues: Sequence[float]) -> np.ndarray:
    """Holm's step-down adjustment of a family of p-values (R's ``p.adjust(p, "holm")``).

    NaN entries are left out of the family and stay NaN.

    Examples
    --------
    >>> holm([0.01, 0.04, float("nan"), 0.03]).round(3).tolist()
    [0.03, 0.06, nan, 0.06]
    """
    p = np.asarray(pvalues, dtype=float)
    out = np.full(p.shape, np.nan)
    ok = np.isfinite(p)
    if ok.any():
        out[ok] = multipletests(p[ok], method="holm")[1]
    return out


def wilcoxon_holm(
    data: pd.DataFrame,
    dv: str,
    within: str,
    subject: str,
    *,
    target: str,
    others: Sequence[str] | None = None,
) -> pd.DataFrame:
    """Wilcoxon signed-rank tests of ``target`` against each other condition, Holm-corrected.

    Zero differences are dropped (R's default); the p-value is exact for small samples
    without ties and otherwise normal-approximate with continuity correction, as R's
    ``wilcox.test(paired = TRUE)`` does.

    Parameters
    ----------
    data : pandas.DataFrame
        Long format: one row per participant, condition and (repeated) observation.
    dv, within, subject : str
        The columns of the scores, the conditions and the participants.
    target : str
        The condition compared with every other (the paper: CASA after learning).
    others : sequence of str, optional
        The conditions to compare with; default all other levels of ``within``.

    Returns
    -------
    pandas.DataFrame
        One row per comparison, columns ``A, B, V, p_unc, p, rbc, median_diff, n, note``:
        ``A = target``; ``V`` is the sum of ranks of positive differences ``A - B`` (R's V);
        ``p`` is Holm-adjusted over the rows; ``rbc`` the matched-pairs rank-biserial
        correlation; ``n`` the number of pairs.

    Examples
    --------
    >>> data = pd.DataFrame({"participant": [f"P{i}" for i in range(6)] * 2,
    ...                      "condition": ["CASA"] * 6 + ["NA"] * 6,
    ...                      "score": [6, 7, 5, 6, 6, 7, 3, 4, 4, 2, 5, 3]})
    >>> table = wilcoxon_holm(data, "score", "condition", "participant", target="CASA")
    >>> table[["A", "B", "V", "p", "rbc", "n"]].round(4)
          A   B     V       p  rbc  n
    0  CASA  NA  21.0  0.0345  1.0  6
    """
    frame = clean(data, dv, [within, subject], "wilcoxon_holm")
    found = levels(frame[within])
    others = [c for c in found if c != target] if others is None else list(others)
    rows = []
    for other in others:
        try:
            rows.append(_signed_rank(frame, dv, within, subject, target, other))
        except Skipped as why:
            rows.append(skipped_row(WILCOXON_COLUMNS, str(why), A=target, B=other).iloc[0])
    table = pd.DataFrame(rows, columns=[*WILCOXON_COLUMNS, "note"])
    table["p"] = holm(table["p_unc"].to_numpy(dtype=float))
    return table


def _signed_rank(frame, dv, within, subject, a, b) -> pd.Series:
    if not (frame[within] == a).any() or not (frame[within] == b).any():
        missing = a if not (frame[within] == a).any() else b
        raise Skipped(f"no observations of {within} = {missing!r}")
    pair = frame[frame[within].isin([a, b])]
    cells, note = complete_cells(pair, dv, [within], subject)
    if cells.empty:
        raise Skipped(f"no participant has both {within} = {a!r} and {b!r}")
    wide = cells.pivot(index=subject, columns=within, values=dv)
    with np.errstate(over="ignore"):
        diff = (wide[a] - wide[b]).to_numpy()
    if not np.isfinite(diff).all():
        raise Skipped(f"paired differences of {dv!r} overflow double precision")
    nonzero = diff[diff != 0.0]
    if len(nonzero) == 0:
        raise Skipped("all paired differences are zero")
    ranks = stats.rankdata(np.abs(nonzero))
    # R's rule: exact only below 50 pairs with neither zero differences nor tied ranks.
    exact = len(nonzero) < 50 and len(nonzero) == len(diff) and len(np.unique(ranks)) == len(ranks)
    result = stats.wilcoxon(
        wide[a],
        wide[b],
        zero_method="wilcox",
        correction=True,
        alternative="two-sided",
        method="exact" if exact else "asymptotic",
    )
    v = float(ranks[nonzero > 0].sum())
    total = float(ranks.sum())
    return pd.Series(
        {
            "A": a,
            "B": b,
            "V": v,
            "p_unc": float(result.pvalue),
            "p": np.nan,
            "rbc": (2.0 * v - total) / total,
            "median_diff": float(np.median(diff)),
            "n": len(diff),
            "note": note,
        }
    )


__all__ = ["rm_anova", "mixedlm", "friedman", "wilcoxon_holm", "holm"]
