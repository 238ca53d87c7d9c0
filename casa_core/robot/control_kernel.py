"""One control tick of the arm's Cartesian velocity controller, compiled (numba).

:meth:`casa_core.robot.sim.ArmSimulation.joint_velocities` runs 20 times per simulated
second; written in numpy it spends most of its time in the overhead of some thirty calls
on arrays of 4 to 42 numbers. :func:`joint_velocities` computes the same formula in one
compiled call; :func:`joint_velocities_numpy` is the formula written plainly in numpy,
the reference the tests hold the compiled one to (they agree to float rounding: the
6 x 6 system is solved here by Cholesky, there by LU).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from casa_core.robot import kinematics as kin

_R0 = kin.EE_ROTATION_AT_ZERO.copy()
_BOUNDED_INDEX = np.flatnonzero(np.isfinite(kin.JOINT_LOWER))
_LOWER_B = kin.JOINT_LOWER[_BOUNDED_INDEX].copy()
_UPPER_B = kin.JOINT_UPPER[_BOUNDED_INDEX].copy()
_MIDDLE_B = (_LOWER_B + _UPPER_B) / 2
_SPEED = kin.JOINT_MAX_SPEED.copy()
_N = kin.N_JOINTS


def limit_gradient(q: np.ndarray) -> np.ndarray:
    """``|dH/dq|`` of the joint-limit index ``H = sum (u - l)^2 / (4 (u - q)(q - l))``.

    Zero for unbounded joints; grows without bound as a joint reaches a limit.

    Examples
    --------
    >>> gradient = limit_gradient(kin.HOME_CONFIGURATION)
    >>> gradient.shape, float(gradient[0])
    ((7,), 0.0)
    """
    bounded = q[_BOUNDED_INDEX]
    to_lower = np.maximum(bounded - _LOWER_B, 1e-4)
    to_upper = np.maximum(_UPPER_B - bounded, 1e-4)
    gradient = np.zeros_like(q)
    span = _UPPER_B - _LOWER_B
    gradient[_BOUNDED_INDEX] = (
        span**2 * np.abs(2 * bounded - _UPPER_B - _LOWER_B) / (4 * to_lower**2 * to_upper**2)
    )
    return gradient


def joint_velocities_numpy(jac, q, state, reference, rotation, action, gains):
    """The controller's joint velocities and next reference, in plain numpy.

    Parameters
    ----------
    jac : ndarray, shape (6, 7)
        pybullet's Jacobian of the tool, rows ``[v; omega]``.
    q : ndarray, shape (7,)
        Joint angles.
    state, reference : ndarray, shape (4,)
        The arm's ``[x, y, z, rot]`` and the reference pose it tracks.
    rotation : ndarray, shape (3, 3)
        The tool's orientation.
    action : ndarray, shape (4,)
        The commanded Cartesian velocity ``[vx, vy, vz, vrot]``.
    gains : sequence of float
        ``(dt, max_lag, position_gain, orientation_gain, damping, null_gain)``.

    Returns
    -------
    qdot : ndarray, shape (7,)
    reference : ndarray, shape (4,)
        The reference advanced by this tick.

    Examples
    --------
    >>> q = kin.HOME_CONFIGURATION
    >>> state = np.array([0.4, 0.0, 0.3, 0.0])
    >>> qdot, reference = joint_velocities_numpy(
    ...     kin.jacobian(q), q, state, state, kin.ee_rotation(0.0), np.zeros(4),
    ...     (0.05, 0.01, 5.0, 5.0, 0.02, 0.5),
    ... )
    >>> qdot.shape, bool((reference == state).all())
    ((7,), True)
    """
    dt, max_lag, position_gain, orientation_gain, damping, null_gain = gains
    lag = np.minimum(np.maximum(reference - state, -max_lag), max_lag)
    reference = state + lag + action * dt
    target = kin.ee_rotation(state[3] + lag[3])
    twist = np.concatenate(
        [
            action[:3] + position_gain * lag[:3],
            orientation_gain * kin.orientation_error(target, rotation),
        ]
    )
    # Weighted damped least squares (Chan and Dubey 1995): a bounded joint nearing a
    # limit gets a heavy weight, so the redundant arm turns its other joints instead.
    weighted = jac * (1.0 / (1.0 + limit_gradient(q)))
    gram = weighted @ jac.T + damping**2 * np.eye(6)
    # In the null space of the task, centre the bounded joints in their range:
    # qdot = c + W^-1 J^T (J W^-1 J^T + damping^2 I)^-1 (twist - J c).
    centring = np.zeros(_N)
    centring[_BOUNDED_INDEX] = (_MIDDLE_B - q[_BOUNDED_INDEX]) * null_gain
    qdot = centring + weighted.T @ np.linalg.solve(gram, twist - jac @ centring)
    # The rotate keys turn the last joint itself: its axis is the tool's z axis
    # reversed, and turning it moves neither the cup nor that axis.
    qdot[6] -= action[3]
    excess = np.max(np.abs(qdot) / _SPEED)
    return (qdot / excess if excess > 1.0 else qdot), reference


@njit(cache=True)
def joint_velocities(linear, angular, q, state, reference, rotation, action, gains):
    """:func:`joint_velocities_numpy` compiled; ``linear``, ``angular`` as pybullet gives them.

    ``linear`` and ``angular`` are the Jacobian's rows (3 sequences of 7 numbers each).
    ``reference`` is advanced in place. Returns ``qdot``, or an empty array when
    ``action`` is not finite.

    Examples
    --------
    >>> q = kin.HOME_CONFIGURATION
    >>> jac = kin.jacobian(q)
    >>> state = np.array([0.4, 0.0, 0.3, 0.0])
    >>> gains = np.array([0.05, 0.01, 5.0, 5.0, 0.02, 0.5])
    >>> action = np.array([0.05, 0.0, 0.0, 0.0])
    >>> fast = joint_velocities(jac[:3], jac[3:], q, state, state.copy(),
    ...                         kin.ee_rotation(0.0), action, gains)
    >>> plain, _ = joint_velocities_numpy(jac, q, state, state, kin.ee_rotation(0.0),
    ...                                   action, gains)
    >>> bool(np.allclose(fast, plain, rtol=0, atol=1e-12))
    True
    """
    for i in range(4):
        if not math.isfinite(action[i]):
            return np.empty(0)
    jac = np.empty((6, _N))
    for j in range(_N):
        for i in range(3):
            jac[i, j] = linear[i][j]
            jac[3 + i, j] = angular[i][j]
    twist = _twist(state, reference, rotation, action, gains)
    inv_weight, centring = _joint_weights(q, gains[5])
    step = _damped_solve(jac, inv_weight, centring, twist, gains[4])
    qdot = np.empty(_N)
    excess = 0.0
    for j in range(_N):
        total = 0.0
        for i in range(6):
            total += jac[i, j] * step[i]
        qdot[j] = centring[j] + inv_weight[j] * total
    qdot[6] -= action[3]
    for j in range(_N):
        excess = max(excess, abs(qdot[j]) / _SPEED[j])
    if excess > 1.0:
        for j in range(_N):
            qdot[j] /= excess
    return qdot


@njit(cache=True)
def _twist(state, reference, rotation, action, gains):
    """The tool twist ``(6,)`` asked of the arm: the action plus the gains' pull toward the
    reference (advanced in place by the action, its lag bounded) and its orientation."""
    dt, max_lag, position_gain, orientation_gain = gains[0], gains[1], gains[2], gains[3]
    lag = np.empty(4)
    for i in range(4):
        lag[i] = min(max(reference[i] - state[i], -max_lag), max_lag)
        reference[i] = state[i] + lag[i] + action[i] * dt
    # target = R0 Rz(angle); delta = target rotation^T; twist = the gains' pull.
    angle = state[3] + lag[3]
    c, s = math.cos(angle), math.sin(angle)
    target = np.empty((3, 3))
    for i in range(3):
        target[i, 0] = _R0[i, 0] * c + _R0[i, 1] * s
        target[i, 1] = -_R0[i, 0] * s + _R0[i, 1] * c
        target[i, 2] = _R0[i, 2]
    delta = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for k in range(3):
                delta[i, j] += target[i, k] * rotation[j, k]
    twist = np.empty(6)
    for i in range(3):
        twist[i] = action[i] + position_gain * lag[i]
    twist[3] = orientation_gain * (0.5 * (delta[2, 1] - delta[1, 2]))
    twist[4] = orientation_gain * (0.5 * (delta[0, 2] - delta[2, 0]))
    twist[5] = orientation_gain * (0.5 * (delta[1, 0] - delta[0, 1]))
    return twist


@njit(cache=True)
def _joint_weights(q, null_gain):
    """W^-1 (the bounded joints weighted down near their limits) and the null-space
    centring c of the bounded joints toward the middle of their range."""
    inv_weight = np.ones(_N)
    centring = np.zeros(_N)
    for b in range(len(_BOUNDED_INDEX)):
        j = _BOUNDED_INDEX[b]
        to_lower = max(q[j] - _LOWER_B[b], 1e-4)
        to_upper = max(_UPPER_B[b] - q[j], 1e-4)
        span = _UPPER_B[b] - _LOWER_B[b]
        gradient = span**2 * abs(2 * q[j] - _UPPER_B[b] - _LOWER_B[b])
        gradient /= 4 * to_lower**2 * to_upper**2
        inv_weight[j] = 1.0 / (1.0 + gradient)
        centring[j] = (_MIDDLE_B[b] - q[j]) * null_gain
    return inv_weight, centring


@njit(cache=True)
def _damped_solve(jac, inv_weight, centring, twist, damping):
    """(J W^-1 J^T + damping^2 I)^-1 (twist - J c), by Cholesky."""
    # gram = J W^-1 J^T + damping^2 I (symmetric positive definite), rhs = twist - J c.
    gram = np.empty((6, 6))
    rhs = np.empty(6)
    for i in range(6):
        for k in range(i + 1):
            total = 0.0
            for j in range(_N):
                total += jac[i, j] * inv_weight[j] * jac[k, j]
            gram[i, k] = total
        gram[i, i] += damping * damping
        total = twist[i]
        for j in range(_N):
            total -= jac[i, j] * centring[j]
        rhs[i] = total
    # Cholesky gram = L L^T in the lower triangle, then the two triangular solves.
    for i in range(6):
        for k in range(i + 1):
            total = gram[i, k]
            for m in range(k):
                total -= gram[i, m] * gram[k, m]
            gram[i, k] = math.sqrt(total) if i == k else total / gram[k, k]
    for i in range(6):
        total = rhs[i]
        for m in range(i):
            total -= gram[i, m] * rhs[m]
        rhs[i] = total / gram[i, i]
    for i in range(5, -1, -1):
        total = rhs[i]
        for m in range(i + 1, 6):
            total -= gram[m, i] * rhs[m]
        rhs[i] = total / gram[i, i]
    return rhs


@njit(cache=True)
def read_pose(position, matrix, previous_rot):
    """The state ``[x, y, z, rot]`` and rotation ``(3, 3)`` of pybullet's tool pose.

    ``position`` and ``matrix`` (row-major, 9 numbers) as pybullet gives them; ``rot``
    is :func:`~casa_core.robot.kinematics.rot_of` of the rotation, unwrapped: the
    previous reading plus the change wrapped into ``[-pi, pi)``.

    Examples
    --------
    >>> state, rotation = read_pose((0.4, 0.0, 0.3), tuple(kin.ee_rotation(0.5).ravel()), 6.0)
    >>> [round(float(v), 6) for v in state], bool((rotation == kin.ee_rotation(0.5)).all())
    ([0.4, 0.0, 0.3, 6.783185], True)
    """
    rotation = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            rotation[i, j] = matrix[3 * i + j]
    # rot_of: the angle of (R0^T rotation)[:, 0] in the plane of its first two entries.
    cosine = _R0[0, 0] * rotation[0, 0] + _R0[1, 0] * rotation[1, 0] + _R0[2, 0] * rotation[2, 0]
    sine = _R0[0, 1] * rotation[0, 0] + _R0[1, 1] * rotation[1, 0] + _R0[2, 1] * rotation[2, 0]
    change = math.atan2(sine, cosine) - previous_rot
    state = np.empty(4)
    for i in range(3):
        state[i] = position[i]
    state[3] = previous_rot + ((change + math.pi) % (2 * math.pi) - math.pi)
    return state, rotation
