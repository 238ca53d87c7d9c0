"""The 20 Hz controller with pybullet in the loop, and the scene.

Expected numbers are the key map's (0.05 m/s, 0.5 rad/s over 0.05 s ticks) and the
orientation definition of ``casa_core.robot.kinematics``; all are read back from
pybullet, not from the controller's own bookkeeping.
"""

import copy
import subprocess
import sys

import numpy as np
import pybullet as p
import pytest
import yaml

from casa_core.robot import kinematics as kin
from casa_core.robot.sim import ArmSimulation
from casa_core.scene import DEFAULT_SCENE, Scene, SceneError


@pytest.fixture()
def sim(scene):
    with ArmSimulation(scene) as simulation:
        yield simulation


def test_reset_puts_the_cup_at_the_start_pose(sim, scene):
    np.testing.assert_allclose(sim.state, scene.start_state, atol=1e-5)
    assert kin.within_limits(sim.q)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_held_key_moves_at_the_key_speed_and_keeps_the_orientation(sim, axis):
    action = np.zeros(4)
    action[axis] = 0.05
    start = sim.state
    for _ in range(40):  # 2 s
        sim.step(action)
    moved = sim.state - start
    # 0.05 m/s for 2 s = 0.1 m along the axis; the others stay put (closed form).
    expected = np.zeros(4)
    expected[axis] = 0.1
    np.testing.assert_allclose(moved, expected, atol=2e-3)
    position, rotation = sim.ee_pose()
    np.testing.assert_allclose(position, sim.state[:3])
    np.testing.assert_allclose(rotation, kin.ee_rotation(sim.state[3]), atol=5e-3)


def test_rotate_key_turns_the_tool_about_its_axis_and_tilts_the_cup(sim):
    start = sim.state
    for _ in range(40):  # 2 s at 0.5 rad/s = 1 rad
        sim.step([0, 0, 0, 0.5])
    assert sim.state[3] == pytest.approx(1.0, abs=0.02)
    np.testing.assert_allclose(sim.state[:3], start[:3], atol=2e-3)  # the cup stays put
    _, rotation = sim.ee_pose()
    np.testing.assert_allclose(rotation, kin.ee_rotation(1.0), atol=0.02)
    # The cup axis leans from vertical by rot (its z component is cos(rot)).
    assert rotation[2, 0] == pytest.approx(np.cos(1.0), abs=0.02)


def test_rot_is_unwrapped_past_pi(sim):
    for _ in range(160):  # 8 s at 0.5 rad/s = 4 rad > pi
        sim.step([0, 0, 0, 0.5])
    assert sim.state[3] == pytest.approx(4.0, abs=0.05)


def test_every_scene_position_is_reached_in_a_straight_line_within_joint_limits(sim, scene):
    """The reachability check of the scene with the fixed tool orientation."""
    targets = [*scene.goals.values(), scene.pouring.position]
    for target in targets:
        target = np.asarray(target, dtype=float)
        sim.reset([*scene.start.position, 0.0])
        start = sim.state[:3]
        line = (target - start) / np.linalg.norm(target - start)
        worst = 0.0
        for _ in range(400):
            error = target - sim.state[:3]
            if np.linalg.norm(error) < 0.003:
                break
            velocity = 0.05 * error / max(np.linalg.norm(error), 0.05)
            state = sim.step([*velocity, 0.0])
            offset = state[:3] - start
            worst = max(worst, np.linalg.norm(offset - (offset @ line) * line))
            assert kin.within_limits(sim.q), f"joint limit on the way to {target}"
        assert np.linalg.norm(target - sim.state[:3]) < 0.003, f"did not reach {target}"
        assert worst < 0.02, f"strayed {worst:.3f} m off the line to {target}"


def test_bad_action_and_bad_scene_are_named(sim):
    with pytest.raises(ValueError, match="action"):
        sim.step([0.0, 0.0, np.nan, 0.0])
    # The scene the simulation needs is checked when it is loaded.
    data = yaml.safe_load(DEFAULT_SCENE.read_text(encoding="utf-8"))
    broken = copy.deepcopy(data)
    del broken["goals"]["red"]
    with pytest.raises(SceneError, match="goals.red"):
        Scene.from_dict(broken)
    broken = copy.deepcopy(data)
    broken["teleop"]["dt"] = "fast"
    with pytest.raises(SceneError, match="teleop.dt"):
        Scene.from_dict(broken)


def test_scene_shows_goals_where_the_scene_says(sim, scene):
    for name, body in sim.bodies.goals.items():
        position, _ = p.getBasePositionAndOrientation(body, physicsClientId=sim.client)
        np.testing.assert_allclose(position, scene.goals[name], atol=1e-9)
    sim.close()
    sim.close()  # idempotent


def test_the_robot_imports_nothing_of_learning_or_the_study():
    code = (
        "import sys, casa_core.robot.keys, casa_core.robot.kinematics, casa_core.robot.scene, "
        "casa_core.robot.sim, casa_core.robot.teleop\n"
        "print(' '.join(m for m in sys.modules if m.startswith(('casa_core.irl', "
        "'casa_core.learning.library', 'casa_core.learning', 'casa_core.study', 'torch'))))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == ""
