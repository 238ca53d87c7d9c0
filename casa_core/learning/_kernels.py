"""Compiled loops of the learned cost and its gradient (numba, cached on disk).

:class:`~casa_core.learning.numpy_cost.NumpyStateCost` runs the whole learned cost here:
the features of the states, the network's matrix products (:func:`linear`), the leaky
ReLUs, the sigmoid and the chain rule back to the states. Each loop runs a fixed
sequence of IEEE operations (no ``fastmath``: no reordering, no fused multiply-adds), so
the same states give the same bits on every run and on every processor, whatever BLAS
kernel the processor would get. They are compiled once per machine and cached (next to
this file, or in numba's user cache directory where the package is read-only).

States are float64 ``(n, 4)`` rows ``[x, y, z, rot]``; the network's inputs and layers
are float32 ``(n, 12 + 4K)`` and ``(n, H)`` for K objects and H hidden units, the inputs
in the order of :func:`casa_core.learning.features.state_features`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: Squared length added under a distance's square root (features.state_features: 1 mm).
DISTANCE_EPS = 1e-6


@numba.njit(cache=True)
def features(states, objects, length_scale, basis, inputs, cos_sin, distances):
    """The network's inputs of ``states``, and what the gradient needs of them.

    Writes ``inputs`` (float32): the rotation ``cos A + sin B + C`` of rot (``basis``
    ``(3, 9)`` holds A, B, C), then the position, each offset ``object - position`` and
    each distance ``sqrt(|offset|**2 + 1e-6)``, divided by ``length_scale``, all in float64
    before the one cast (beyond float32's range: inf). Also ``cos_sin`` ``(n, 2)`` and the
    distances ``(n, K)``, in float64.
    """
    k = objects.shape[0]
    for i in range(states.shape[0]):
        c, s = math.cos(states[i, 3]), math.sin(states[i, 3])
        cos_sin[i, 0], cos_sin[i, 1] = c, s
        for j in range(9):
            inputs[i, j] = np.float32(c * basis[0, j] + s * basis[1, j] + basis[2, j])
        for a in range(3):
            inputs[i, 9 + a] = np.float32(states[i, a] / length_scale)
        for o in range(k):
            dx = objects[o, 0] - states[i, 0]
            dy = objects[o, 1] - states[i, 1]
            dz = objects[o, 2] - states[i, 2]
            inputs[i, 12 + 3 * o] = np.float32(dx / length_scale)
            inputs[i, 13 + 3 * o] = np.float32(dy / length_scale)
            inputs[i, 14 + 3 * o] = np.float32(dz / length_scale)
            distance = math.sqrt(dx * dx + dy * dy + dz * dz + DISTANCE_EPS)
            distances[i, o] = distance
            inputs[i, 12 + 3 * k + o] = np.float32(distance / length_scale)


@numba.njit(cache=True)
def linear(x, w, bias, out):
    """``out = bias + x @ w`` (float32): each sum starts at the bias and adds
    ``x[i, k] * w[k, j]`` in the order of k, each product and sum rounded on its own.

    Two rows of ``x`` and four of ``w`` at a time, the innermost loop along ``out``'s
    row: it vectorises and uses each loaded weight twice, and no sum changes its order,
    so any vector width gives the bits of a plain loop (tests/learning: bit for bit).
    """
    n_rows, n_k = x.shape
    pairs = n_rows - n_rows % 2
    for i in range(0, pairs, 2):
        _two_rows(x, w, bias, out, i)
    if pairs < n_rows:
        _one_row(x, w, bias, out, n_rows - 1)


@numba.njit(cache=True, inline="always")
def _two_rows(x, w, bias, out, i):
    n_k, n_j = w.shape
    blocks = n_k - n_k % 4
    for j in range(n_j):
        out[i, j] = bias[j]
        out[i + 1, j] = bias[j]
    for k in range(0, blocks, 4):
        a0, a1, a2, a3 = x[i, k], x[i, k + 1], x[i, k + 2], x[i, k + 3]
        b0, b1, b2, b3 = x[i + 1, k], x[i + 1, k + 1], x[i + 1, k + 2], x[i + 1, k + 3]
        for j in range(n_j):
            w0, w1, w2, w3 = w[k, j], w[k + 1, j], w[k + 2, j], w[k + 3, j]
            out[i, j] = (((out[i, j] + a0 * w0) + a1 * w1) + a2 * w2) + a3 * w3
            out[i + 1, j] = (((out[i + 1, j] + b0 * w0) + b1 * w1) + b2 * w2) + b3 * w3
    for k in range(blocks, n_k):
        for j in range(n_j):
            out[i, j] += x[i, k] * w[k, j]
            out[i + 1, j] += x[i + 1, k] * w[k, j]


@numba.njit(cache=True, inline="always")
def _one_row(x, w, bias, out, i):
    for j in range(w.shape[1]):
        out[i, j] = bias[j]
    for k in range(w.shape[0]):
        for j in range(w.shape[1]):
            out[i, j] += x[i, k] * w[k, j]


@numba.njit(cache=True)
def leaky_relu(h, slope, out):
    """``out = h`` where ``h > 0``, else ``h * slope`` (float32, as torch's leaky_relu)."""
    for i in range(h.shape[0]):
        for j in range(h.shape[1]):
            x = h[i, j]
            out[i, j] = x if x > 0 else x * slope


@numba.njit(cache=True)
def leaky_relu_backward(grad, h, slope):
    """``grad`` times the leaky ReLU's slope at ``h``, in place (torch's leaky_relu_backward)."""
    for i in range(h.shape[0]):
        for j in range(h.shape[1]):
            if not h[i, j] > 0:
                grad[i, j] = grad[i, j] * slope


@numba.njit(cache=True)
def costs(logits, cost_scale, offset, values, slopes):
    """``values = cost_scale * sigmoid(logits) - offset`` and its slopes in the logits.

    In float64 from the float32 ``logits``; ``slopes`` (float32) is
    ``cost_scale * sigmoid * (1 - sigmoid)`` (only where ``slopes`` has rows).
    """
    for i in range(logits.shape[0]):
        sigmoid = 1.0 / (1.0 + math.exp(-np.float64(logits[i])))
        values[i] = cost_scale * sigmoid - offset
        if i < slopes.shape[0]:
            slopes[i] = np.float32(cost_scale * sigmoid * (1.0 - sigmoid))


@numba.njit(cache=True)
def output_backward(slopes, w3, h2, slope, d_h2):
    """``d_h2 = outer(slopes, w3)`` through the second leaky ReLU at ``h2`` (float32)."""
    for i in range(h2.shape[0]):
        for j in range(h2.shape[1]):
            g = slopes[i] * w3[j]
            d_h2[i, j] = g if h2[i, j] > 0 else g * slope


@numba.njit(cache=True)
def features_backward(d_inputs, states, objects, length_scale, basis, cos_sin, distances, grad):
    """The gradient ``grad`` ``(n, 4)`` in the states, from the one ``d_inputs`` in the inputs.

    The chain rule through :func:`features`: the position gets its own columns and
    minus each offset's, over ``length_scale``, and minus each distance's times
    ``offset / (length_scale * distance)``; rot gets ``d_R . (cos B - sin A)``.
    """
    k = objects.shape[0]
    first = 12 + 3 * k
    for i in range(states.shape[0]):
        for a in range(3):
            linear = np.float64(d_inputs[i, 9 + a])
            for o in range(k):
                linear -= np.float64(d_inputs[i, 12 + 3 * o + a])
            grad[i, a] = linear / length_scale
        for o in range(k):
            along = np.float64(d_inputs[i, first + o]) / (length_scale * distances[i, o])
            for a in range(3):
                grad[i, a] -= along * (objects[o, a] - states[i, a])
        turned_a, turned_b = 0.0, 0.0
        for j in range(9):
            d = np.float64(d_inputs[i, j])
            turned_a += d * basis[0, j]
            turned_b += d * basis[1, j]
        grad[i, 3] = cos_sin[i, 0] * turned_b - cos_sin[i, 1] * turned_a
