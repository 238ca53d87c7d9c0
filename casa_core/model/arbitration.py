"""Arbitration (the human's control authority alpha) and policy blending.

The blended action is u = alpha T(a) + (1 - alpha) u*, where T(a) is the direct
teleoperation of the user's input and u* the robot's action for the most likely
intent; alpha = 1 gives the user full control.

Each formula lives in one unchecked core (``_alpha_confidence``, ``_alpha_distance``,
``_alpha_belief``), called by the public function after checking its input and by the
assistant on its per-step path, on input it has checked once.
"""

from __future__ import annotations

import math

import numpy as np

from casa_core.model import _cores as cores
from casa_core.model._checks import as_finite_or_inf, require_positive, scalar_or_array


def alpha_confidence(beta):
    """CASA's arbitration: alpha = min(1, 1 / beta_hat of the most likely intent).

    Parameters
    ----------
    beta : float or array_like
        beta_hat of the most likely intent theta*, >= 0 (``inf`` allowed).

    Returns
    -------
    float or ndarray
        alpha in [0, 1]: 1 for ``beta <= 1`` (also ``beta = 0``), 0 for ``beta = inf``.

    Examples
    --------
    >>> alpha_confidence([0.5, 4.0])
    array([1.  , 0.25])
    >>> alpha_confidence(np.inf)
    0.0
    """
    beta = as_finite_or_inf("beta", beta, nonnegative=True)
    return scalar_or_array(cores.alpha_confidence(beta))


def alpha_distance(distance, D):
    """Policy blending's arbitration (PBA): alpha = min(1, d / D).

    Parameters
    ----------
    distance : float or array_like
        d, the distance (m) from the end effector to the predicted goal, >= 0.
    D : float
        The distance past which the robot does not assist, > 0 (0.55 m in the
        original implementation).

    Returns
    -------
    float or ndarray
        alpha in [0, 1].

    Examples
    --------
    >>> alpha_distance(0.275, 0.55)
    0.5
    >>> alpha_distance([0.0, 1.0], 0.55)
    array([0., 1.])
    """
    distance = as_finite_or_inf("distance", distance, nonnegative=True)
    require_positive(D=D)
    return scalar_or_array(cores.alpha_distance(distance, D))


def alpha_belief(p_star, n_intents):
    """Belief-based arbitration: alpha = 1 - (P* |Theta| - 1) / (|Theta| - 1), in [0, 1].

    The paper's text gives (P* |Theta| - 1) / (|Theta| - 1) but describes the
    behaviour "belief goes to 1 and thus sets the user's control authority to 0";
    we build the described behaviour (see docs/departures.md): alpha = 1 for a
    uniform belief, 0 for a certain one.

    With a single intent the formula is 0 / 0 and the belief, 1 by construction, is
    also the uniform one: it says nothing about which intent the user pursues, there
    being no alternative to compare. Belief arbitration then gives the user full
    control, alpha = 1, as for any uniform belief, rather than handing the robot
    full control on no evidence.

    Parameters
    ----------
    p_star : float or array_like
        P(theta* | xi), the belief in the most likely intent, in [0, 1].
    n_intents : int
        |Theta|, the number of intents, >= 1.

    Returns
    -------
    float or ndarray
        alpha, clipped to [0, 1]; 1 for ``n_intents == 1``.

    Raises
    ------
    ValueError
        On NaN or a ``p_star`` outside [0, 1], or an ``n_intents`` that is not an
        integer >= 1.

    Examples
    --------
    >>> alpha_belief([0.5, 1.0], 2)
    array([1., 0.])
    >>> alpha_belief(2 / 3, 3)
    0.5
    >>> alpha_belief(1.0, 1)
    1.0
    """
    p_star = as_finite_or_inf("p_star", p_star)
    if ((p_star < 0) | (p_star > 1)).any():
        raise ValueError("p_star must be a probability in [0, 1]")
    try:
        whole = int(n_intents) == n_intents and not isinstance(n_intents, bool)
    except (TypeError, ValueError, OverflowError):  # None, a string, inf
        whole = False
    if not whole or n_intents < 1:
        raise ValueError(f"belief arbitration needs an integer >= 1 intents, got {n_intents!r}")
    return scalar_or_array(cores.alpha_belief(p_star, n_intents))


def blend(alpha, user_action, robot_action):
    """Policy blending: alpha * user_action + (1 - alpha) * robot_action.

    Parameters
    ----------
    alpha : float or array_like
        The user's control authority, in [0, 1].
    user_action, robot_action : array_like
        T(a), the direct teleoperation of the user's input, and u*, the robot's action.

    Returns
    -------
    ndarray
        The blended action u.

    Examples
    --------
    >>> blend(0.25, np.array([1.0, 0.0]), np.array([0.0, 1.0]))
    array([0.25, 0.75])
    """
    if (  # every control tick: a scalar alpha and float actions, checked in two calls
        isinstance(alpha, float)
        and 0.0 <= alpha <= 1.0
        and isinstance(user_action, np.ndarray)
        and isinstance(robot_action, np.ndarray)
        and user_action.dtype == robot_action.dtype == np.float64
        and math.isfinite(user_action.sum() + robot_action.sum())
    ):
        return alpha * user_action + (1.0 - alpha) * robot_action
    return _checked_blend(alpha, user_action, robot_action)


def _checked_blend(alpha, user_action, robot_action):
    """:func:`blend` for any input: each argument checked and converted."""
    alpha = as_finite_or_inf("alpha", alpha)
    if ((alpha < 0) | (alpha > 1)).any():
        raise ValueError("alpha must lie in [0, 1]")
    user = as_finite_or_inf("user_action", user_action)
    robot = as_finite_or_inf("robot_action", robot_action)
    return alpha * user + (1.0 - alpha) * robot
