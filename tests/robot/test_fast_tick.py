"""The compiled control tick and the pouring cost's gradient compute the plain formulas.

The controller's joint velocities (``casa_core.robot.control_kernel``, numba) are held
to the same formula in plain numpy on pybullet's own Jacobian, over configurations
across the joint ranges (near limits too), lags beyond ``max_lag`` and commands fast
enough to hit the joint speed limits. The pouring cost's hand-written gradient
(``casa_core.planning.pouring.PouringCost``) is held to torch's autograd of
``PouringIntent.state_cost``, at random states and where its roundings act (at the
target, the cup upright, the cup at the pouring tilt). A trial CSV checked on whole
arrays (``casa_core.io.validation``) gives the table and the problems the cell-by-cell
checks give, on a valid trial and on one broken cell of each kind.
"""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pybullet as p
import pytest
import torch

from casa_core.io import validation
from casa_core.io._cells import read_csv_cells
from casa_core.io.atomic import frame_to_csv_text
from casa_core.model import arbitration
from casa_core.planning import optimize
from casa_core.planning.pouring import PouringIntent
from casa_core.robot import kinematics as kin
from casa_core.robot.control_kernel import joint_velocities, joint_velocities_numpy, read_pose
from casa_core.robot.sim import TOOL_LINK
from casa_core.scene import load_scene


def _random_tick(rng, sim, scene):
    """A configuration, its pose, a reference and a command.

    Half the configurations hold the tool orientation (inverse kinematics of a pose near
    the start, small commands); the others are random with a joint near its limit and a
    large orientation error and command, so that the speed limits bind.
    """
    if rng.random() < 0.5:
        pose = scene.start_state + rng.normal(0.0, [0.05, 0.05, 0.05, 0.5])
        q = kin.inverse_kinematics(pose[:3], pose[3])
        action = rng.normal(0.0, 0.02, size=4)
    else:
        q = kin.HOME_CONFIGURATION + rng.normal(0.0, 0.3, size=7)
        bounded = np.flatnonzero(np.isfinite(kin.JOINT_LOWER))
        near = rng.choice(bounded)
        q[near] = kin.JOINT_LOWER[near] + rng.uniform(0.0, 0.02)
        q = np.clip(q, kin.JOINT_LOWER + 1e-5, kin.JOINT_UPPER - 1e-5)
        action = rng.normal(0.0, 0.2, size=4)
    state = sim.reset([0.0, 0.0, 0.0, 0.0], q=q)
    reference = state + rng.normal(0.0, 0.01, size=4)  # often beyond max_lag = 0.01
    return state, reference, action


def _jacobian(sim):
    """pybullet's Jacobian rows (linear, angular) of the tool at the arm's joint angles."""
    zeros = [0.0] * 7
    return p.calculateJacobian(
        sim.robot, TOOL_LINK, [0.0] * 3, sim.q.tolist(), zeros, zeros, physicsClientId=sim.client
    )


def test_the_compiled_tick_equals_the_numpy_formula(sim):
    # The same formula; the 6 x 6 solve differs (Cholesky vs LU) by float rounding.
    rng = np.random.default_rng(0)
    scaled = 0
    for _ in range(200):
        state, reference, action = _random_tick(rng, sim, load_scene())
        linear, angular = _jacobian(sim)
        jac = np.array((*linear, *angular))
        want, want_reference = joint_velocities_numpy(
            jac, sim.q, state, reference, sim._rotation, action, sim._gains
        )
        advanced = reference.copy()
        got = joint_velocities(
            linear, angular, sim.q, state, advanced, sim._rotation, action, sim._gains
        )
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12)
        np.testing.assert_array_equal(advanced, want_reference)
        scaled += bool(np.isclose(np.max(np.abs(want) / kin.JOINT_MAX_SPEED), 1.0))
    assert 20 < scaled < 200  # both branches of the speed limit were exercised


