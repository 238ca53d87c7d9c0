"""The learned per-state cost and its gradient without autograd, for planning.

The planner evaluates a learned cost and its gradient in the states thousands of
times per learned intent, on a few hundred states at a time. For a network this
small, torch's per-operation and autograd overhead costs several times the
arithmetic; :class:`NumpyStateCost` computes the same formula
(:mod:`casa_core.learning.features`: features in float64, the network in float32,
the sigmoid in float64) and its gradient by hand (the chain rule through the
network and the features), with no autograd and no BLAS: all of it in compiled loops
of a fixed order (:mod:`casa_core.learning._kernels`), into work arrays kept per row
count, so the planner's results do not depend on the processor's BLAS kernel. Training
the network's weights stays in torch (:mod:`casa_core.learning.network`: the same
products, with autograd).

The values agree with the torch formula to float32 rounding (the matrix products
sum in another order): ``tests/learning/test_speed_equivalence.py`` checks costs and
gradients against torch's autograd.

Examples
--------
>>> import torch
>>> from casa_core.learning.features import bounded_cost, cost_logits, cost_network
>>> network = cost_network(16, hidden=8, negative_slope=0.01, seed=0)
>>> objects = np.array([[0.4, 0.22, 0.12]])
>>> cost = NumpyStateCost(network, objects=objects, length_scale=0.1, cost_scale=10.0)
>>> states = np.array([[[0.4, 0.1, 0.2, 0.3], [0.35, 0.1, 0.25, 0.0]]])
>>> values, grad = cost.value_and_grad(states)
>>> reference = bounded_cost(
...     cost_logits(
...         network, torch.from_numpy(states), objects=torch.from_numpy(objects),
...         length_scale=0.1,
...     ),
...     10.0,
... ).detach().numpy()
>>> values.shape, grad.shape, bool(np.allclose(values, reference, rtol=1e-5))
((1, 2), (1, 2, 4), True)
"""

from __future__ import annotations

import numpy as np
import torch

from casa_core.learning import _kernels
from casa_core.planning.rotation import R0

# R(rot) = cos(rot) A + sin(rot) B + C, row-major (planning.rotation.end_effector_rotation).
_ZERO = np.zeros(3)
_BASIS = np.stack(
    [
        np.stack([R0[:, 0], R0[:, 1], _ZERO], axis=-1).reshape(9),
        np.stack([R0[:, 1], -R0[:, 0], _ZERO], axis=-1).reshape(9),
        np.stack([_ZERO, _ZERO, R0[:, 2]], axis=-1).reshape(9),
    ]
)
#: Row counts whose work buffers a cost keeps (a planner meets a few sizes again and again).
_BUFFERED_SIZES = 32


def _linear_layers(network: torch.nn.Sequential) -> tuple[list, float]:
    """``[(W, b), ...]`` (float32 numpy copies) of the 3 linear layers and the leaky slope."""
    modules = list(network)
    linears = [m for m in modules if isinstance(m, torch.nn.Linear)]
    slopes = {m.negative_slope for m in modules if isinstance(m, torch.nn.LeakyReLU)}
    if len(linears) != 3 or len(slopes) != 1 or len(modules) != 5:
        raise ValueError(
            "the numpy cost needs the network of casa_core.learning.cost_network "
            "(Linear, LeakyReLU, Linear, LeakyReLU, Linear)"
        )
    layers = [
        (m.weight.detach().float().numpy().copy(), m.bias.detach().float().numpy().copy())
        for m in linears
    ]
    return layers, float(slopes.pop())


class _Buffers:
    """Work arrays for ``n`` rows."""

    def __init__(self, n: int, n_inputs: int, hidden: int, k: int):
        def new(*shape):
            return np.empty(shape, dtype=np.float32)

        self.inputs, self.d_inputs = new(n, n_inputs), new(n, n_inputs)
        self.h1, self.a1, self.h2, self.a2 = (new(n, hidden) for _ in range(4))
        self.d_h2, self.d_h1 = new(n, hidden), new(n, hidden)
        # The last layer writes a column; the sigmoid reads it as a vector.
        self.logits_column = new(n, 1)
        self.logits, self.slopes = self.logits_column.reshape(n), new(n)
        self.cos_sin, self.distances = np.empty((n, 2)), np.empty((n, k))
        self.no_slopes = self.slopes[:0]


