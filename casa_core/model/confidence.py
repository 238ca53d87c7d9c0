"""Situational confidence: suboptimality and the estimate beta_hat (paper, Sec. II-C).

Under the Laplace approximation (eq. laplace) the likelihood of a trajectory prefix
depends on the intent's cost only through its *suboptimality*

    S = C(xi_{0->t}) + C(xi*_{t->T}) - C(xi*_{0->T}),

the extra cost of the observed prefix plus the best completion over the best
trajectory from the start. Maximizing that likelihood in beta gives eq. beta_mle,
and adding an exponential prior Exp(lambda) gives eq. beta_map:

    beta_hat = t k / (2 (lambda + S)).
"""

from __future__ import annotations

import numpy as np

from casa_core.model import _cores as cores
from casa_core.model._checks import as_finite_or_inf, require_positive, scalar_or_array


def suboptimality(prefix_cost, cost_to_go, optimal_cost):
    """Suboptimality of a trajectory prefix for one intent, clamped at 0.

    Parameters
    ----------
    prefix_cost : float or array_like
        C(xi_{0->t}), the cost of the observed prefix.
    cost_to_go : float or array_like
        C(xi*_{t->T}), the optimal cost from the current state with the time left.
    optimal_cost : float or array_like
        C(xi*_{0->T}), the optimal cost from the start state.

    Returns
    -------
    float or ndarray
        ``prefix_cost + cost_to_go - optimal_cost``, clamped at 0: a numerical
        planner can return a start cost above the true optimum, and an observed
        trajectory can never beat the optimum (see docs/departures.md).

    Examples
    --------
    >>> suboptimality(3.0, 2.0, 4.0)
    1.0
    >>> suboptimality(1.0, 2.0, 4.0)
    0.0
    """
    prefix = as_finite_or_inf("prefix_cost", prefix_cost)
    to_go = as_finite_or_inf("cost_to_go", cost_to_go)
    optimal = as_finite_or_inf("optimal_cost", optimal_cost)
    with np.errstate(invalid="raise"):
        try:
            subopt = cores.suboptimality(prefix, to_go, optimal)
        except FloatingPointError as exc:
            raise ValueError("suboptimality of infinite costs is undefined (inf - inf)") from exc
    return scalar_or_array(subopt)


def beta_hat(subopt, t, k, lam=0.0):
    """Confidence estimate beta_hat = t k / (2 (lam + subopt)) (eqs. beta_mle, beta_map).

    Parameters
    ----------
    subopt : float or array_like
        Suboptimality of the prefix, >= 0 (see :func:`suboptimality`).
    t : float or array_like
        Number of time steps observed so far, >= 0.
    k : int
        Action dimensionality (7 joint velocities for the JACO arm).
    lam : float, default 0.0
        Rate of the exponential prior on beta; 0 gives the maximum-likelihood
        estimate (eq. beta_mle), lam > 0 the MAP estimate (eq. beta_map; the
        original implementation used 4).

    Returns
    -------
    float or ndarray
        beta_hat, never negative or NaN: 0 where ``t == 0`` (no evidence yet) and
        ``inf`` only where ``t > 0`` and ``subopt + lam == 0``.

    Raises
    ------
    ValueError
        On NaN or negative ``subopt``, ``t`` or ``lam``, or ``k <= 0``.

    Examples
    --------
    >>> beta_hat(3.0, t=4, k=7, lam=4.0)
    2.0
    >>> beta_hat(5.0, t=0, k=7)
    0.0
    >>> beta_hat(-0.0, t=1, k=7, lam=-0.0)  # no suboptimality and no prior: certain
    inf
    """
    subopt = as_finite_or_inf("subopt", subopt, nonnegative=True)
    t = as_finite_or_inf("t", t, nonnegative=True)
    lam = as_finite_or_inf("lam", lam, nonnegative=True)
    require_positive(k=k)
    beta = cores.beta_hat(subopt, t, k, lam)
    # inf / inf (infinite t with infinite suboptimality) has no meaning here.
    if np.isnan(beta).any():
        raise ValueError("beta_hat is undefined for infinite t together with infinite subopt")
    return scalar_or_array(beta)
