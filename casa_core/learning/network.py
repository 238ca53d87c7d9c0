"""The learned cost's network run in torch with its matrix products in a fixed order.

``torch.nn.Linear`` calls MKL, whose sums' order depends on the processor and on
``MKL_CBWR``. :func:`network_output` runs each linear layer through
:func:`casa_core.learning._kernels.linear` instead, forward and backward (the
gradients in the inputs, the weights and the biases, each sum in the order of its
terms), so that training the network and every torch evaluation of a learned cost give
the same bits on every processor, with the products of the planner's
:class:`~casa_core.learning.numpy_cost.NumpyStateCost`. Autograd sees an ordinary
function of the layers' parameters.

Examples
--------
>>> import torch
>>> from casa_core.learning.features import cost_network
>>> net = cost_network(4, hidden=8, negative_slope=0.01, seed=0)
>>> x = torch.ones(3, 4)
>>> bool(torch.allclose(network_output(net, x), net(x), rtol=1e-6, atol=1e-7))
True
"""

from __future__ import annotations

import numpy as np
import torch

from casa_core.learning import _kernels


def _rows(tensor: torch.Tensor) -> np.ndarray:
    """A float32 tensor ``(..., m)`` as a C-contiguous numpy ``(n, m)``."""
    return np.ascontiguousarray(tensor.detach().reshape(-1, tensor.shape[-1]).numpy())


def _product(x: np.ndarray, w: np.ndarray, bias=None) -> np.ndarray:
    """``bias + x @ w`` (no bias: zeros) in :func:`_kernels.linear`'s order."""
    if bias is None:
        bias = np.zeros(w.shape[1], dtype=np.float32)
    out = np.empty((x.shape[0], w.shape[1]), dtype=np.float32)
    _kernels.linear(x, np.ascontiguousarray(w), bias, out)
    return out


class _FixedOrderLinear(torch.autograd.Function):
    """``x @ weight.T + bias`` of float32 tensors, in both directions off the BLAS."""

    @staticmethod
    def forward(ctx, x, weight, bias):
        ctx.save_for_backward(x, weight)
        w = weight.detach().numpy()
        out = _product(_rows(x), w.T, bias.detach().numpy())
        return torch.from_numpy(out).reshape(*x.shape[:-1], w.shape[0])

    @staticmethod
    def backward(ctx, grad_out):
        x, weight = ctx.saved_tensors
        g = _rows(grad_out)
        grad_x = grad_weight = grad_bias = None
        if ctx.needs_input_grad[0]:
            grad_x = torch.from_numpy(_product(g, weight.detach().numpy())).reshape(x.shape)
        if ctx.needs_input_grad[1]:
            # Each weight's gradient sums over the rows in their order.
            grad_weight = torch.from_numpy(_product(np.ascontiguousarray(g.T), _rows(x)))
        if ctx.needs_input_grad[2]:
            ones = np.ones((1, g.shape[0]), dtype=np.float32)
            grad_bias = torch.from_numpy(_product(ones, g)[0])
        return grad_x, grad_weight, grad_bias


def network_output(network: torch.nn.Sequential, inputs: torch.Tensor) -> torch.Tensor:
    """``network(inputs)`` (float32) for a network of Linear and LeakyReLU layers."""
    x = inputs
    for module in network:
        if isinstance(module, torch.nn.Linear):
            x = _FixedOrderLinear.apply(x, module.weight, module.bias)
        elif isinstance(module, torch.nn.LeakyReLU):
            x = torch.nn.functional.leaky_relu(x, module.negative_slope)
        else:
            raise ValueError(
                f"the learned cost's network has Linear and LeakyReLU layers only, "
                f"not {type(module).__name__}"
            )
    return x


def network_shape(network: torch.nn.Module) -> dict:
    """``inputs``, ``hidden`` (units of the first layer) and ``negative_slope`` of a
    network of :func:`~casa_core.learning.features.cost_network`'s form, read from it."""
    layers = list(network.children())
    first = layers[0] if layers else None
    slopes = {m.negative_slope for m in layers if isinstance(m, torch.nn.LeakyReLU)}
    if not isinstance(first, torch.nn.Linear) or len(slopes) != 1:
        raise ValueError("a learned cost's network starts with a Linear layer, one leaky slope")
    return {
        "inputs": first.in_features,
        "hidden": first.out_features,
        "negative_slope": slopes.pop(),
    }
