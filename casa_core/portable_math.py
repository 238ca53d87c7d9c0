"""sin, cos, exp and sqrt of torch tensors, the same on every x86-64 CPU, with their gradients.

torch computes these (and acos, asin, atan, erf, log, tan, tanh, trunc and a few more)
of a CPU tensor with Intel MKL's vector maths, VML, which picks its code path by the
processor's vendor and model, past the switches of :mod:`casa_core.numerics`: a last
bit then differs between an Intel and an AMD machine. Here numpy computes the values,
on the code path :mod:`casa_core.numerics` caps at the baseline, and the backward pass
builds the derivative from values computed in the forward pass (``d sin = cos``, ``d exp
= exp``, ``d sqrt = 1 / (2 sqrt)``), so neither pass reaches VML. Each takes and returns
a CPU tensor of any shape and floating dtype; the gradient is first-order only.

Examples
--------
>>> import torch
>>> x = torch.tensor([0.0, 0.5], dtype=torch.float64, requires_grad=True)
>>> y = sin(x).sum()
>>> y.backward()
>>> bool(torch.equal(x.grad, cos(x.detach())))
True
>>> sqrt(torch.tensor([4.0, 9.0], dtype=torch.float64)).tolist()
[2.0, 3.0]
"""

from __future__ import annotations

import numpy as np
import torch
from torch.autograd.function import once_differentiable


def _tensor(values) -> torch.Tensor:
    # numpy returns a scalar, not an array, for a 0-d input.
    return torch.from_numpy(np.asarray(values))


class _Sin(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        values = x.detach().numpy()
        ctx.save_for_backward(_tensor(np.cos(values)))
        return _tensor(np.sin(values))

    @staticmethod
    @once_differentiable
    def backward(ctx, grad):
        (derivative,) = ctx.saved_tensors
        return grad * derivative


class _Cos(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        values = x.detach().numpy()
        ctx.save_for_backward(_tensor(-np.sin(values)))
        return _tensor(np.cos(values))

    @staticmethod
    @once_differentiable
    def backward(ctx, grad):
        (derivative,) = ctx.saved_tensors
        return grad * derivative


class _Exp(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        result = _tensor(np.exp(x.detach().numpy()))
        ctx.save_for_backward(result)
        return result

    @staticmethod
    @once_differentiable
    def backward(ctx, grad):
        (result,) = ctx.saved_tensors
        return grad * result


class _Sqrt(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        result = _tensor(np.sqrt(x.detach().numpy()))
        ctx.save_for_backward(result)
        return result

    @staticmethod
    @once_differentiable
    def backward(ctx, grad):
        (result,) = ctx.saved_tensors
        # torch's own formula for the derivative of sqrt.
        return grad / (2 * result)


def sin(x: torch.Tensor) -> torch.Tensor:
    """``torch.sin(x)`` computed by numpy; differentiable."""
    return _Sin.apply(x)


def cos(x: torch.Tensor) -> torch.Tensor:
    """``torch.cos(x)`` computed by numpy; differentiable."""
    return _Cos.apply(x)


def exp(x: torch.Tensor) -> torch.Tensor:
    """``torch.exp(x)`` computed by numpy; differentiable."""
    return _Exp.apply(x)


def sqrt(x: torch.Tensor) -> torch.Tensor:
    """``torch.sqrt(x)`` computed by numpy; differentiable where ``x > 0``."""
    return _Sqrt.apply(x)


__all__ = ["cos", "exp", "sin", "sqrt"]
