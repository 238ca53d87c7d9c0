"""Rank tests for the Likert answers: Friedman, and Wilcoxon signed-rank tests with Holm.

Both follow R (``friedman.test``, ``wilcox.test(paired = TRUE)``, ``p.adjust(p, "holm")``);
repeated answers of one participant in one condition are averaged first and participants
missing a condition are dropped, as in :mod:`casa_core.stats.within`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy import stats

from casa_core.stats._tables import Skipped, clean, complete_cells, levels, skipped_row

FRIEDMAN_COLUMNS = ["Q", "df1", "p", "W", "n"]
WILCOXON_COLUMNS = ["A", "B", "V", "p_unc", "p", "rbc", "median_diff", "n"]


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

    NaN entries (comparisons that could not be tested) stay NaN but count in the family
    size ``m``, as R's default ``n = length(p)`` does: a comparison planned and skipped
    still costs its share of the error rate, so the others are adjusted as if it had
    been run and failed (p = 1), the conservative reading.

    Examples
    --------
    >>> holm([0.01, 0.04, float("nan"), 0.03]).round(3).tolist()
    [0.04, 0.09, nan, 0.09]
    """
    p = np.asarray(pvalues, dtype=float)
    out = np.full(p.shape, np.nan)
    ok = np.isfinite(p)
    if ok.any():
        # R: pmin(1, cummax((n - i + 1) p[o])) with n = length(p), NaN included.
        order = np.argsort(p[ok], kind="stable")
        factors = len(p) - np.arange(ok.sum())
        adjusted = np.minimum(1.0, np.maximum.accumulate(factors * p[ok][order]))
        values = np.empty(int(ok.sum()))
        values[order] = adjusted
        out[ok] = values
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
        ``p`` is Holm-adjusted over all the rows, skipped comparisons included in the
        family (:func:`holm`); ``rbc`` the matched-pairs rank-biserial
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
    table = pd.DataFrame(rows, columns=[*WILCOXON_COLUMNS, "note"]).reset_index(drop=True)
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
    result = stats.wilcoxon(  # type: ignore[call-overload]  # scipy-stubs lack "asymptotic"
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


__all__ = ["friedman", "holm", "wilcoxon_holm"]
