"""The learned per-state cost and its gradient without autograd, for planning.

The planner evaluates a learned cost and its gradient in the states thousands of
times per learned intent, on a few hundred states at a time. For a network this
small, torch's per-operation and autograd overhead costs several times the
arithmetic; :class:`NumpyStateCost` computes the same formula
(:mod:`casa_core.learning.features`: features in float64, the network in float32,
the sigmoid in float64) and its gradient by hand (the chain rule through the
network and the features), with no autograd: the network's four matrix products in
torch, everything between them in compiled loops (:mod:`casa_core.learning._kernels`),
into work arrays kept per row count. Training the network's weights stays in torch.

The values agree with the torch formula to float32 rounding (the matrix products
may sum in another order): ``tests/learning/test_speed_equivalence.py`` checks costs and
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
    """``[(W, b), ...]`` (detached float32 copies) of the 3 linear layers and the leaky slope."""
    modules = list(network)
    linears = [m for m in modules if isinstance(m, torch.nn.Linear)]
    slopes = {m.negative_slope for m in modules if isinstance(m, torch.nn.LeakyReLU)}
    if len(linears) != 3 or len(slopes) != 1 or len(modules) != 5:
        raise ValueError(
            "the numpy cost needs the network of casa_core.learning.cost_network "
            "(Linear, LeakyReLU, Linear, LeakyReLU, Linear)"
        )
    layers = [(m.weight.detach().float().clone(), m.bias.detach().float().clone()) for m in linears]
    return layers, float(slopes.pop())


class _Buffers:
    """Work arrays for ``n`` rows: each a numpy array and, where torch writes it, a tensor."""

    def __init__(self, n: int, n_inputs: int, hidden: int, k: int):
        def pair(*shape):
            tensor = torch.empty(shape, dtype=torch.float32)
            return tensor, tensor.numpy()

        (self.inputs_t, self.inputs) = pair(n, n_inputs)
        (self.h1_t, self.h1), (self.a1_t, self.a1) = pair(n, hidden), pair(n, hidden)
        (self.h2_t, self.h2), (self.a2_t, self.a2) = pair(n, hidden), pair(n, hidden)
        (self.logits_t, self.logits), (self.slopes_t, self.slopes) = pair(n), pair(n)
        (self.d_h2_t, self.d_h2), (self.d_h1_t, self.d_h1) = pair(n, hidden), pair(n, hidden)
        (self.d_inputs_t, self.d_inputs) = pair(n, n_inputs)
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
        (self._w1, self._b1), (self._w2, self._b2), (w3, b3) = layers
        self._w3, self._b3 = w3[0].contiguous(), b3
        self._w3_np = self._w3.numpy()
        # Transposed once, contiguous: the forward pass multiplies by W^T.
        self._w1t, self._w2t = self._w1.T.contiguous(), self._w2.T.contiguous()
        # float32, as torch's leaky ReLU multiplies by it.
        self._slope = np.float32(slope)
        self.objects = np.ascontiguousarray(np.asarray(objects, dtype=float).reshape(-1, 3))
        self.length_scale = float(length_scale)
        self.cost_scale = float(cost_scale)
        self.offset = float(offset)
        self._buffers: dict[int, _Buffers] = {}

    def __getstate__(self):
        # A copy (deepcopy, pickle) gets its own work arrays: copied, a tensor and the
        # numpy view of its memory would no longer share it.
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
        # No autograd context needed: neither the weights nor the inputs require grad.
        torch.addmm(self._b1, work.inputs_t, self._w1t, out=work.h1_t)
        _kernels.leaky_relu(work.h1, self._slope, work.a1)
        torch.addmm(self._b2, work.a1_t, self._w2t, out=work.h2_t)
        _kernels.leaky_relu(work.h2, self._slope, work.a2)
        torch.addmv(self._b3, work.a2_t, self._w3, out=work.logits_t)
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
        _kernels.output_backward(work.slopes, self._w3_np, work.h2, self._slope, work.d_h2)
        torch.mm(work.d_h2_t, self._w2, out=work.d_h1_t)
        _kernels.leaky_relu_backward(work.d_h1, work.h1, self._slope)
        torch.mm(work.d_h1_t, self._w1, out=work.d_inputs_t)
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