class NumpyStateCost:
    """``cost_scale * sigmoid(network(features(s))) - offset`` and its gradient, in numpy.

    A snapshot of the network's weights at construction: build a new one after the
    weights change. Not reentrant (it reuses its work arrays): one call at a time.

    Parameters
    ----------
    network : torch.nn.Sequential
        A network of :func:`casa_core.learning.features.cost_network`.
    objects : array_like, shape (K, 3)
        Positions of the scene objects, in feature order.
    length_scale, cost_scale : float
        As in :mod:`casa_core.learning.features`.
    offset : float
        Subtracted from every per-state cost.
    """

    def __init__(self, network, *, objects, length_scale: float, cost_scale: float, offset=0.0):
        layers, slope = _linear_layers(network)
        (self._w1, self._b1), (self._w2, self._b2), (w3, self._b3) = layers
        # Transposed once, contiguous: the forward pass multiplies by W^T.
        self._w1t, self._w2t = np.ascontiguousarray(self._w1.T), np.ascontiguousarray(self._w2.T)
        self._w3t, self._w3 = np.ascontiguousarray(w3.T), w3[0]
        self._no_bias_inputs = np.zeros(self._w1.shape[1], dtype=np.float32)
        self._no_bias_hidden = np.zeros(self._w1.shape[0], dtype=np.float32)
        # float32, as torch's leaky ReLU multiplies by it.
        self._slope = np.float32(slope)
        self.objects = np.ascontiguousarray(np.asarray(objects, dtype=float).reshape(-1, 3))
        self.length_scale = float(length_scale)
        self.cost_scale = float(cost_scale)
        self.offset = float(offset)
        self._buffers: dict[int, _Buffers] = {}

    def __getstate__(self):
        # A copy (deepcopy) gets its own, empty work arrays: they are scratch, not state.
        return {**self.__dict__, "_buffers": {}}

    def _forward(self, states: np.ndarray, *, with_slopes: bool):
        states = np.asarray(states, dtype=float)
        shape = states.shape[:-1]
        flat = np.ascontiguousarray(states.reshape(-1, 4))
        n = len(flat)
        work = self._buffers.get(n)
        if work is None:
            if len(self._buffers) >= _BUFFERED_SIZES:
                self._buffers.clear()
            work = self._buffers[n] = _Buffers(
                n, self._w1.shape[1], self._w1.shape[0], len(self.objects)
            )
        _kernels.features(
            flat,
            self.objects,
            self.length_scale,
            _BASIS,
            work.inputs,
            work.cos_sin,
            work.distances,
        )
        _kernels.linear(work.inputs, self._w1t, self._b1, work.h1)
        _kernels.leaky_relu(work.h1, self._slope, work.a1)
        _kernels.linear(work.a1, self._w2t, self._b2, work.h2)
        _kernels.leaky_relu(work.h2, self._slope, work.a2)
        _kernels.linear(work.a2, self._w3t, self._b3, work.logits_column)
        values = np.empty(n)
        slopes = work.slopes if with_slopes else work.no_slopes
        _kernels.costs(work.logits, self.cost_scale, self.offset, values, slopes)
        return values.reshape(shape), shape, flat, work

    def __call__(self, states) -> np.ndarray:
        """Per-state costs ``(...)`` of states ``(..., 4)``."""
        return self._forward(states, with_slopes=False)[0]

    def value_and_grad(self, states) -> tuple[np.ndarray, np.ndarray]:
        """Per-state costs ``(...)`` and the gradient of their sum in the states ``(..., 4)``."""
        values, shape, flat, work = self._forward(states, with_slopes=True)
        # The network's backward pass, as autograd computes it.
        _kernels.output_backward(work.slopes, self._w3, work.h2, self._slope, work.d_h2)
        _kernels.linear(work.d_h2, self._w2, self._no_bias_hidden, work.d_h1)
        _kernels.leaky_relu_backward(work.d_h1, work.h1, self._slope)
        _kernels.linear(work.d_h1, self._w1, self._no_bias_inputs, work.d_inputs)
        grad = np.empty((len(flat), 4))
        _kernels.features_backward(
            work.d_inputs,
            flat,
            self.objects,
            self.length_scale,
            _BASIS,
            work.cos_sin,
            work.distances,
            grad,
        )
        return values, grad.reshape(*shape, 4)
