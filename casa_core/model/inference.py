"""Intent inference: the Boltzmann likelihood under Laplace's method and the posterior.

Dropping the Hessian ratio of eq. (laplace), which does not depend on beta, the
log-likelihood of a trajectory prefix given an intent with confidence beta is

    log P(xi_{0->t} | theta, beta) = -beta S + (t k / 2) log(beta / 2 pi),

with S the intent's suboptimality (:mod:`casa_core.model.confidence`). Under a uniform
prior over intents the posterior (eq. goal_inference) normalizes these likelihoods.
"""

from __future__ import annotations

from casa_core.model import _cores as cores
from casa_core.model._checks import as_finite_or_inf, require_positive, scalar_or_array


def log_likelihood(subopt, beta, t, k):
    """Log-likelihood of the observed prefix under one intent (eq. laplace, Hessians dropped).

    Parameters
    ----------
    subopt : float or array_like
        Suboptimality S >= 0 of the prefix for the intent.
    beta : float or array_like
        Rationality / confidence, >= 0 (``inf`` allowed).
    t : float or array_like
        Time steps observed, >= 0.
    k : int
        Action dimensionality.

    Returns
    -------
    float or ndarray
        ``-beta * subopt + (t k / 2) log(beta / (2 pi))``. With no evidence
        (``t == 0``) the second term is 0. At ``beta = inf`` the value is
        ``+inf`` for a perfect prefix (S = 0) and ``-inf`` otherwise; at
        ``beta = 0`` with ``t > 0`` it is ``-inf``.

    Examples
    --------
    >>> import numpy as np
    >>> round(log_likelihood(0.0, 2 * np.pi, t=3, k=7), 12)
    0.0
    """
    subopt = as_finite_or_inf("subopt", subopt, nonnegative=True)
    beta = as_finite_or_inf("beta", beta, nonnegative=True)
    t = as_finite_or_inf("t", t, nonnegative=True)
    require_positive(k=k)
    return scalar_or_array(cores.log_likelihood(subopt, beta, t, k))


def posterior(log_likelihoods):
    """Intent posterior P(theta | xi) under a uniform prior (eq. goal_inference).

    Parameters
    ----------
    log_likelihoods : array_like, shape (..., n_intents)
        Log-likelihood of the prefix under each intent (last axis).

    Returns
    -------
    ndarray, shape (..., n_intents)
        Probabilities summing to 1 along the last axis, computed stably (log-sum-exp)
        so that very negative log-likelihoods do not underflow to 0/0. Intents at
        ``+inf`` share the mass equally; if every intent is at ``-inf`` the data say
        nothing that separates them and the posterior is the uniform prior.

    Examples
    --------
    >>> import numpy as np
    >>> posterior([-1000.0, -1000.0 - np.log(3)])
    array([0.75, 0.25])
    """
    logs = as_finite_or_inf("log_likelihoods", log_likelihoods)
    if logs.ndim == 0 or logs.shape[-1] == 0:
        raise ValueError("log_likelihoods needs a last axis with at least one intent")
    return cores.posterior(logs)
