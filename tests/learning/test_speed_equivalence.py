"""The fast paths compute what the plain ones compute (speed work must not change results).

Each fast path is checked against the plain computation it replaces: the numpy learned
cost and its hand-written gradient against the definition
(:func:`casa_core.learning.features.bounded_cost`, offset included) and torch's autograd
on the same network, a learned intent's planning cost against its state cost, the
written-out Adam against ``torch.optim.Adam``, the compiled walk and optimizer step
against a walk on Python floats and the array formulas,
the vector length against ``numpy.linalg.norm``, and plans with the numpy cost against
plans with the torch cost.
"""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np
import pytest
import torch

from casa_core import portable_math
from casa_core.learning import NeuralIntent, cost_network, feature_names
from casa_core.learning import _kernels as learning_kernels
from casa_core.learning.adam import Adam
from casa_core.learning.features import bounded_cost, cost_logits
from casa_core.learning.numpy_cost import NumpyStateCost
from casa_core.planning import PlannerConfig, _kernels, optimize
from casa_core.planning.optimizer import feasible
from casa_core.scene import load_scene
from casa_core.study.learning_evidence import scene_objects

OBJECTS = scene_objects(load_scene())
POSITIONS = np.array(list(OBJECTS.values()))


def network(hidden=32, seed=3):
    return cost_network(len(feature_names(OBJECTS)), hidden=hidden, negative_slope=0.01, seed=seed)


#: Relative agreement of two float32 evaluations of the network whose matrix products
#: add their terms in different orders (test_numpy_cost_and_gradient_equal_torch_autograd).
FLOAT32_SUMS = 1e-6
#: The same in the cost's tail, per unit of cost_scale: a logit of magnitude L is rounded
#: to L * 6e-8, and the cost, cost_scale * sigmoid(logit), moves by that much relative
#: to cost_scale * sigmoid * (1 - sigmoid), which is tiny there; absolute, it stays below
#: cost_scale * 1e-6.
FLOAT32_TAIL = 1e-6
#: The same for the gradients, whose entries are of order 1 to 10.
FLOAT32_GRADIENT = 1e-5


def random_states(rng, shape=(5, 30)):
    """States around the workspace with rot over two turns, as planning meets them."""
    position = rng.uniform([0.2, -0.4, 0.05], [0.7, 0.4, 0.5], size=(*shape, 3))
    return np.concatenate([position, rng.uniform(-6.0, 6.0, size=(*shape, 1))], axis=-1)


def torch_cost_and_grad(net, states, cost_scale, offset):
    x = torch.from_numpy(states).requires_grad_(True)
    objects = torch.from_numpy(POSITIONS)
    logits = cost_logits(net, x, objects=objects, length_scale=0.1)
    values = bounded_cost(logits, cost_scale, offset=offset)
    (grad,) = torch.autograd.grad(values.sum(), x)
    return values.detach().numpy(), grad.numpy()


@pytest.mark.parametrize(
    ("hidden", "seed", "shape"),
    # The IRL batch (5 demonstrations x 30 states, 128 units), a learned intent's cold
    # plan (a few guides), one warm-started row, and a flat list of states.
    [(128, 0, (5, 30)), (32, 3, (3, 17)), (64, 1, (1, 1)), (32, 2, (7,))],
)
def test_numpy_cost_and_gradient_equal_torch_autograd(hidden, seed, shape):
    # The same float32 network, but the fast cost sums each product's terms in its own
    # fixed order and torch (MKL) in another: the values agree to float32 rounding of
    # the network's sums, 1e-6 relative (about 8 float32 ulp; measured up to 1.4e-7).
    rtol, atol = FLOAT32_SUMS, 0.0
    rng = np.random.default_rng(seed)
    net = network(hidden, seed)
    states = random_states(rng, shape)
    fast = NumpyStateCost(net, objects=POSITIONS, length_scale=0.1, cost_scale=56.75, offset=1.5)
    values, grad = fast.value_and_grad(states)
    want_values, want_grad = torch_cost_and_grad(net, states, 56.75, 1.5)
    assert values.shape == shape and grad.shape == (*shape, 4)
    np.testing.assert_allclose(values, want_values, rtol=rtol, atol=atol)
    # The gradient goes back through the same sums: to float32 rounding of entries of
    # order 1 to 10 (measured up to 1.7e-6).
    np.testing.assert_allclose(grad, want_grad, rtol=FLOAT32_GRADIENT, atol=FLOAT32_GRADIENT)
    np.testing.assert_array_equal(fast(states), values)


