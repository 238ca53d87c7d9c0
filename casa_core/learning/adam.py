"""Adam for the IRL network, written out.

The same update as ``torch.optim.Adam`` on the CPU (its single-tensor form, with
L2 weight decay added to the gradient), to the bit, with one exception: the square
root of the second moment comes from :mod:`casa_core.portable_math`, because torch's
own depends on the processor. ``tests/learning/test_speed_equivalence.py`` checks the
weights after 60 steps against torch's given the same square root. Written out because constructing
``torch.optim.Adam`` imports ``torch._dynamo``, which costs about 1.7 CPU-seconds
once per process, as much as learning an intent itself.
"""

from __future__ import annotations

import torch

from casa_core import portable_math


class Adam:
    """Adam (Kingma and Ba 2015) with L2 weight decay, as ``torch.optim.Adam``.

    Parameters
    ----------
    params : iterable of torch.Tensor
        The parameters to optimize (their ``.grad`` is read by :meth:`step`).
    lr, weight_decay : float
        Step size and the L2 weight added to the gradient.
    betas : (float, float)
        Decay rates of the first and second moments.
    eps : float
        Added to the denominator.

    Examples
    --------
    >>> weight = torch.tensor([1.0, -2.0], requires_grad=True)
    >>> adam = Adam([weight], lr=0.1, weight_decay=0.0)
    >>> (weight**2).sum().backward()
    >>> adam.step()
    >>> [round(w, 6) for w in weight.detach().tolist()]  # lr against the gradient's sign
    [0.9, -1.9]
    """

    def __init__(self, params, *, lr: float, weight_decay: float, betas=(0.9, 0.999), eps=1e-8):
        self.params = list(params)
        self.lr, self.weight_decay = float(lr), float(weight_decay)
        self.betas, self.eps = (float(betas[0]), float(betas[1])), float(eps)
        self.steps = 0
        self._moments = [(torch.zeros_like(p), torch.zeros_like(p)) for p in self.params]

    def zero_grad(self) -> None:
        """Forget the gradients (set them to None, as torch's default)."""
        for param in self.params:
            param.grad = None

    def step(self) -> None:
        """One Adam update of every parameter with a gradient."""
        beta1, beta2 = self.betas
        self.steps += 1
        # torch counts steps in a float32 tensor and reads them back as a float.
        step = float(torch.tensor(float(self.steps), dtype=torch.float32).item())
        step_size = self.lr / (1 - beta1**step)
        correction2_sqrt = (1 - beta2**step) ** 0.5
        with torch.no_grad():
            for param, (mean, square) in zip(self.params, self._moments, strict=True):
                if param.grad is None:
                    continue
                grad = param.grad
                if self.weight_decay != 0:
                    grad = grad.add(param, alpha=self.weight_decay)
                mean.lerp_(grad, 1 - beta1)
                square.mul_(beta2).addcmul_(grad, grad, value=1 - beta2)
                denominator = (portable_math.sqrt(square) / correction2_sqrt).add_(self.eps)
                param.addcdiv_(mean, denominator, value=-step_size)
