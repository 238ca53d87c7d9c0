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
    }
