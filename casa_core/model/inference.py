"""Intent inference: the Boltzmann likelihood under Laplace's method and the posterior.

Dropping the Hessian ratio of eq. (laplace), which does not depend on beta, the
log-likelihood of a trajectory prefix given an intent with confidence beta is

    log P(xi_{0->t} | theta, beta) = -beta S + (t k / 2) log(beta / 2 pi),

with S the intent's suboptimality (:mod:`casa_core.model.confidence`). Under a uniform
prior over intents the posterior (eq. goal_inference) normalizes these likelihoods.
"""

from __future__ import annotations

import numpy as np

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
    >>> round(log_likelihood(0.0, 2 * np.pi, t=3, k=7), 12)
    0.0
    """
    subopt = as_finite_or_inf("subopt", subopt, nonnegative=True)
    beta = as_finite_or_inf("beta", beta, nonnegative=True)
    t = as_finite_or_inf("t", t, nonnegative=True)
    require_positive(k=k)
    return scalar_or_array(_log_likelihood(subopt, beta, t, k))


def _log_likelihood(subopt: np.ndarray, beta: np.ndarray, t, k) -> np.ndarray:
    """:func:`log_likelihood` on checked input (the assistant's per-step path)."""
    half_evidence = t * k / 2.0
    with np.errstate(divide="ignore", invalid="ignore"):
        fit = np.where(subopt == 0, 0.0, -beta * subopt)
        spread = np.where(half_evidence == 0, 0.0, half_evidence * np.log(beta / (2 * np.pi)))
        total = fit + spread
    # inf - inf: beta = inf with S > 0 means the prefix is impossible under the intent.
    return np.where(np.isnan(total), -np.inf, total)


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
    >>> posterior([-1000.0, -1000.0 - np.log(3)])
    array([0.75, 0.25])
    """
    logs = as_finite_or_inf("log_likelihoods", log_likelihoods)
    if logs.ndim == 0 or logs.shape[-1] == 0:
        raise ValueError("log_likelihoods needs a last axis with at least one intent")
    return _posterior(logs)


def _posterior(logs: np.ndarray) -> np.ndarray:
    """:func:`posterior` on checked input (the assistant's per-step path)."""
    certain = logs == np.inf
    if certain.any():
        # Rows with an intent at +inf share their mass among those; the others as below.
        has_certain = certain.any(axis=-1, keepdims=True)
        shared = certain / np.maximum(certain.sum(axis=-1, keepdims=True), 1)
        return np.where(has_certain, shared, _posterior(np.where(has_certain, 0.0, logs)))
    top = logs.max(axis=-1, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    weights = np.exp(logs - top)
    total = weights.sum(axis=-1, keepdims=True)
    if (total > 0).all():  # the usual case: the same quotient, without the uniform fallback
        return weights / total
    uniform = np.full_like(weights, 1.0 / weights.shape[-1])
    with np.errstate(invalid="ignore"):
        return np.where(total > 0, weights / total, uniform)
