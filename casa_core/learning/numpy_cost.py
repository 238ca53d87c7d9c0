"""The learned per-state cost and its gradient in numpy, for planning.

The planner evaluates a learned cost and its gradient in the states thousands of
times per learned intent, on a few hundred states at a time. For a network this
small, torch's per-operation and autograd overhead costs several times the
arithmetic; :class:`NumpyStateCost` computes the same formula
(:mod:`casa_core.learning.features`: features in float64, the network in float32,
the sigmoid in float64) and its gradient by hand (the chain rule through the
network and the features), with no autograd. Training the network's weights stays in
torch.

The values agree with the torch formula to float32 rounding (the matrix products
may sum in another order): ``tests/test_irl.py`` checks costs and gradients against
torch's autograd.

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

from casa_core.rotation import R0

# R(rot) = cos(rot) A + sin(rot) B + C, row-major (casa_core.rotation.end_effector_rotation).
_ZERO = np.zeros(3)
_A = np.stack([R0[:, 0], R0[:, 1], _ZERO], axis=-1).reshape(9)
_B = np.stack([R0[:, 1], -R0[:, 0], _ZERO], axis=-1).reshape(9)
_C = np.stack([_ZERO, _ZERO, R0[:, 2]], axis=-1).reshape(9)


_leaky_relu = torch.nn.functional.leaky_relu
_leaky_relu_backward = torch.ops.aten.leaky_relu_backward


def _linear_layers(network: torch.nn.Module) -> tuple[list, float]:
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


class NumpyStateCost:
    """``cost_scale * sigmoid(network(features(s))) - offset`` and its gradient, in numpy.

    A snapshot of the network's weights at construction: build a new one after the
    weights change.

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
        layers, self._slope = _linear_layers(network)
        (self._w1, self._b1), (self._w2, self._b2), (w3, b3) = layers
        self._w3, self._b3 = w3[0].contiguous(), b3
        # Transposed once, contiguous: the forward pass multiplies by W^T.
        self._w1t, self._w2t = self._w1.T.contiguous(), self._w2.T.contiguous()
        self.objects = np.asarray(objects, dtype=float).reshape(-1, 3)
        self.length_scale = float(length_scale)
        k = len(self.objects)
        # d features / d position of the linear features (position, then each offset).
        self._linear_jacobian = np.vstack([np.eye(3)] + [-np.eye(3)] * k) / self.length_scale
        self._distance_columns = slice(12 + 3 * k, 12 + 4 * k)
        self._rotation_basis = np.column_stack([_A, _B])
        self.cost_scale = float(cost_scale)
        self.offset = float(offset)

    def _forward(self, states: np.ndarray):
        states = np.asarray(states, dtype=float)
        shape = states.shape[:-1]
        flat = states.reshape(-1, 4)
        n, k = len(flat), len(self.objects)
        cos, sin = np.cos(flat[:, 3:4]), np.sin(flat[:, 3:4])
        offsets = self.objects[None, :, :] - flat[:, None, :3]  # (n, K, 3), feature order
        dx, dy, dz = offsets[..., 0], offsets[..., 1], offsets[..., 2]
        distances = np.sqrt(dx * dx + dy * dy + dz * dz + 1e-6)
        inputs = np.empty((n, 12 + 4 * k), dtype=np.float32)
        inputs[:, :9] = cos * _A + sin * _B + _C
        lengths = np.concatenate([flat[:, :3], offsets.reshape(n, 3 * k), distances], axis=1)
        with np.errstate(over="ignore"):  # beyond float32's range: inf, as torch casts it
            inputs[:, 9:] = lengths / self.length_scale
        # No autograd context needed: neither the weights nor the inputs require grad.
        h1 = torch.addmm(self._b1, torch.from_numpy(inputs), self._w1t)
        h2 = torch.addmm(self._b2, _leaky_relu(h1, self._slope), self._w2t)
        logits = torch.addmv(self._b3, _leaky_relu(h2, self._slope), self._w3).numpy()
        sigmoid = 1.0 / (1.0 + np.exp(-logits.astype(np.float64)))
        values = (self.cost_scale * sigmoid - self.offset).reshape(shape)
        cache = (shape, cos, sin, flat[:, :3], distances, h1, h2, sigmoid)
        return values, cache

    def __call__(self, states) -> np.ndarray:
        """Per-state costs ``(...)`` of states ``(..., 4)``."""
        return self._forward(states)[0]

    def value_and_grad(self, states) -> tuple[np.ndarray, np.ndarray]:
        """Per-state costs ``(...)`` and the gradient of their sum in the states ``(..., 4)``."""
        values, (shape, cos, sin, position, distances, h1, h2, sigmoid) = self._forward(states)
        slope_of_sigmoid = self.cost_scale * sigmoid * (1.0 - sigmoid)
        d_logits = torch.from_numpy(slope_of_sigmoid.astype(np.float32))
        # The network's backward pass, as autograd computes it.
        d_h2 = _leaky_relu_backward(torch.outer(d_logits, self._w3), h2, self._slope, False)
        d_h1 = _leaky_relu_backward(d_h2.mm(self._w2), h1, self._slope, False)
        d_inputs = d_h1.mm(self._w1).numpy().astype(np.float64)
        # The features' gradient as products with constant matrices (few numpy calls).
        along = d_inputs[:, self._distance_columns] / (self.length_scale * distances)
        grad = np.empty((len(d_inputs), 4))
        # Position: its own columns and the offsets' (linear), then the distances'.
        grad[:, :3] = d_inputs[:, 9 : self._distance_columns.start] @ self._linear_jacobian
        grad[:, :3] -= along @ self.objects - position * along.sum(axis=1, keepdims=True)
        turned = d_inputs[:, :9] @ self._rotation_basis  # (d R . A, d R . B)
        grad[:, 3] = cos[:, 0] * turned[:, 1] - sin[:, 0] * turned[:, 0]
        return values, grad.reshape(*shape, 4)
