"""The learned per-state cost and its gradient without autograd, for planning.

The planner evaluates a learned cost and its gradient in the states thousands of
times per learned intent, on a few hundred states at a time. For a network this
small, torch's per-operation and autograd overhead costs several times the
arithmetic; :class:`NumpyStateCost` is a copy, for speed, of the formula whose
definition is :func:`casa_core.learning.features.bounded_cost` on
:func:`~casa_core.learning.features.cost_logits` (features in float64, the network in
float32, the sigmoid in float64, the offset subtracted last), with its gradient by
hand (the chain rule through the network and the features), with no autograd and no
BLAS: all of it in compiled loops of a fixed order (:mod:`casa_core.learning._kernels`),
into work arrays kept per row count, so the planner's results do not depend on the
processor's BLAS kernel. Training
the network's weights stays in torch (:mod:`casa_core.learning.network`: the same
products, with autograd).

The values agree with the definition to float32 rounding (the matrix products sum in
another order): ``tests/learning/test_speed_equivalence.py`` checks costs and gradients
against it and torch's autograd on the same states, and a learned intent's
:attr:`~casa_core.learning.NeuralIntent.planning_cost` against its
:meth:`~casa_core.learning.NeuralIntent.state_cost`, offset included.

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


def _work_arrays(n: int, n_inputs: int, hidden: int, k: int) -> _kernels.Work:
    """The work arrays of ``n`` rows (:class:`_kernels.Work`)."""

    def new(*shape):
        return np.empty(shape, dtype=np.float32)

    return _kernels.Work(
        inputs=new(n, n_inputs),
        cos_sin=np.empty((n, 2)),
        distances=np.empty((n, k)),
        h1=new(n, hidden),
        a1=new(n, hidden),
        h2=new(n, hidden),
        a2=new(n, hidden),
        logits=new(n, 1),
        slopes=new(n),
        d_h2=new(n, hidden),
        d_h1=new(n, hidden),
        d_inputs=new(n, n_inputs),
    )


class NumpyStateCost:
    """:func:`~casa_core.learning.features.bounded_cost` with ``offset`` and its gradient.

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
        Subtracted from every per-state cost (a learned intent's ``cost_offset``).
    """

    def __init__(self, network, *, objects, length_scale: float, cost_scale: float, offset=0.0):
        layers, slope = _linear_layers(network)
        (w1, b1), (w2, b2), (w3, b3) = layers
        # The forward pass multiplies by W^T, the backward pass by W (contiguous copies).
        contiguous = np.ascontiguousarray
        self._layers = _kernels.Layers(
            w1_t=contiguous(w1.T),
            b1=contiguous(b1),
            w2_t=contiguous(w2.T),
            b2=contiguous(b2),
            w3_t=contiguous(w3.T),
            b3=contiguous(b3),
            w2=contiguous(w2),
            w1=contiguous(w1),
            w3=contiguous(w3[0]),
            no_hidden_bias=np.zeros(w1.shape[0], dtype=np.float32),
            no_input_bias=np.zeros(w1.shape[1], dtype=np.float32),
        )
        self._shape = (w1.shape[1], w1.shape[0])  # inputs, hidden units
        # float32, as torch's leaky ReLU multiplies by it.
        self._slope = np.float32(slope)
        self.objects = np.ascontiguousarray(np.asarray(objects, dtype=float).reshape(-1, 3))
        self.length_scale = float(length_scale)
        self.cost_scale = float(cost_scale)
        self.offset = float(offset)
        self._buffers: dict[int, _kernels.Work] = {}

    def __getstate__(self):
        # A copy (deepcopy) gets its own, empty work arrays: they are scratch, not state.
        return {**self.__dict__, "_buffers": {}}

    def _work(self, states) -> tuple[np.ndarray, tuple, _kernels.Work]:
        """The flat states ``(n, 4)``, their leading shape and the work arrays of ``n`` rows."""
        states = np.asarray(states, dtype=float)
        flat = np.ascontiguousarray(states.reshape(-1, 4))
        n = len(flat)
        work = self._buffers.get(n)
        if work is None:
            if len(self._buffers) >= _BUFFERED_SIZES:
                self._buffers.clear()
            work = self._buffers[n] = _work_arrays(n, *self._shape, len(self.objects))
        return flat, states.shape[:-1], work

    def _model(
        self,
    ) -> tuple[np.ndarray, float, np.ndarray, _kernels.Layers, np.float32, float, float]:
        """The kernels' arguments that describe the cost: objects, features and network."""
        return (
            self.objects,
            self.length_scale,
            _BASIS,
            self._layers,
            self._slope,
            self.cost_scale,
            self.offset,
        )

    def __call__(self, states) -> np.ndarray:
        """Per-state costs ``(...)`` of states ``(..., 4)``."""
        flat, shape, work = self._work(states)
        values = np.empty(len(flat))
        _kernels.cost(flat, *self._model(), work, values)
        return values.reshape(shape)

    def value_and_grad(self, states) -> tuple[np.ndarray, np.ndarray]:
        """Per-state costs ``(...)`` and the gradient of their sum in the states ``(..., 4)``."""
        flat, shape, work = self._work(states)
        values, grad = np.empty(len(flat)), np.empty((len(flat), 4))
        _kernels.cost_and_gradient(flat, *self._model(), work, values, grad)
        return values.reshape(shape), grad.reshape(*shape, 4)
