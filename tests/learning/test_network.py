"""The fixed-order network (casa_core.learning.network) against torch's own layers.

References: torch's ``nn.Linear`` and autograd on the same float32 network (MKL sums in
another order, so they agree to float32 rounding), and a plain loop on float32 scalars
(tests/learning/test_speed_equivalence.py's ``python_linear``), which the forward pass
must equal bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from casa_core.learning import cost_network
from casa_core.learning.network import network_output
from tests.learning.test_speed_equivalence import FLOAT32_GRADIENT, python_linear


def leaky(h, slope):
    return np.where(h > 0, h, h * np.float32(slope)).astype(np.float32)


def test_forward_equals_a_plain_loop_bit_for_bit():
    net = cost_network(5, hidden=8, negative_slope=0.01, seed=2)
    x = torch.from_numpy(np.random.default_rng(0).normal(size=(7, 5)).astype(np.float32))
    (w1, b1), (w2, b2), (w3, b3) = (
        (m.weight.detach().numpy().T, m.bias.detach().numpy())
        for m in net
        if isinstance(m, torch.nn.Linear)
    )
    h = leaky(python_linear(x.numpy(), w1, b1), 0.01)
    h = leaky(python_linear(h, w2, b2), 0.01)
    want = python_linear(h, w3, b3)
    np.testing.assert_array_equal(network_output(net, x).detach().numpy(), want)


@pytest.mark.parametrize("shape", [(150, 32), (5, 30, 32), (1, 32)])
def test_values_and_gradients_equal_torch_autograd(shape):
    net = cost_network(32, hidden=64, negative_slope=0.01, seed=1)
    data = np.random.default_rng(len(shape)).normal(size=shape).astype(np.float32)
    got_x, want_x = (torch.tensor(data, requires_grad=True) for _ in range(2))

    got = network_output(net, got_x)
    # A smooth function of every output, so every gradient entry is exercised.
    (got**2).sum().backward()
    got_grads = [p.grad.clone() for p in net.parameters()]
    net.zero_grad()
    want = net(want_x)
    (want**2).sum().backward()

    assert got.shape == want.shape
    np.testing.assert_allclose(got.detach(), want.detach(), rtol=FLOAT32_GRADIENT, atol=1e-6)
    np.testing.assert_allclose(got_x.grad, want_x.grad, rtol=FLOAT32_GRADIENT, atol=1e-5)
    for got_grad, param in zip(got_grads, net.parameters(), strict=True):
        np.testing.assert_allclose(got_grad, param.grad, rtol=FLOAT32_GRADIENT, atol=1e-4)


def test_a_network_of_other_layers_is_refused():
    net = torch.nn.Sequential(torch.nn.Linear(3, 2), torch.nn.Tanh())
    with pytest.raises(ValueError, match="Linear and LeakyReLU layers only, not Tanh"):
        network_output(net, torch.ones(1, 3))