def test_the_simulation_uses_the_compiled_tick(sim):
    rng = np.random.default_rng(1)
    state, reference, action = _random_tick(rng, sim, load_scene())
    sim._reference = reference.copy()
    linear, angular = _jacobian(sim)
    want, want_reference = joint_velocities_numpy(
        np.array((*linear, *angular)), sim.q, state, reference, sim._rotation, action, sim._gains
    )
    np.testing.assert_allclose(sim.joint_velocities(action), want, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(sim._reference, want_reference)


def test_the_compiled_reading_equals_the_numpy_one(sim):
    # rot_of of pybullet's matrix, unwrapped from the last reading (as the numpy code did).
    rng = np.random.default_rng(3)
    for _ in range(200):
        state, _, action = _random_tick(rng, sim, load_scene())
        previous = rng.uniform(-20.0, 20.0)
        link = p.getLinkState(
            sim.robot, TOOL_LINK, computeForwardKinematics=True, physicsClientId=sim.client
        )
        matrix = p.getMatrixFromQuaternion(link[5])
        got, rotation = read_pose(link[4], matrix, previous)
        change = kin.rot_of(np.array(matrix).reshape(3, 3)) - np.float64(previous)
        want_rot = previous + float((change + np.pi) % (2 * np.pi) - np.pi)
        np.testing.assert_array_equal(rotation, np.array(matrix).reshape(3, 3))
        np.testing.assert_array_equal(got[:3], link[4])
        assert got[3] == pytest.approx(want_rot, abs=1e-12)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_command_leaves_the_reference_alone(sim, bad):
    reference = sim._reference.copy()
    with pytest.raises(ValueError, match="4 finite numbers"):
        sim.joint_velocities([0.0, bad, 0.0, 0.0])
    np.testing.assert_array_equal(sim._reference, reference)


def _pour_states(intent, rng):
    """Random states, and states at the smoothed kinks: at the target, upright, poured."""
    position = rng.uniform([0.3, -0.2, 0.1], [0.7, 0.4, 0.5], size=(40, 3))
    rot = rng.uniform(-7.0, 7.0, size=(40, 1))
    random = np.concatenate([position, rot], axis=1)
    near = intent.target + rng.normal(0.0, 1e-4, size=(6, 3))  # d within the 1 mm rounding
    at_radius = intent.target + np.array([intent.radius, 0.0, 0.0])
    special = [
        [*intent.target, 0.0],
        [*intent.target, intent.tilt],
        [*at_radius, 0.0],
        [*at_radius, 1e-5],
        [*at_radius, -intent.tilt],
        *(
            [*x, r]
            for x, r in zip(near, [0.0, 1e-6, -1e-6, intent.tilt, 2 * np.pi, 3.0], strict=True)
        ),
    ]
    return np.concatenate([random, np.array(special)])[None]


def test_the_pouring_cost_and_gradient_equal_torch_autograd():
    # The same formula in float64, differentiated by hand: equal to rounding.
    rng = np.random.default_rng(2)
    for options in ({}, {"radius": 0.1, "pour_weight": 0.3, "spill_weight": 0.5}):
        intent = PouringIntent.from_scene(load_scene(), **options)
        states = _pour_states(intent, rng)
        x = torch.from_numpy(states).requires_grad_(True)
        want = intent.state_cost(x)
        (want_grad,) = torch.autograd.grad(want.sum(), x)
        values, grad = intent.planning_cost.value_and_grad(states)
        np.testing.assert_allclose(values, want.detach().numpy(), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(grad, want_grad.numpy(), rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(intent.planning_cost(states[0]), values[0])


def test_pouring_plans_with_the_hand_gradient_equal_plans_with_autograd():
    # Adam divides each gradient component by its own size, so rounding-level differences
    # of near-zero components (which differ between CPUs' vector units) steer the iterates
    # apart mid-run, and the stopping rule ends them some iterations apart (1 on AMD AVX2,
    # 11 on Intel AVX-512). What must hold everywhere: both converge (stop before the
    # cap) to the same optimum, to within the stopping rule's tolerance (tol = 1e-4).
    intent = PouringIntent.from_scene(load_scene())
    start = load_scene().start_state
    for steps in (10, 30):
        fast = optimize(intent.planning_cost, start, steps, config=intent.planner)
        plain = optimize(intent.state_cost, start, steps, config=intent.planner)
        assert max(fast.iterations, plain.iterations) < intent.planner.iterations
        np.testing.assert_allclose(fast.states, plain.states, rtol=0, atol=intent.planner.tol)
        np.testing.assert_allclose(fast.costs, plain.costs, rtol=1e-6)


def _trial_text():
    """A valid casa-trial/1 CSV of 301 ticks with two intents (written as a trial writes)."""
    rng = np.random.default_rng(4)
    n = 301
    belief = rng.uniform(0.0, 1.0, n)
    frame = pd.DataFrame(
        {
            "t": np.round(np.arange(n) * 0.05, 6),
            "x": rng.uniform(0.3, 0.6, n),
            "y": rng.uniform(-0.3, 0.3, n),
            "z": rng.uniform(0.1, 0.4, n),
            "rot": rng.uniform(-3.0, 3.0, n),
            "keys": rng.choice(["", "x+", "x+ y-", "rot+"], n),
            "alpha": rng.uniform(0.0, 1.0, n),
            **{f"q{i}": rng.normal(size=n) for i in range(1, 8)},
            "beta:a": rng.uniform(0.0, 5.0, n),
            "beta:b": rng.uniform(0.0, 5.0, n),
            "belief:a": belief,
            "belief:b": 1.0 - belief,
        }
    )
    return frame_to_csv_text(frame)


def _replace_cell(text, line, column, value):
    rows = text.split("\n")
    header = rows[0].split(",")
    cells = rows[line - 1].split(",")
    cells[header.index(column)] = value
    rows[line - 1] = ",".join(cells)
    return "\n".join(rows)


def _edits():
    """Valid and broken variants of one trial: every rule the whole-table check decides."""
    text = _trial_text()
    yield "valid", text, None
    yield "valid, intents named", text, {"intents": ["a", "b"]}
    yield "an intent not in the metadata", text, {"intents": ["a"]}
    yield "valid, two rows", "\n".join(text.split("\n")[:3]) + "\n", None
    for column, value in [
        ("x", "nan"),
        ("x", "2.5"),
        ("alpha", "1.0000001"),
        ("beta:a", "-1e-9"),
        ("rot", "150"),
        ("q3", "inf"),
        ("q3", "abc"),
        ("t", "0.1"),  # not increasing
        ("t", "0.101"),  # an irregular step (a warning)
        ("keys", "x+ x+"),
        ("keys", "up"),
        ("keys", "x+\u00a0y-"),
        ("belief:a", "2"),
    ]:
        yield f"{column} = {value!r}", _replace_cell(text, 5, column, value), None  # t = 0.15
    yield "valid, as float() reads it", _replace_cell(text, 5, "rot", " 1_0"), None
    # Beliefs summing to 1 - 2e-6 (outside the tolerance) and to 1 - 6e-7 (inside).
    for shortfall in (2e-6, 6e-7):
        lines = text.split("\n")
        belief = float(lines[5].split(",")[-1])
        yield (
            f"beliefs short by {shortfall}",
            _replace_cell(text, 6, "belief:b", repr(belief - shortfall)),
            None,
        )
    yield "first tick late", text.replace("\n0.0,", "\n0.2,", 1), None
    stretched = pd.read_csv(io.StringIO(text))
    stretched["t"] = np.round(stretched["t"] * 2, 6)
    yield "a 10 Hz trial", frame_to_csv_text(stretched), None


@pytest.mark.parametrize(("what", "text", "meta"), list(_edits()), ids=lambda x: str(x)[:30])
def test_the_whole_table_check_reads_what_the_cell_checks_read(what, text, meta, monkeypatch):
    # The same table and the same problems, word for word, with and without the fast path.
    frame, problems = validation.parse_trial_csv(text, "t.csv", meta=meta)
    cells, _ = read_csv_cells(text, "t.csv")
    taken = validation._valid_frame(cells, meta) is not None
    assert taken == what.startswith("valid")  # the fast path decides only valid tables
    monkeypatch.setattr(validation, "_valid_frame", lambda cells, meta: None)
    want_frame, want_problems = validation.parse_trial_csv(text, "t.csv", meta=meta)
    assert [str(p) for p in problems] == [str(p) for p in want_problems]
    assert [p.severity for p in problems] == [p.severity for p in want_problems]
    pd.testing.assert_frame_equal(frame, want_frame, check_exact=True)
    assert list(frame.dtypes) == list(want_frame.dtypes)
    if taken:
        assert problems == []


def test_the_scalar_blend_is_the_checked_one_to_the_bit():
    rng = np.random.default_rng(6)
    cases = [(float(a), rng.normal(size=4), rng.normal(size=4)) for a in rng.uniform(size=50)]
    cases += [(0.0, np.zeros(4), np.full(4, np.inf)), (np.float64(0.3), np.ones(4), -np.ones(4))]
    for alpha, user, robot in cases:
        want = arbitration._checked_blend(alpha, user, robot)
        np.testing.assert_array_equal(arbitration.blend(alpha, user, robot), want)
    with pytest.raises(ValueError, match="user_action contains NaN"):
        arbitration.blend(0.5, np.array([np.nan, 0.0]), np.zeros(2))
    with pytest.raises(ValueError, match="alpha must lie"):
        arbitration.blend(1.5, np.zeros(2), np.zeros(2))
