"""Arbitration (the human's control authority alpha) and policy blending.

The blended action is u = alpha T(a) + (1 - alpha) u*, where T(a) is the direct
teleoperation of the user's input and u* the robot's action for the most likely
intent; alpha = 1 gives the user full control.
"""

from __future__ import annotations

import numpy as np

from casa_core._checks import as_finite_or_inf, scalar_or_array


def alpha_confidence(beta):
    """CASA's arbitration: alpha = min(1, 1 / beta_hat of the most likely intent).

    >>> alpha_confidence([0.5, 4.0])
    array([1.  , 0.25])
    """
    beta = as_finite_or_inf("beta", beta, nonnegative=True)
    with np.errstate(divide="ignore"):
        return scalar_or_array(np.minimum(1.0, 1.0 / beta))


def alpha_distance(distance, D):
    """Policy blending's arbitration (PBA): alpha = min(1, d / D).

    ``d`` is the distance to the predicted goal and ``D`` the distance past which
    the robot does not assist (0.55 m in the original implementation).

    >>> alpha_distance(0.275, 0.55)
    0.5
    """
    distance = as_finite_or_inf("distance", distance, nonnegative=True)
    if not (np.isfinite(D) and D > 0):
        raise ValueError(f"D (assistance distance) must be a positive number, got {D!r}")
    return scalar_or_array(np.minimum(1.0, distance / D))


def alpha_belief(p_star, n_intents):
    """Belief-based arbitration: alpha = 1 - (P* |Theta| - 1) / (|Theta| - 1), in [0, 1].

    The paper's text gives (P* |Theta| - 1) / (|Theta| - 1) but describes the
    behaviour "belief goes to 1 and thus sets the user's control authority to 0";
    we build the described behaviour (NOTES section 2): alpha = 1 for a uniform
    belief, 0 for a certain one.

    >>> alpha_belief([0.5, 1.0], 2)
    array([1., 0.])
    """
    p_star = as_finite_or_inf("p_star", p_star)
    if ((p_star < 0) | (p_star > 1)).any():
        raise ValueError("p_star must be a probability in [0, 1]")
    if int(n_intents) != n_intents or n_intents < 2:
        raise ValueError(f"belief arbitration needs at least 2 intents, got {n_intents!r}")
    alpha = 1.0 - (p_star * n_intents - 1.0) / (n_intents - 1.0)
    return scalar_or_array(np.clip(alpha, 0.0, 1.0))


def blend(alpha, user_action, robot_action):
    """Policy blending: alpha * user_action + (1 - alpha) * robot_action.

    >>> blend(0.25, np.array([1.0, 0.0]), np.array([0.0, 1.0]))
    array([0.25, 0.75])
    """
    alpha = as_finite_or_inf("alpha", alpha)
    if ((alpha < 0) | (alpha > 1)).any():
        raise ValueError("alpha must lie in [0, 1]")
    user = as_finite_or_inf("user_action", user_action)
    robot = as_finite_or_inf("robot_action", robot_action)
    return alpha * user + (1.0 - alpha) * robot


# Scalar cores on checked input, for the assistant's per-step path (same formulas).
def _alpha_confidence(beta: float) -> float:
    return 1.0 if beta <= 1.0 else 1.0 / beta


def _alpha_distance(distance: float, D: float) -> float:
    return min(1.0, distance / D)


def _alpha_belief(p_star: float, n_intents: int) -> float:
    return min(1.0, max(0.0, 1.0 - (p_star * n_intents - 1.0) / (n_intents - 1.0)))