def test_numpy_cost_gradient_on_an_object_and_far_away():
    # On an object the distance is sqrt(1e-6) (features.state_features' rounding), where
    # the gradient exists; far away the inputs are large. rot 0 and a full turn. Among
    # planning states, as a batch the size of a plan (torch's products sum as for it).
    net = network(32, 5)
    states = random_states(np.random.default_rng(5), (1, 30))
    states[0, :3] = [[*POSITIONS[0], 0.0], [*POSITIONS[-1], -np.pi], [50.0, -40.0, 30.0, 2 * np.pi]]
    fast = NumpyStateCost(net, objects=POSITIONS, length_scale=0.1, cost_scale=10.0)
    values, grad = fast.value_and_grad(states)
    want_values, want_grad = torch_cost_and_grad(net, states, 10.0, 0.0)
    assert np.isfinite(grad).all()
    np.testing.assert_allclose(values, want_values, rtol=FLOAT32_SUMS, atol=10.0 * FLOAT32_TAIL)
    np.testing.assert_allclose(grad, want_grad, rtol=FLOAT32_GRADIENT, atol=FLOAT32_GRADIENT)


def test_the_compiled_sigmoid_and_offset_are_bounded_cost_to_float64_rounding():
    # The same float32 logits into _kernels.costs and into the definition: torch's
    # sigmoid and the kernel's 1 / (1 + exp(-x)) are each within about an ulp of the
    # exact value (libm exp), so they agree to a few float64 ulp (4 eps relative;
    # measured 2.5); the offset's subtraction rounds once more, on the scale of
    # cost_scale (4 eps absolute per unit of cost_scale; measured 1.1). Logits across
    # the sigmoid's range, its saturated tails included.
    eps = np.finfo(float).eps
    rng = np.random.default_rng(7)
    logits = np.concatenate([rng.normal(0.0, 5.0, 2000), rng.uniform(-80.0, 80.0, 2000)])
    logits = np.append(logits, [0.0, -700.0, 700.0]).astype(np.float32)
    values, slopes = np.empty(len(logits)), np.empty(len(logits), dtype=np.float32)
    for offset, rtol, atol in ((0.0, 4 * eps, 0.0), (1.5, 0.0, 4 * eps * 56.75)):
        learning_kernels.costs(logits, 56.75, offset, values, slopes)
        want = bounded_cost(torch.from_numpy(logits).double(), 56.75, offset=offset).numpy()
        np.testing.assert_allclose(values, want, rtol=rtol, atol=atol)


def test_a_learned_intents_planning_cost_is_its_state_cost_offset_included():
    # NeuralIntent hands its one cost_offset to both: the compiled planning cost and the
    # definition agree as in test_numpy_cost_and_gradient_equal_torch_autograd (absolute
    # tolerance: the offset brings values near zero), and each is the intent's cost
    # without the offset less the offset (an offset is one rounding, of order 1e-14).
    net = network(32, 4)
    states = random_states(np.random.default_rng(4), (3, 17))

    def intent(offset):
        return NeuralIntent(
            "n", net, objects=OBJECTS, cost_scale=56.75, length_scale=0.1, cost_offset=offset
        )

    offset, plain = intent(2.25), intent(0.0)
    values, grad = offset.planning_cost.value_and_grad(states)
    x = torch.from_numpy(states).requires_grad_(True)
    want = offset.state_cost(x)
    (want_grad,) = torch.autograd.grad(want.sum(), x)
    atol = 56.75 * FLOAT32_TAIL
    np.testing.assert_allclose(values, want.detach().numpy(), rtol=FLOAT32_SUMS, atol=atol)
    np.testing.assert_allclose(grad, want_grad, rtol=FLOAT32_GRADIENT, atol=FLOAT32_GRADIENT)
    np.testing.assert_allclose(plain.planning_cost(states) - values, 2.25, rtol=1e-12)
    unoffset = plain.state_cost(torch.from_numpy(states)) - want.detach()
    np.testing.assert_allclose(unoffset.numpy(), 2.25, rtol=1e-12)


