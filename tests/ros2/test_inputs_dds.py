"""The assistant's inputs and outputs over DDS, chosen by its ROS parameters: a joystick
(``sensor_msgs/Joy``, with an enable button) in and a Cartesian twist out, set by a
ROS 2 parameters file; a ``TwistStamped`` in, set by ``--param``; parameter values that
break their rule refused by name before anything moves.

Under NA the robot has no share (alpha 1), so the blended command is the user's own:
what the twist output carries can be compared with what the joystick commanded.
"""

from __future__ import annotations

import numpy as np
import pytest

from casa_core.io import read_trial
from casa_core.robot import kinematics as kin
from tests.ros2.ros_processes import casa, ros_env, stop

pytest.importorskip("rclpy", reason="the ros2 extra is not installed")
from tests.ros2.harness import Harness  # noqa: E402  (needs rclpy)

PARAMS_FILE = """\
casa_assist:
  ros__parameters:
    user_input: joy
    joy:
      axes: [1, 0, 3, 2]
      scales: [1.0, 1.0, -1.0, 1.0]
      enable_button: 0
    twist_output: true
    twist_output_frame: jaco_base
"""


@pytest.fixture
def env(monkeypatch):
    env = ros_env()
    # rclpy in this process reads the environment too (the domain is given to it).
    for name in ("RMW_IMPLEMENTATION", "ROS_AUTOMATIC_DISCOVERY_RANGE"):
        monkeypatch.setenv(name, env[name])
    return env


def start_q(scene):
    return kin.inverse_kinematics(np.asarray(scene.start_state[:3]), scene.start_state[3])


def assist_args(out, *extra):
    args = ["ros2", "assist", "--task", "known_goal", "--method", "NA", "--participant", "P05"]
    return args + ["--out", str(out), "--duration", "30", *extra]


def test_a_joystick_in_and_a_twist_out_set_by_a_parameters_file(tmp_path, scene, env):
    params = tmp_path / "casa_assist.yaml"
    params.write_text(PARAMS_FILE)
    out = tmp_path / "P05"
    assist = casa(assist_args(out, "--params-file", str(params)), env, tmp_path / "assist.log")
    harness = Harness(env, user="joy")
    q = start_q(scene)
    # Left stick pushed fully up (x+), right stick half down (z: reversed by the scale, +).
    held = ([0.0, 1.0, 0.0, -0.5], [1])
    released = ([0.0, 1.0, 0.0, -0.5], [0])
    try:
        harness.wait_until_assisting(q, joy=held)
        twists_before, states_before = len(harness.twists), len(harness.states)
        harness.run(1.5, positions=q, joy=held)
        pushed = harness.twists[twists_before:]
        faults = {state["fault"] for state in harness.states[states_before:]}
        harness.run(0.5, positions=q, joy=released)
        twists_before = len(harness.twists)
        harness.run(1.0, positions=q, joy=released)
        let_go = harness.twists[twists_before:]
    finally:
        harness.close()
        stop([assist])
    log = (tmp_path / "assist.log").read_text()
    assert assist.returncode == 0, log
    assert "joy (joy) in" in log and "servo_node/delta_twist_cmds" in log
    assert pushed and {twist.header.frame_id for twist in pushed} == {"jaco_base"}
    linear = np.array([[t.twist.linear.x, t.twist.linear.y, t.twist.linear.z] for t in pushed])
    # The harness publishes both the joystick and the joint states: on a loaded machine
    # either can fall silent for longer than its age, and the node stops the twist, by
    # design. Those zero twists must come with the logged fault that says which.
    moving = np.any(linear != 0.0, axis=1)
    np.testing.assert_allclose(linear[moving], [[0.05, 0.0, 0.025]] * moving.sum(), atol=1e-12)
    assert moving.mean() > 0.9, moving.mean()
    assert moving.all() or faults & {"user-silent", "joint-state-stale"}, faults
    assert let_go and not any(t.twist.linear.x or t.twist.linear.z for t in let_go)
    _, frame = read_trial(out / "known_goal_no_misspecification_NA")
    assert "x+ z+" in set(frame["keys"]) and "" in set(frame["keys"])


def test_a_twist_stamped_in_set_by_a_param(tmp_path, scene, env):
    out = tmp_path / "P05"
    args = assist_args(out, "--param", "user_input:=twist_stamped")
    assist = casa(args, env, tmp_path / "assist.log")
    harness = Harness(env, user="twist_stamped")
    q = start_q(scene)
    try:
        harness.wait_until_assisting(q, twist=(0.0, 0.05, 0.0, 0.0))
        commands_before = len(harness.commands)
        harness.run(1.0, positions=q, twist=(0.0, 0.05, 0.0, 0.0))
        commands = np.array(harness.commands[commands_before:])
    finally:
        harness.close()
        stop([assist])
    log = (tmp_path / "assist.log").read_text()
    assert assist.returncode == 0, log
    # The joint velocities move the tool along +y (the kinematics' Jacobian).
    velocity = kin.jacobian(q)[:3] @ np.median(commands, axis=0)
    assert velocity[1] > 0.04 and abs(velocity[0]) < 0.01, velocity
    assert not harness.twists  # the twist output is off by default
    _, frame = read_trial(out / "known_goal_no_misspecification_NA")
    assert "y+" in set(frame["keys"])


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--param", "user_input:=keyboard"], "parameter user_input: 'keyboard' is not one of"),
        (["--param", "joy.axes:=[1.5, 0.0, 3.0, 2.0]"], "parameter joy.axes: the wrong type"),
        (["--param", "twist_outptu:=true"], "--param twist_outptu: unknown"),
    ],
)
def test_a_parameter_that_breaks_its_rule_stops_the_node_by_name(tmp_path, env, extra, message):
    out = tmp_path / "P05"
    assist = casa(assist_args(out, *extra), env, tmp_path / "assist.log")
    assert assist.wait(timeout=60) == 2
    log = (tmp_path / "assist.log").read_text()
    assert message in log and "Traceback" not in log, log
    assert not out.exists()
