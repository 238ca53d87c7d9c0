"""Kenward-Roger F test of fixed effects in a linear mixed model with variance components.

The covariance of the observations is linear in its variance parameters,
``V = sum_i theta_i G_i`` (a participant intercept, participant x method, participant x
task and the residual, each ``G_i = Z_i Z_i'``), so the Kenward and Roger (1997)
adjustment needs no second derivatives of ``V``: the small-sample covariance of the
fixed effects (``Phi_A``), the scaling of the Wald F and its denominator degrees of
freedom follow from ``V``, the design and the REML estimates ``theta`` alone. The
formulas are those of R's pbkrtest (``vcovAdj``, ``KRmodcomp``; Halekoh and Hojsgaard
2014). On a balanced split-plot or fully within-subjects design with positive variance
components the test equals the classical repeated-measures ANOVA F of the term.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy import stats

from casa_core.stats import _dense

KR_COLUMNS = ["F", "df1", "df2", "p", "scaling"]


def kenward_roger(
    X: np.ndarray,
    y: np.ndarray,
    structures: Sequence[np.ndarray],
    variances: Sequence[float],
    L: np.ndarray,
) -> pd.Series:
    """Kenward-Roger F test of ``H0: L beta = 0`` given REML variance estimates.

    Parameters
    ----------
    X : numpy.ndarray
        The fixed-effects design, ``n x p``, of full column rank.
    y : numpy.ndarray
        The ``n`` observations.
    structures : sequence of numpy.ndarray
        The ``n x n`` matrices ``G_i`` of ``V = sum_i theta_i G_i`` (the identity for the
        residual among them).
    variances : sequence of float
        The REML estimates ``theta_i``, one per structure (a component at 0 stays in).
    L : numpy.ndarray
        The hypothesis, ``q x p`` of full row rank ``q`` (e.g. the rows selecting a
        term's coefficients).

    Returns
    -------
    pandas.Series
        ``F, df1, df2, p, scaling``: the scaled Wald F, its degrees of freedom
        ``(q, m)``, p and the scaling ``lambda`` (F = lambda x Wald / q).

    Examples
    --------
    Two conditions of four participants with a random intercept: the F is the paired
    t squared, on ``n - 1`` degrees of freedom.

    >>> a, b = np.array([1.0, 1.4, 0.9, 1.3]), np.array([1.6, 1.9, 1.2, 2.1])
    >>> y = np.concatenate([a, b])
    >>> X = np.column_stack([np.ones(8), np.repeat([0.0, 1.0], 4)])
    >>> same = np.equal.outer(np.tile(np.arange(4), 2), np.tile(np.arange(4), 2))
    >>> d = b - a
    >>> sw = (np.var(a, ddof=1) + np.var(b, ddof=1)) / 2 - np.var(d, ddof=1) / 2
    >>> kr = kenward_roger(X, y, [same * 1.0, np.eye(8)], [sw, np.var(d, ddof=1) / 2],
    ...                    np.array([[0.0, 1.0]]))
    >>> t = d.mean() / (d.std(ddof=1) / 2)
    >>> print(round(kr["F"], 6) == round(t**2, 6), round(kr["df2"], 6))
    True 3.0
    """
    X, y, L = (np.asarray(m, dtype=float) for m in (X, y, L))
    L = np.atleast_2d(L)
    G = [np.asarray(g, dtype=float) for g in structures]
    # Every product and solve in fixed order (stats._dense): the same bits on every CPU.
    mm = _dense.matmul
    V = np.sum([theta * g for theta, g in zip(variances, G, strict=True)], axis=0)
    Vinv = _dense.spd_inverse(V)
    VinvX = mm(Vinv, X)
    Phi = _dense.spd_inverse(mm(X.T, VinvX))
    beta = mm(Phi, mm(VinvX.T, y))
    # P = V^-1 - V^-1 X Phi X' V^-1: the REML projection.
    P = Vinv - mm(mm(VinvX, Phi), VinvX.T)
    k = len(G)
    # d(X'V^-1 X)/d theta_i = -X'V^-1 G_i V^-1 X; Q_ij = X'V^-1 G_i V^-1 G_j V^-1 X.
    GVX = [mm(g, VinvX) for g in G]
    Pd = [-mm(VinvX.T, gvx) for gvx in GVX]
    PG = [mm(P, g) for g in G]
    information = np.array([[np.sum(PG[i] * PG[j].T) for j in range(k)] for i in range(k)])
    # W: the asymptotic covariance of the REML estimates, 2 x the inverse of tr(P G_i P G_j).
    try:
        W = 2.0 * _dense.spd_inverse(information)
    except np.linalg.LinAlgError:  # a variance without information: pbkrtest's generalised inverse
        W = 2.0 * np.linalg.pinv(information)
    U = np.zeros_like(Phi)
    VinvGVX = [mm(Vinv, gvx) for gvx in GVX]
    for i in range(k):
        for j in range(k):
            Q = mm(GVX[i].T, VinvGVX[j])
            U += W[i, j] * (Q - mm(mm(Pd[i], Phi), Pd[j]))
    PhiA = Phi + 2.0 * mm(mm(Phi, U), Phi)
    q = L.shape[0]
    Theta = mm(L.T, _dense.cholesky_solve(_dense.cholesky(mm(mm(L, Phi), L.T)), L))
    parts = [mm(mm(mm(Theta, Phi), Pd[i]), Phi) for i in range(k)]
    traces = np.array([np.trace(m) for m in parts])
    A1 = float(np.sum(traces * mm(W, traces)))
    A2 = float(sum(W[i, j] * np.sum(parts[i] * parts[j].T) for i in range(k) for j in range(k)))
    # Degenerate designs (no information on a variance) divide by 0: NaN, not an error.
    with np.errstate(divide="ignore", invalid="ignore"):
        A1, A2 = np.float64(A1), np.float64(A2)
        B = (A1 + 6.0 * A2) / (2.0 * q)
        g = ((q + 1.0) * A1 - (q + 4.0) * A2) / ((q + 2.0) * A2)
        denominator = 3.0 * q + 2.0 * (1.0 - g)
        c1, c2, c3 = g / denominator, (q - g) / denominator, (q + 2.0 - g) / denominator
        V0 = 0.0 if abs(1.0 + c1 * B) < 1e-10 else 1.0 + c1 * B
        V1, V2 = 1.0 - c2 * B, 1.0 - c3 * B
        # pbkrtest's .divZero: 0 / 0 is 1 there.
        ratio = 1.0 if abs(1.0 - A2 / q) < 1e-14 and abs(V1) < 1e-14 else (1.0 - A2 / q) / V1
        rho = (1.0 / q) * ratio**2 * V0 / V2
        df2 = float(4.0 + (q + 2.0) / (q * rho - 1.0))
        # lambda = m / (E* (m - 2)), E* = 1 / (1 - A2 / q); pbkrtest's guard where m is 2.
        scaling = 1.0 if abs(df2 - 2.0) < 1e-2 else float(df2 * (1.0 - A2 / q) / (df2 - 2.0))
    Lb = mm(L, beta)
    wald = float(np.sum(Lb * _dense.cholesky_solve(_dense.cholesky(mm(mm(L, PhiA), L.T)), Lb)))
    F = scaling * wald / q
    if not (np.isfinite(F) and np.isfinite(df2) and df2 > 0):
        F = df2 = np.nan
    return pd.Series(
        {"F": F, "df1": float(q), "df2": df2, "p": float(stats.f.sf(F, q, df2)), "scaling": scaling}
    )


__all__ = ["KR_COLUMNS", "kenward_roger"]
