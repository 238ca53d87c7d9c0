"""Compiled loops of the learned cost and its gradient (numba, cached on disk).

:class:`~casa_core.learning.numpy_cost.NumpyStateCost` runs the whole learned cost here:
the features of the states, the network's matrix products (:func:`linear`), the leaky
ReLUs, the sigmoid and the chain rule back to the states, in one call of :func:`cost` or
:func:`cost_and_gradient` (a planner's iteration pays one call's overhead). Each loop runs a fixed
sequence of IEEE operations (no ``fastmath``: no reordering, no fused multiply-adds), so
the same states give the same bits on every run and on every processor, whatever BLAS
kernel the processor would get. They are compiled once per machine and cached (next to
this file, or in numba's user cache directory where the package is read-only).

The formula these loops compute is defined once, in torch:
:func:`casa_core.learning.features.bounded_cost` on
:func:`~casa_core.learning.features.cost_logits`; ``tests/learning/test_speed_equivalence.py``
checks them against it (:func:`costs` alone to float64 rounding, the whole cost and its
gradient to float32 rounding of the network's sums).

States are float64 ``(n, 4)`` rows ``[x, y, z, rot]``; the network's inputs and layers
are float32 ``(n, 12 + 4K)`` and ``(n, H)`` for K objects and H hidden units, the inputs
in the order of :func:`casa_core.learning.features.state_features`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

#: Squared length added under a distance's square root (features.state_features: 1 mm).
DISTANCE_EPS = 1e-6


class Layers(NamedTuple):
    """The network's weights as the loops read them: the forward pass multiplies by
    W^T, the backward pass by W (contiguous copies), with zero biases for the latter."""

    w1_t: np.ndarray
    b1: np.ndarray
    w2_t: np.ndarray
    b2: np.ndarray
    w3_t: np.ndarray
    b3: np.ndarray
    w2: np.ndarray
    w1: np.ndarray
    w3: np.ndarray  # the output layer's one row
    no_hidden_bias: np.ndarray
    no_input_bias: np.ndarray


class Work(NamedTuple):
    """The scratch arrays of one call on ``n`` states (the features, the forward pass, the
    backward pass), reused between calls of the same ``n``."""

    inputs: np.ndarray
    cos_sin: np.ndarray
    distances: np.ndarray
    h1: np.ndarray
    a1: np.ndarray
    h2: np.ndarray
    a2: np.ndarray
    logits: np.ndarray
    slopes: np.ndarray
    d_h2: np.ndarray
    d_h1: np.ndarray
    d_inputs: np.ndarray


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

    Four rows of ``x`` and four of ``w`` at a time, the innermost loop along ``out``'s
    row: it vectorises and uses each loaded weight four times. Fewer than 8 columns
    (the last layer's one) run eight rows' sums side by side instead, so that they do
    not wait on each other. No sum changes its order, so any vector width gives the
    bits of a plain loop (tests/learning: bit for bit).
    """
    n_rows = x.shape[0]
    if w.shape[1] < 8:
        _narrow(x, w, bias, out)
        return
    quads = n_rows - n_rows % 4
    for i in range(0, quads, 4):
        _four_rows(x, w, bias, out, i)
    for i in range(quads, n_rows):
        _one_row(x, w, bias, out, i)


@numba.njit(cache=True, inline="always")
def _four_rows(x, w, bias, out, i):
    n_k, n_j = w.shape
    blocks = n_k - n_k % 4
    for r in range(4):
        for j in range(n_j):
            out[i + r, j] = bias[j]
    for k in range(0, blocks, 4):
        a0, a1, a2, a3 = x[i, k], x[i, k + 1], x[i, k + 2], x[i, k + 3]
        b0, b1, b2, b3 = x[i + 1, k], x[i + 1, k + 1], x[i + 1, k + 2], x[i + 1, k + 3]
        c0, c1, c2, c3 = x[i + 2, k], x[i + 2, k + 1], x[i + 2, k + 2], x[i + 2, k + 3]
        d0, d1, d2, d3 = x[i + 3, k], x[i + 3, k + 1], x[i + 3, k + 2], x[i + 3, k + 3]
        for j in range(n_j):
            w0, w1, w2, w3 = w[k, j], w[k + 1, j], w[k + 2, j], w[k + 3, j]
            out[i, j] = (((out[i, j] + a0 * w0) + a1 * w1) + a2 * w2) + a3 * w3
            out[i + 1, j] = (((out[i + 1, j] + b0 * w0) + b1 * w1) + b2 * w2) + b3 * w3
            out[i + 2, j] = (((out[i + 2, j] + c0 * w0) + c1 * w1) + c2 * w2) + c3 * w3
            out[i + 3, j] = (((out[i + 3, j] + d0 * w0) + d1 * w1) + d2 * w2) + d3 * w3
    for k in range(blocks, n_k):
        for r in range(4):
            for j in range(n_j):
                out[i + r, j] += x[i + r, k] * w[k, j]


