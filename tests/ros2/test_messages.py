"""The ROS-free checks and conversions of the topics' messages."""

from __future__ import annotations

import json

import numpy as np
import pytest

from casa_core.ros2.messages import (
    JOINT_NAMES,
    MessageError,
    action_keys,
    joint_command,
    joint_positions,
    joy_action,
    state_json,
    user_action,
)


def test_joint_states_are_matched_by_name_and_checked():
    names = ["finger_1", *JOINT_NAMES[::-1]]
    q = joint_positions(names, [9.0, *range(7)])
    assert q.tolist() == [6, 5, 4, 3, 2, 1, 0]
    with pytest.raises(MessageError, match="joints joint_7 missing"):
        joint_positions(JOINT_NAMES[:6], range(6))
    with pytest.raises(MessageError, match="7 joint names but 6 positions"):
        joint_positions(JOINT_NAMES, range(6))
    with pytest.raises(MessageError, match="without names must have 7"):
        joint_positions([], range(6))
    with pytest.raises(MessageError, match="non-finite position of joint_2"):
        joint_positions(JOINT_NAMES, [0, np.inf, 0, 0, 0, 0, 0])


def test_commands_are_checked():
    assert joint_command([0.1] * 7).shape == (7,)
    with pytest.raises(MessageError, match="6 values, expected 7"):
        joint_command([0.0] * 6)
    with pytest.raises(MessageError, match="non-finite"):
        joint_command([np.nan] + [0.0] * 6)
    with pytest.raises(MessageError, match="4 finite numbers"):
        user_action([np.nan, 0, 0], 0)


def test_a_twist_is_a_key_press_within_the_key_speeds():
    action = user_action([1.0, -0.02, 0.0], 3.0)
    assert action.tolist() == [0.05, -0.02, 0.0, 0.5]
    assert action_keys(action) == "x+ rot+"  # -0.02 is below half a key's speed
    assert action_keys(np.zeros(4)) == ""


def test_a_joystick_maps_its_axes_to_the_key_speeds():
    # game_controller_node's layout: 0 left x, 1 left y, 2 right x, 3 right y.
    axes = [0.2, 1.0, -1.0, 0.5, 0.0, 0.0]
    action = joy_action(axes, [], speed=0.05, rot_speed=0.5)
    # x from the left stick's y, y from its x, z from the right stick's y, rot from its x.
    assert np.allclose(action, [0.05, 0.01, 0.025, -0.5])
    assert action_keys(action) == "x+ z+ rot-"
    # A reversed axis and a deflection beyond 1 (a badly calibrated pad) stay within a key.
    action = joy_action([0, 1.7, 0, 0], [], scales=(-1, 1, 1, 1), speed=0.05)
    assert action.tolist() == [-0.05, 0.0, 0.0, 0.0]
    # The enable button: sticks count only while it is held.
    assert not joy_action(axes, [0, 0], enable_button=1).any()
    assert joy_action(axes, [0, 1], enable_button=1).any()


def test_a_joystick_message_that_does_not_fit_the_map_is_refused():
    with pytest.raises(MessageError, match="3 axes, the axis map \\[1, 0, 3, 2\\] needs 4"):
        joy_action([0.0] * 3, [])
    with pytest.raises(MessageError, match="2 buttons, the enable button is number 4"):
        joy_action([0.0] * 4, [1, 1], enable_button=4)
    with pytest.raises(MessageError, match="non-finite axis"):
        joy_action([0.0, np.nan, 0.0, 0.0], [])


def test_the_state_message_without_inference():
    text = state_json(0.0, 1.0, None, np.zeros(4), "user-silent")
    assert json.loads(text) == {
        "alpha": 1.0,
        "belief": {},
        "beta": {},
        "fault": "user-silent",
        "intent": None,
        "misspecified": False,
        "state": [0.0, 0.0, 0.0, 0.0],
        "t": 0.0,
        "user": [],
    }
