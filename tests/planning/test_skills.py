"""The pouring intent and the cup's orientation (casa_core.planning.pouring and .rotation)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from casa_core.planning.pouring import PouringIntent, cup_axis, cup_tilt_deg, cup_upright
from casa_core.planning.rotation import end_effector_rotation
from casa_core.robot.kinematics import ee_rotation
from casa_core.scene import load_scene

SCENE = load_scene()


def as_t(value):
    return torch.tensor(value, dtype=torch.float64)


@pytest.mark.parametrize("rot", [0.0, 0.4, -1.1, 1.8, 3.0])
def test_rotation_is_the_arms_own_and_a_rotation(rot):
    matrix = end_effector_rotation(as_t(rot)).numpy()
    np.testing.assert_allclose(matrix, ee_rotation(rot), atol=1e-12)
    np.testing.assert_allclose(matrix.T @ matrix, np.eye(3), atol=1e-12)
    assert np.linalg.det(matrix) == pytest.approx(1.0)


def test_cup_upright_feature_and_tilt():
    # The original's u = 1 - (cup axis . world z): 0 upright, 1 on its side, 2 inverted;
    # the cup turns about a horizontal axis, so its tilt from upright is |rot|.
    u = cup_upright(as_t([0.0, np.pi / 2, np.pi])).numpy()
    np.testing.assert_allclose(u, [0.0, 1.0, 2.0], atol=1e-12)
    assert cup_tilt_deg(1.8) == pytest.approx(np.degrees(1.8))
    assert cup_tilt_deg(-0.5) == pytest.approx(np.degrees(0.5))
    np.testing.assert_allclose(cup_axis(as_t(0.0)).numpy(), [0.0, 0.0, 1.0], atol=1e-12)


def test_pouring_optimum_carries_upright_then_tilts_at_the_target():
    intent = PouringIntent.from_scene(SCENE)
    trajectory = intent.optimal_trajectory(SCENE.start_state, 15.0)
    assert trajectory.shape == (31, 4)
    end = trajectory[-1]
    assert np.linalg.norm(end[:3] - intent.target) < 0.01
    assert cup_tilt_deg(end[3]) == pytest.approx(np.degrees(SCENE.pouring.tilt), abs=3.0)
    far = np.linalg.norm(trajectory[:, :3] - intent.target, axis=1) > 2 * intent.radius
    assert far.sum() >= 10  # the carry is long enough for this to say something
    assert (cup_tilt_deg(trajectory[far, 3]) < 5.0).all()  # no spilling on the way


def test_tilting_has_a_gradient_at_the_upright_cup():
    # Why the cost uses chords of the cup axis: u is flat at the upright cup.
    intent = PouringIntent.from_scene(SCENE)
    state = as_t([*intent.target, 0.0]).requires_grad_(True)
    intent.state_cost(state[None, None, :]).sum().backward()
    assert state.grad[3] < 0  # tilting toward the pouring angle lowers the cost


def test_costs_add_up_along_a_trajectory():
    intent = PouringIntent.from_scene(SCENE)
    states = np.array([[0.45, -0.22, 0.38, 0.0], [0.47, -0.2, 0.36, 0.1], [0.5, -0.1, 0.3, 0.2]])
    steps = intent.step_cost(states[0], states[1]) + intent.step_cost(states[1], states[2])
    assert intent.prefix_cost(states) == pytest.approx(steps)


def test_the_scene_gives_target_and_tilt():
    intent = PouringIntent.from_scene(SCENE, "p", radius=0.1)
    assert intent.target.tolist() == list(SCENE.pouring.position)
    assert (intent.name, intent.tilt, intent.radius) == ("p", SCENE.pouring.tilt, 0.1)


def test_bad_parameters_are_named():
    with pytest.raises(ValueError, match="radius of intent 'pour' must be a positive number"):
        PouringIntent("pour", [0.5, 0.2, 0.3], tilt=1.8, radius=0.0)
    with pytest.raises(ValueError, match="spill_weight"):
        PouringIntent("pour", [0.5, 0.2, 0.3], tilt=1.8, spill_weight=np.nan)
    with pytest.raises(ValueError, match="target"):
        PouringIntent("pour", [0.5, 0.2], tilt=1.8)
    with pytest.raises(ValueError, match="tilt of intent 'pour' must be finite"):
        PouringIntent("pour", [0.5, 0.2, 0.3], tilt=np.inf)