def test_numpy_cost_results_outlive_its_work_arrays():
    # The cost reuses work arrays per row count: what it returned must not change.
    fast = NumpyStateCost(network(), objects=POSITIONS, length_scale=0.1, cost_scale=10.0)
    rng = np.random.default_rng(7)
    first, second = random_states(rng), random_states(rng)
    values, grad = fast.value_and_grad(first)
    kept = values.copy(), grad.copy()
    fast.value_and_grad(second), fast(second)
    np.testing.assert_array_equal(values, kept[0])
    np.testing.assert_array_equal(grad, kept[1])
    np.testing.assert_array_equal(fast.value_and_grad(first)[1], kept[1])


def test_a_copied_numpy_cost_computes_what_the_original_does():
    # The assistant is deep-copied (casa_core.bench.suite), pickling is how a cost leaves a
    # process: each copy must compute with its own work arrays.
    fast = NumpyStateCost(network(), objects=POSITIONS, length_scale=0.1, cost_scale=10.0)
    rng = np.random.default_rng(8)
    first, second = random_states(rng), random_states(rng)
    fast.value_and_grad(first)
    for copied in (copy.deepcopy(fast), pickle.loads(pickle.dumps(fast))):
        for values, want in zip(
            copied.value_and_grad(second), fast.value_and_grad(second), strict=True
        ):
            np.testing.assert_array_equal(values, want)


def test_numpy_cost_refuses_another_network():
    with pytest.raises(ValueError, match="cost_network"):
        NumpyStateCost(
            torch.nn.Sequential(torch.nn.Linear(4, 1)),
            objects=POSITIONS,
            length_scale=0.1,
            cost_scale=1.0,
        )


def test_written_out_adam_equals_torch_adam_bit_for_bit(monkeypatch):
    # Ours takes its square root from casa_core.portable_math (torch's goes through MKL's
    # vector maths, which is not correctly rounded and depends on the CPU); with torch's
    # Adam given the same square root, every other operation must agree to the bit.
    monkeypatch.setattr(torch.Tensor, "sqrt", portable_math.sqrt)
    torch.manual_seed(0)
    inputs = torch.randn(40, len(feature_names(OBJECTS)))
    nets = [network(16, 2), network(16, 2)]
    optimizers = [
        torch.optim.Adam(nets[0].parameters(), lr=3e-3, weight_decay=1e-3),
        Adam(nets[1].parameters(), lr=3e-3, weight_decay=1e-3),
    ]
    for _ in range(60):
        for net, optimizer in zip(nets, optimizers, strict=True):
            optimizer.zero_grad()
            (net(inputs) ** 2).mean().backward()
            optimizer.step()
    for theirs, ours in zip(nets[0].parameters(), nets[1].parameters(), strict=True):
        assert torch.equal(theirs, ours)


def clip(value):
    return max(-1.0, min(1.0, value))


def python_walk(starts, targets, limit):
    """The feasibility walk on Python floats, one state at a time (the reference)."""
    out = []
    for start, row in zip(starts.tolist(), targets.tolist(), strict=True):
        previous, walked = start, []
        for target in row:
            step = [t - p for t, p in zip(target, previous, strict=True)]
            if limit == "axis":
                step = [clip(s) for s in step]
            else:
                divisor = max(
                    math.sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]), 1.0
                )
                step = [s / divisor for s in step[:3]] + [clip(step[3])]
            previous = [p + s for p, s in zip(previous, step, strict=True)]
            walked.append(previous)
        out.append(walked)
    return np.array(out)


def python_linear(x, w, bias):
    """``bias + x @ w`` on float32 scalars: each sum from the bias, k in order."""
    out = np.empty((x.shape[0], w.shape[1]), dtype=np.float32)
    for i in range(x.shape[0]):
        for j in range(w.shape[1]):
            total = bias[j]
            for k in range(w.shape[0]):
                total = np.float32(total + np.float32(x[i, k] * w[k, j]))
            out[i, j] = total
    return out


