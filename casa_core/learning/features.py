"""The learned cost's inputs and network, and its per-state formula (paper, Sec. II-E).

A learned intent's per-state cost is

    C_phi(s) = cost_scale * sigmoid(f_phi(x(s))),

with x(s) the features of state ``s = [x, y, z, rot]`` (:func:`state_features`) and
f_phi a network of 2 hidden layers of leaky-ReLU units (:func:`cost_network`). The
sigmoid bounds the cost to [0, cost_scale]. A learned intent subtracts its constant
``cost_offset`` from it (:class:`~casa_core.learning.NeuralIntent`).

:func:`bounded_cost` on :func:`cost_logits` is the definition of the formula, offset
included: training and :meth:`NeuralIntent.state_cost
<casa_core.learning.NeuralIntent.state_cost>` call it. The planner runs a compiled
copy for speed (:class:`~casa_core.learning.numpy_cost.NumpyStateCost`, whose loops are
:func:`casa_core.learning._kernels.cost`); ``tests/learning/test_speed_equivalence.py``
checks that copy against this definition on the same states, values and gradients, to
float32 rounding of the network's sums.

Input features, in this order (:func:`feature_names`):
    1. end-effector rotation matrix R(rot), row-major (9;
       :func:`casa_core.planning.rotation.end_effector_rotation`);
    2. end-effector position x, y, z (3);
    3. for each scene object, its position minus the end effector's (3 each);
    4. for each object, its distance to the end effector (1 each): a function of
       the above that the network would otherwise have to learn from a few
       demonstrations (with it, a goal is one unit away).
    Lengths are divided by ``length_scale`` so the network sees numbers of order one.

Examples
--------
>>> import torch
>>> network = cost_network(len(feature_names(["red"])), hidden=8, negative_slope=0.01, seed=0)
>>> states = torch.tensor([[[0.4, 0.1, 0.2, 0.0]]], dtype=torch.float64)
>>> objects = torch.tensor([[0.4, 0.22, 0.12]], dtype=torch.float64)
>>> logits = cost_logits(network, states, objects=objects, length_scale=0.1)
>>> cost = bounded_cost(logits, 10.0)
>>> cost.shape, bool(0.0 <= cost.item() <= 10.0)
(torch.Size([1, 1]), True)
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import torch

from casa_core import portable_math
from casa_core.learning.network import network_output
from casa_core.planning.rotation import end_effector_rotation


def feature_names(object_names) -> list[str]:
    """Names of the network's inputs, in order (stored with a learned intent).

    Examples
    --------
    >>> feature_names(["red"])[9:]
    ['x', 'y', 'z', 'red_dx', 'red_dy', 'red_dz', 'red_distance']
    """
    names = [f"R{i}{j}" for i in range(3) for j in range(3)] + ["x", "y", "z"]
    for obj in object_names:
        names += [f"{obj}_dx", f"{obj}_dy", f"{obj}_dz"]
    return names + [f"{obj}_distance" for obj in object_names]


def state_features(states: torch.Tensor, objects: torch.Tensor, *, length_scale: float):
    """Network inputs ``(..., 12 + 4K)`` (float32) of states ``(..., 4)`` given objects ``(K, 3)``.

    Examples
    --------
    >>> import torch
    >>> states = torch.tensor([[0.4, 0.1, 0.2, 0.0]], dtype=torch.float64)
    >>> objects = torch.tensor([[0.4, 0.1, 0.3]], dtype=torch.float64)
    >>> state_features(states, objects, length_scale=0.1)[0, 9:].tolist()  # x y z, offset, distance
    [4.0, 1.0, 2.0, 0.0, 0.0, 1.0, 1.0000499486923218]
    """
    position = states[..., :3]
    rotation = end_effector_rotation(states[..., 3]).flatten(start_dim=-2)
    offsets = objects - position[..., None, :]
    # Rounded at 1 mm so that the gradient exists on the object itself.
    distances = portable_math.sqrt((offsets * offsets).sum(dim=-1) + 1e-6)
    inputs = [position, offsets.flatten(start_dim=-2), distances]
    # float32 halves the network's time; the planner keeps states in float64.
    return torch.cat([rotation] + [x / length_scale for x in inputs], dim=-1).float()


def cost_network(n_inputs: int, *, hidden: int, negative_slope: float, seed: int):
    """The 2-hidden-layer leaky-ReLU network (float32), initialised from ``seed``.

    Examples
    --------
    >>> a, b = (cost_network(4, hidden=8, negative_slope=0.01, seed=1) for _ in range(2))
    >>> all(torch.equal(x, y) for x, y in zip(a.parameters(), b.parameters()))
    True
    """
    generator = torch.Generator().manual_seed(int(seed))
    layers = [
        torch.nn.Linear(n_inputs, hidden, dtype=torch.float32),
        torch.nn.LeakyReLU(negative_slope),
        torch.nn.Linear(hidden, hidden, dtype=torch.float32),
        torch.nn.LeakyReLU(negative_slope),
        torch.nn.Linear(hidden, 1, dtype=torch.float32),
    ]
    with torch.no_grad():
        for layer in layers:
            if isinstance(layer, torch.nn.Linear):
                # PyTorch's default initialisation, U(-1/sqrt(fan_in), 1/sqrt(fan_in)),
                # drawn from our generator instead of the global one.
                bound = 1.0 / math.sqrt(layer.in_features)
                layer.weight.uniform_(-bound, bound, generator=generator)
                layer.bias.uniform_(-bound, bound, generator=generator)
    return torch.nn.Sequential(*layers)


def cost_logits(network, states: torch.Tensor, *, objects: torch.Tensor, length_scale: float):
    """The network's output f_phi(x(s)) ``(...)`` (float64) at states ``(..., 4)``.

    The network runs with its products in a fixed order (:mod:`casa_core.learning.network`).
    """
    inputs = state_features(states, objects, length_scale=length_scale)
    return network_output(network, inputs)[..., 0].double()


def bounded_cost(
    logits: torch.Tensor,
    cost_scale: float,
    *,
    offset: float = 0.0,
    mean_trajectory: bool = False,
):
    """The per-state cost ``cost_scale * sigmoid(logits) - offset``.

    Without ``offset`` it lies in [0, cost_scale]. With ``mean_trajectory``,
    ``logits`` are ``(B, n)`` (B trajectories of n states) and the result is the
    trajectories' mean cost (the per-state costs summed along each, averaged over B),
    the scale applied last as in training, which cannot see a constant offset (every
    trajectory has n states): no ``offset`` then.

    Examples
    --------
    >>> import torch
    >>> bounded_cost(torch.zeros(2, 3, dtype=torch.float64), 4.0).tolist()
    [[2.0, 2.0, 2.0], [2.0, 2.0, 2.0]]
    >>> bounded_cost(torch.zeros(2, 3, dtype=torch.float64), 4.0, mean_trajectory=True).item()
    6.0
    >>> bounded_cost(torch.zeros(1, 2, dtype=torch.float64), 4.0, offset=0.5).tolist()
    [[1.5, 1.5]]
    """
    if mean_trajectory:
        if offset:
            raise ValueError("the mean trajectory cost of training has no offset")
        return cost_scale * torch.sigmoid(logits).sum(dim=1).mean()
    return cost_scale * torch.sigmoid(logits) - offset


def object_positions(objects: Mapping) -> tuple[list[str], np.ndarray]:
    """Names and positions ``(K, 3)`` of named scene objects (name -> 3 finite numbers).

    Examples
    --------
    >>> names, positions = object_positions({"red": (0.4, 0.22, 0.12)})
    >>> names, positions.shape
    (['red'], (1, 3))
    """
    if not isinstance(objects, Mapping):
        raise ValueError(
            f"objects must map names to positions (x, y, z), got {type(objects).__name__}"
        )
    names, positions = [], []
    for name, value in objects.items():
        position = np.asarray(value, dtype=float)
        if position.shape != (3,) or not np.isfinite(position).all():
            raise ValueError(f"object {name!r} must be 3 finite numbers (x, y, z), got {value!r}")
        names.append(str(name))
        positions.append(position)
    return names, np.array(positions).reshape(-1, 3)