@numba.njit(cache=True, inline="always")
def _one_row(x, w, bias, out, i):
    for j in range(w.shape[1]):
        out[i, j] = bias[j]
    for k in range(w.shape[0]):
        for j in range(w.shape[1]):
            out[i, j] += x[i, k] * w[k, j]


@numba.njit(cache=True, inline="always")
def _narrow(x, w, bias, out):
    n_rows, n_k = x.shape
    eights = n_rows - n_rows % 8
    for j in range(w.shape[1]):
        for i in range(0, eights, 8):
            s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = bias[j]
            for k in range(n_k):
                wk = w[k, j]
                s0, s1 = s0 + x[i, k] * wk, s1 + x[i + 1, k] * wk
                s2, s3 = s2 + x[i + 2, k] * wk, s3 + x[i + 3, k] * wk
                s4, s5 = s4 + x[i + 4, k] * wk, s5 + x[i + 5, k] * wk
                s6, s7 = s6 + x[i + 6, k] * wk, s7 + x[i + 7, k] * wk
            out[i, j], out[i + 1, j], out[i + 2, j], out[i + 3, j] = s0, s1, s2, s3
            out[i + 4, j], out[i + 5, j], out[i + 6, j], out[i + 7, j] = s4, s5, s6, s7
        for i in range(eights, n_rows):
            total = bias[j]
            for k in range(n_k):
                total += x[i, k] * w[k, j]
            out[i, j] = total


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

    :func:`casa_core.learning.features.bounded_cost` with ``offset``, written out: in
    float64 from the float32 ``logits``; ``slopes`` (float32) is
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


@numba.njit(cache=True)
def cost(states, objects, length_scale, basis, layers, slope, cost_scale, offset, work, values):
    """The whole learned cost of ``states`` into ``values``, in one call (no gradient).

    ``layers`` (:class:`Layers`) and ``work`` (:class:`Work`) are
    :class:`~casa_core.learning.numpy_cost.NumpyStateCost`'s arrays; :func:`features`,
    the three :func:`linear` layers with their leaky ReLUs and :func:`costs`, as the
    separate calls would run them.
    """
    features(states, objects, length_scale, basis, work.inputs, work.cos_sin, work.distances)
    linear(work.inputs, layers.w1_t, layers.b1, work.h1)
    leaky_relu(work.h1, slope, work.a1)
    linear(work.a1, layers.w2_t, layers.b2, work.h2)
    leaky_relu(work.h2, slope, work.a2)
    linear(work.a2, layers.w3_t, layers.b3, work.logits)
    costs(work.logits[:, 0], cost_scale, offset, values, work.slopes)


@numba.njit(cache=True)
def cost_and_gradient(
    states, objects, length_scale, basis, layers, slope, cost_scale, offset, work, values, grad
):
    """:func:`cost` and the gradient ``grad`` ``(n, 4)`` of the costs' sum in the states.

    The network's backward pass as autograd runs it (:func:`output_backward`, the two
    transposed products, :func:`leaky_relu_backward`), then :func:`features_backward`.
    """
    cost(states, objects, length_scale, basis, layers, slope, cost_scale, offset, work, values)
    output_backward(work.slopes, layers.w3, work.h2, slope, work.d_h2)
    linear(work.d_h2, layers.w2, layers.no_hidden_bias, work.d_h1)
    leaky_relu_backward(work.d_h1, work.h1, slope)
    linear(work.d_h1, layers.w1, layers.no_input_bias, work.d_inputs)
    features_backward(
        work.d_inputs, states, objects, length_scale, basis, work.cos_sin, work.distances, grad
    )