# Row counts with and without a remainder of the 4-row and 8-row blocks, inner sizes
# with and without a remainder of the 4-term blocks, widths below 8 (the narrow path)
# and above.
@pytest.mark.parametrize(
    "rows, inner, width",
    [(1, 3, 1), (2, 4, 5), (7, 9, 8), (10, 28, 17), (13, 64, 1), (19, 12, 3), (6, 5, 9)],
)
def test_blocked_linear_equals_a_plain_loop_bit_for_bit(rows, inner, width):
    rng = np.random.default_rng(rows + inner)
    x, w = (rng.normal(size=shape).astype(np.float32) for shape in [(rows, inner), (inner, width)])
    bias = rng.normal(size=width).astype(np.float32)
    out = np.full((rows, width), np.nan, dtype=np.float32)
    learning_kernels.linear(x, w, bias, out)
    np.testing.assert_array_equal(out, python_linear(x, w, bias))


@pytest.mark.parametrize("limit", ["axis", "norm"])
@pytest.mark.parametrize("rows", [1, 2, 5, 9])
def test_compiled_walk_equals_a_python_walk_bit_for_bit(rows, limit):
    rng = np.random.default_rng(rows)
    starts = rng.normal(size=(rows, 4))
    # Steps of 1.5 on average: about half of them are clipped.
    targets = np.cumsum(1.5 * rng.normal(size=(rows, 30, 4)), axis=1)
    np.testing.assert_array_equal(
        feasible(starts, targets, limit), python_walk(starts, targets, limit)
    )


def numpy_adam_step(states, grad, row_costs, m, v, best, best_cost, starts, lr, k, limit):
    """One optimizer iteration as array formulas (the reference of ``adam_step``)."""
    improved = row_costs < best_cost
    best_cost, best = np.where(improved, row_costs, best_cost), best.copy()
    best[improved] = states[improved]
    squared = grad * grad
    if limit == "norm":
        squared[..., :3] = squared[..., :3].mean(axis=-1, keepdims=True)
    m = 0.9 * m + (1 - 0.9) * grad
    v = 0.999 * v + (1 - 0.999) * squared
    m_hat, v_hat = m / (1 - 0.9**k), v / (1 - 0.999**k)
    updated = python_walk(starts, states - lr * m_hat / (np.sqrt(v_hat) + 1e-12), limit)
    return updated, m, v, best, best_cost, float(np.abs(updated - states).max())


@pytest.mark.parametrize("limit", ["axis", "norm"])
def test_compiled_adam_step_equals_the_array_formulas_bit_for_bit(limit):
    rng = np.random.default_rng(4)
    starts = rng.normal(size=(3, 4))
    states = feasible(starts, np.cumsum(rng.normal(size=(3, 30, 4)), axis=1), limit)
    grad, m = rng.normal(size=(2, 3, 30, 4))
    v = rng.uniform(0.0, 2.0, size=(3, 30, 4))
    best, best_cost, row_costs = (
        rng.normal(size=(3, 30, 4)),
        np.array([1.0, 2.0, 3.0]),
        np.array([2.0, 1.0, np.nan]),
    )
    want = numpy_adam_step(states, grad, row_costs, m, v, best, best_cost, starts, 0.3, 7, limit)
    got = [states.copy(), m.copy(), v.copy(), best.copy(), best_cost.copy()]
    moved = _kernels.adam_step(
        got[0],
        grad,
        np.ones(4),
        row_costs,
        got[1],
        got[2],
        got[3],
        got[4],
        starts,
        0.3,
        1 - 0.9**7,
        1 - 0.999**7,
        limit == "norm",
    )
    for ours, theirs in zip(got + [moved], want, strict=True):
        np.testing.assert_array_equal(ours, theirs)


def test_plans_with_the_numpy_cost_match_plans_with_the_torch_cost():
    # The optimizer runs the same iterations on costs and gradients equal to float32
    # rounding (1e-6 relative): Adam moves each state by lr times its normalised gradient,
    # so the plans agree to a micrometre (measured: 2e-8) and their costs to 1e-6.
    net = network(64, 0)
    intent = NeuralIntent("n", net, objects=OBJECTS, cost_scale=56.75, length_scale=0.1)
    config = PlannerConfig(iterations=60)
    starts = np.array([[0.45, -0.22, 0.38, 0.0], [0.4, 0.0, 0.3, 0.5]])
    fast = optimize(intent.planning_cost, starts, 30, config=config)
    plain = optimize(intent.state_cost, starts, 30, config=config)
    assert fast.iterations == plain.iterations
    np.testing.assert_allclose(fast.states, plain.states, rtol=0.0, atol=1e-6)
    np.testing.assert_allclose(fast.costs, plain.costs, rtol=FLOAT32_SUMS)
