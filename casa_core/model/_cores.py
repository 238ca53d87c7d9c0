"""The equations' cores on checked input: the assistant's per-step path.

Each public function of :mod:`casa_core.model` checks its input, then computes with the
core of the same name here; the assistant (:mod:`casa_core.assist.assistant`), whose
inputs were checked once, calls the cores directly every inference step. One core, one
equation: the rules at the edges (no evidence, one intent, infinite costs) live here,
so the checked functions and the assistant cannot tell them differently.
"""

from __future__ import annotations

import numpy as np


def suboptimality(prefix, to_go, optimal) -> np.ndarray:
    """C(xi_0->t) + C(xi*_t->T) - C(xi*_0->T), clamped at 0."""
    return np.maximum(prefix + to_go - optimal, 0.0)


def beta_hat(subopt: np.ndarray, t, k, lam) -> np.ndarray:
    """t k / (2 (lam + subopt)); 0 where t k = 0 (no evidence)."""
    evidence = t * k
    # + 0.0 turns -0.0 (lam = subopt = -0.0 pass the checks) into 0.0, whose quotient is
    # +inf; every other value is unchanged.
    denominator = 2.0 * (lam + subopt) + 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(evidence == 0, 0.0, evidence / denominator)


def log_likelihood(subopt: np.ndarray, beta: np.ndarray, t, k) -> np.ndarray:
    """-beta subopt + (t k / 2) log(beta / 2 pi), -inf where that is inf - inf."""
    half_evidence = t * k / 2.0
    with np.errstate(divide="ignore", invalid="ignore"):
        fit = np.where(subopt == 0, 0.0, -beta * subopt)
        spread = np.where(half_evidence == 0, 0.0, half_evidence * np.log(beta / (2 * np.pi)))
        total = fit + spread
    # inf - inf: beta = inf with S > 0 means the prefix is impossible under the intent.
    return np.where(np.isnan(total), -np.inf, total)


def posterior(logs: np.ndarray) -> np.ndarray:
    """The normalized exponentials of ``logs`` along the last axis (log-sum-exp)."""
    certain = logs == np.inf
    if certain.any():
        # Rows with an intent at +inf share their mass among those; the others as below.
        has_certain = certain.any(axis=-1, keepdims=True)
        shared = certain / np.maximum(certain.sum(axis=-1, keepdims=True), 1)
        return np.where(has_certain, shared, posterior(np.where(has_certain, 0.0, logs)))
    top = logs.max(axis=-1, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    weights = np.exp(logs - top)
    total = weights.sum(axis=-1, keepdims=True)
    if (total > 0).all():  # the usual case: the same quotient, without the uniform fallback
        return weights / total
    uniform = np.full_like(weights, 1.0 / weights.shape[-1])
    with np.errstate(invalid="ignore"):
        return np.where(total > 0, weights / total, uniform)


def alpha_confidence(beta):
    """min(1, 1 / beta); 1 / 0 is inf, so beta = 0 gives 1."""
    with np.errstate(divide="ignore"):
        return np.minimum(1.0, np.divide(1.0, beta))


def alpha_distance(distance, D):
    """min(1, distance / D), D > 0."""
    return np.minimum(1.0, distance / D)


def alpha_belief(p_star, n_intents):
    """1 - (P* |Theta| - 1) / (|Theta| - 1) in [0, 1]; 1 for one intent (a belief of 1 by
    construction, no evidence: the user keeps control)."""
    if n_intents == 1:
        return np.ones_like(p_star)
    # np.clip's arithmetic (maximum, then minimum) without its overhead on a scalar.
    return np.minimum(np.maximum(1.0 - (p_star * n_intents - 1.0) / (n_intents - 1.0), 0.0), 1.0)
