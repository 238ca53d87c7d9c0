"""The assistant node's parameters, without ROS: their rules and the parameters file."""

from __future__ import annotations

import pytest

from casa_core.ros2.messages import JOY_AXES, MAX_COMMAND_AGE
from casa_core.ros2.parameters import (
    PARAMETERS,
    ParameterError,
    check_overrides,
    node_parameters,
)


def test_the_defaults_are_the_documented_ones():
    parameters = node_parameters()
    assert parameters.user_input == "twist" and parameters.joy_axes == JOY_AXES
    assert parameters.joint_output and not parameters.twist_output
    assert parameters.max_command_age == MAX_COMMAND_AGE
    assert parameters.joy_enable_button == -1


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"user_input": "keyboard"}, "user_input: 'keyboard' is not one of"),
        ({"joy.axes": [1, 0, 3]}, "joy.axes: needs 4 values"),
        ({"joy.axes": [1, 0, 3, -2]}, "indices must be 0 or more"),
        ({"joy.scales": [1.0, 1.0, 1.0, float("nan")]}, "joy.scales: needs 4 finite numbers"),
        ({"joy.enable_button": -3}, "joy.enable_button: -3 is not -1 or an index"),
        ({"twist_output": "yes"}, "twist_output: 'yes' is not true or false"),
        ({"joint_output": False}, "both false, no output"),
        ({"max_joint_state_age": -0.1}, "max_joint_state_age: -0.1 is not a positive number"),
        ({"max_command_age": float("inf")}, "max_command_age: inf is not finite"),
        ({"maximum_command_age": 1.0}, "unknown parameter maximum_command_age"),
    ],
)
def test_a_value_that_breaks_its_rule_is_named(values, message):
    with pytest.raises(ParameterError, match=message):
        node_parameters(values)


def test_overrides_the_node_does_not_have_are_refused(tmp_path):
    check_overrides(["user_input:=joy", "use_sim_time:=false"])
    with pytest.raises(ParameterError, match="--param user_inptu: unknown"):
        check_overrides(["user_inptu:=joy"])
    with pytest.raises(ParameterError, match="is not NAME:=VALUE"):
        check_overrides(["user_input=joy"])
    good = tmp_path / "good.yaml"
    good.write_text(
        "/**:\n  ros__parameters:\n    use_sim_time: false\n    other_nodes_param: 1\n"
        "/lab/casa_assist:\n  ros__parameters:\n    user_input: joy\n"
        "    joy:\n      axes: [1, 0, 4, 3]\n      enable_button: 9\n"
        "teleop_twist_joy_node:\n  ros__parameters:\n    scale_linear: 0.05\n"
    )
    check_overrides([], good)
    bad = tmp_path / "bad.yaml"
    bad.write_text("casa_assist:\n  ros__parameters:\n    joy:\n      axis: [1, 0, 4, 3]\n")
    with pytest.raises(ParameterError, match="bad.yaml: casa_assist: parameter joy.axis: unknown"):
        check_overrides([], bad)
    for text, message in [
        ("casa_assist: [1, 2]\n", "has no ros__parameters mapping"),
        ("- 1\n", "maps node names to ros__parameters"),
        ("casa_assist: {ros__parameters: [\n", "not a ROS 2 parameters file"),
    ]:
        bad.write_text(text)
        with pytest.raises(ParameterError, match=message):
            check_overrides([], bad)
    with pytest.raises(ParameterError, match="missing.yaml: not a ROS 2 parameters file"):
        check_overrides([], tmp_path / "missing.yaml")


def test_every_parameter_is_described():
    for name, (default, description) in PARAMETERS.items():
        assert description and default is not None, name
