"""Compiled loops of the trajectory optimizer (numba, cached on disk).

A trajectory has 30 dependent steps and the batches are small, so numpy's per-call
overhead costs far more than the arithmetic; these loops run the same IEEE operations in
the same order as the array formulas they stand for (no ``fastmath``: no reordering, no
fused multiply-adds), so they give the same bits on every run. They are compiled once
per machine and cached (next to this file, or in numba's user cache directory where the
package is read-only).

All arrays are float64; trajectories are ``(B, n, 4)`` states ``[x, y, z, rot]`` in
units of the per-step limit (:func:`casa_core.planning.optimizer.feasible`).
"""

from __future__ import annotations

import math

import numba


@numba.njit(cache=True)
def _clip(value):
    """``value`` clipped to [-1, 1] (NaN stays NaN, as ``numpy.clip``)."""
    if value > 1.0:
        return 1.0
    if value < -1.0:
        return -1.0
    return value


@numba.njit(cache=True)
def _walk_row(start, targets, norm, out):
    """Walk one row from ``start`` ``(4,)`` toward ``targets`` ``(n, 4)`` into ``out``.

    Each step ``targets[t] - previous`` is clipped to [-1, 1] per axis, or (``norm``)
    its position part divided by ``max(|step|, 1)`` and its rot clipped; the walked
    state is ``previous + step``.
    """
    x, y, z, r = start[0], start[1], start[2], start[3]
    for t in range(targets.shape[0]):
        sx = targets[t, 0] - x
        sy = targets[t, 1] - y
        sz = targets[t, 2] - z
        sr = _clip(targets[t, 3] - r)
        if norm:
            length = math.sqrt(sx * sx + sy * sy + sz * sz)
            # max(length, 1) that keeps a NaN, as numpy.maximum does.
            divisor = 1.0 if length <= 1.0 else length
            sx, sy, sz = sx / divisor, sy / divisor, sz / divisor
        else:
            sx, sy, sz = _clip(sx), _clip(sy), _clip(sz)
        x, y, z, r = x + sx, y + sy, z + sz, r + sr
        out[t, 0], out[t, 1], out[t, 2], out[t, 3] = x, y, z, r


#: Adam's decay rates of the first and second moments, and its epsilon.
ADAM_BETA1, ADAM_BETA2, ADAM_EPS = 0.9, 0.999, 1e-12


@numba.njit(cache=True)
def walk(starts, targets, norm, out):
    """The feasible trajectories ``out`` ``(B, n, 4)`` from ``starts`` ``(B, 4)``.

    Row by row, :func:`_walk_row` toward ``targets`` ``(B, n, 4)``.
    """
    for b in range(targets.shape[0]):
        _walk_row(starts[b], targets[b], norm, out[b])


@numba.njit(cache=True)
def adam_step(states, grad, grad_scale, row_costs, m, v, best, best_cost, starts, lr, c1, c2, norm):
    """One optimizer iteration on ``states`` (in place); returns how far a state moved.

    First the best iterate: rows whose ``row_costs`` ``(B,)`` beat ``best_cost`` copy
    ``states`` into ``best``. Then Adam with the gradient ``grad * grad_scale``
    (``grad_scale`` ``(4,)``): ``m = 0.9 m + 0.1 g``, ``v = 0.999 v + 0.001 g**2``
    (with ``norm``, ``g**2`` of the position replaced by the mean of its three axes), the
    target ``states - lr (m / c1) / (sqrt(v / c2) + 1e-12)`` with the bias corrections
    ``c1 = 1 - 0.9**k`` and ``c2 = 1 - 0.999**k`` at iteration k, and the states become the
    walk from ``starts`` toward the target (:func:`_walk_row`). Returns the largest
    ``|new - old|`` over all states (NaN if any is NaN).
    """
    beta1, beta2, eps = ADAM_BETA1, ADAM_BETA2, ADAM_EPS
    batch, n = states.shape[0], states.shape[1]
    g = [0.0, 0.0, 0.0, 0.0]
    squared = [0.0, 0.0, 0.0, 0.0]
    target = states.copy()
    moved, nan = 0.0, False
    for b in range(batch):
        if row_costs[b] < best_cost[b]:
            best_cost[b] = row_costs[b]
            best[b] = states[b]
        for t in range(n):
            for a in range(4):
                g[a] = grad[b, t, a] * grad_scale[a]
                squared[a] = g[a] * g[a]
            if norm:
                shared = (squared[0] + squared[1] + squared[2]) / 3.0
                squared[0], squared[1], squared[2] = shared, shared, shared
            for a in range(4):
                m[b, t, a] = beta1 * m[b, t, a] + (1 - beta1) * g[a]
                v[b, t, a] = beta2 * v[b, t, a] + (1 - beta2) * squared[a]
                m_hat = m[b, t, a] / c1
                v_hat = v[b, t, a] / c2
                target[b, t, a] = states[b, t, a] - lr * m_hat / (math.sqrt(v_hat) + eps)
        walked = target[b]
        _walk_row(starts[b], target[b], norm, walked)
        for t in range(n):
            for a in range(4):
                step = abs(walked[t, a] - states[b, t, a])
                if step != step:
                    nan = True
                elif step > moved:
                    moved = step
                states[b, t, a] = walked[t, a]
    return math.nan if nan else moved
