"""The assistant node's ROS parameters, without ROS: names, defaults, descriptions, checks.

``casa ros2 assist`` declares each entry of :data:`PARAMETERS` as a read-only ROS
parameter (set with ``--param NAME:=VALUE`` or a ROS 2 parameters file, ``--params-file``)
and turns the values it gets into :class:`NodeParameters` with :func:`node_parameters`,
which names a parameter that breaks its rule. The trial's conditions (task, method,
participant, output folder) are command options, not parameters: they change with every
trial, these with the robot and the input device.

Examples
--------
>>> node_parameters({"user_input": "joy", "joy.enable_button": 9}).joy_enable_button
9
>>> node_parameters({"max_command_age": 0})
Traceback (most recent call last):
...
casa_core.ros2.parameters.ParameterError: parameter max_command_age: 0 is not a positive number of s
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import yaml

from casa_core.ros2.messages import JOY_AXES, MAX_COMMAND_AGE, MAX_JOINT_STATE_AGE

#: The node's name: a parameters file's section for it is ``casa_assist`` (or ``/**``).
NODE_NAME = "casa_assist"
#: Parameters every ROS 2 node has; a parameters file may set them for all nodes.
STANDARD_PARAMETERS = ("use_sim_time",)

#: How the user's command arrives (the ``user_input`` parameter).
USER_INPUTS = ("twist", "twist_stamped", "joy")

#: name: (default, description). Each is a ROS parameter of ``casa ros2 assist``.
PARAMETERS: dict[str, tuple[object, str]] = {
    "user_input": (
        "twist",
        "the user's command: twist (geometry_msgs/Twist on cmd_vel), twist_stamped "
        "(geometry_msgs/TwistStamped on cmd_vel) or joy (sensor_msgs/Joy on joy)",
    ),
    "joy.axes": (
        list(JOY_AXES),
        "the Joy axes read as x, y, z and the wrist turn (indices into Joy.axes)",
    ),
    "joy.scales": (
        [1.0, 1.0, 1.0, 1.0],
        "each axis' factor (-1 reverses it); full deflection times the factor is a key's speed",
    ),
    "joy.enable_button": (
        -1,
        "a button (index into Joy.buttons) that must be held for the sticks to count; -1: none",
    ),
    "joint_output": (
        True,
        "publish the blended command as joint velocities on velocity_controller/commands",
    ),
    "twist_output": (
        False,
        "also publish it as a Cartesian twist (geometry_msgs/TwistStamped) on "
        "servo_node/delta_twist_cmds, for an arm driven by a servo controller",
    ),
    "twist_output_frame": ("base_link", "the frame_id of the twist output: the robot base"),
    "max_command_age": (
        MAX_COMMAND_AGE,
        "a user command older than this (s) is not acted on (fault user-silent)",
    ),
    "max_joint_state_age": (
        MAX_JOINT_STATE_AGE,
        "a joint state older than this (s) stops the arm (fault joint-state-stale)",
    ),
}


class ParameterError(ValueError):
    """A parameter value that breaks its rule; the text names the parameter."""


@dataclass(frozen=True)
class NodeParameters:
    """The checked values of :data:`PARAMETERS` (see there for what each means)."""

    user_input: str
    joy_axes: tuple[int, int, int, int]
    joy_scales: tuple[float, float, float, float]
    joy_enable_button: int
    joint_output: bool
    twist_output: bool
    twist_output_frame: str
    max_command_age: float
    max_joint_state_age: float


def node_parameters(values: dict | None = None) -> NodeParameters:
    """:class:`NodeParameters` from ``values`` (name: value), the defaults for the rest.

    Raises
    ------
    ParameterError
        Naming an unknown parameter, or one whose value breaks its rule.
    """
    values = dict(values or {})
    unknown = sorted(set(values) - set(PARAMETERS))
    if unknown:
        raise ParameterError(
            f"unknown parameter {unknown[0]}; the node has {', '.join(PARAMETERS)}"
        )
    get = {name: values.get(name, default) for name, (default, _) in PARAMETERS.items()}
    if get["user_input"] not in USER_INPUTS:
        raise ParameterError(
            f"parameter user_input: {get['user_input']!r} is not one of {', '.join(USER_INPUTS)}"
        )
    axes = _numbers("joy.axes", get["joy.axes"], int)
    if any(axis < 0 for axis in axes):
        raise ParameterError(f"parameter joy.axes: indices must be 0 or more, got {axes}")
    scales = _numbers("joy.scales", get["joy.scales"], float)
    button = get["joy.enable_button"]
    if not isinstance(button, int) or isinstance(button, bool) or button < -1:
        raise ParameterError(f"parameter joy.enable_button: {button!r} is not -1 or an index")
    for name in ("joint_output", "twist_output"):
        if not isinstance(get[name], bool):
            raise ParameterError(f"parameter {name}: {get[name]!r} is not true or false")
    if not (get["joint_output"] or get["twist_output"]):
        raise ParameterError("parameters joint_output and twist_output: both false, no output")
    for name in ("max_command_age", "max_joint_state_age"):
        age = get[name]
        if isinstance(age, bool) or not isinstance(age, int | float) or not age > 0:
            raise ParameterError(f"parameter {name}: {age!r} is not a positive number of s")
        if not math.isfinite(age):
            raise ParameterError(f"parameter {name}: {age!r} is not finite")
    return NodeParameters(
        user_input=get["user_input"],
        joy_axes=axes,
        joy_scales=scales,
        joy_enable_button=button,
        joint_output=get["joint_output"],
        twist_output=get["twist_output"],
        twist_output_frame=str(get["twist_output_frame"]),
        max_command_age=float(get["max_command_age"]),
        max_joint_state_age=float(get["max_joint_state_age"]),
    )


def check_overrides(params: list[str], params_file: Path | str | None = None) -> None:
    """Refuse ``--param NAME:=VALUE`` and parameters-file entries the node does not have.

    ROS would ignore them silently; a misspelt parameter must not leave its default in
    force unnoticed. The file's sections for this node (``casa_assist``, any namespace,
    or ``/**``) are checked; nested keys are joined with dots (``joy: {axes: ...}`` is
    ``joy.axes``). Values are checked once the node has them (:func:`node_parameters`).

    Raises
    ------
    ParameterError
        Naming the option or the file, and the parameter.
    """
    known = set(PARAMETERS) | set(STANDARD_PARAMETERS)
    for param in params:
        name, sep, _ = param.partition(":=")
        if not sep or not name:
            raise ParameterError(f"--param {param!r} is not NAME:=VALUE")
        if name not in known:
            raise ParameterError(f"--param {name}: unknown; the node has {', '.join(PARAMETERS)}")
    if params_file is None:
        return
    path = Path(params_file)
    try:
        document = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        raise ParameterError(f"{path}: not a ROS 2 parameters file: {error}") from None
    if not isinstance(document, dict):
        raise ParameterError(f"{path}: a parameters file maps node names to ros__parameters")
    for node, section in document.items():
        if str(node) != "/**" and str(node).rsplit("/", 1)[-1] != NODE_NAME:
            continue
        values = section.get("ros__parameters") if isinstance(section, dict) else None
        if not isinstance(values, dict):
            raise ParameterError(f"{path}: {node}: has no ros__parameters mapping")
        for name in _flat_names(values):
            if name not in known and str(node) != "/**":
                raise ParameterError(
                    f"{path}: {node}: parameter {name}: unknown; the node has "
                    f"{', '.join(PARAMETERS)}"
                )


def _flat_names(values: dict, prefix: str = "") -> list[str]:
    names = []
    for key, value in values.items():
        name = f"{prefix}{key}"
        names += _flat_names(value, f"{name}.") if isinstance(value, dict) else [name]
    return names


def _numbers(name: str, value, kind) -> tuple:
    items = list(value) if isinstance(value, list | tuple) else None
    if items is None or len(items) != 4:
        raise ParameterError(f"parameter {name}: needs 4 values (x, y, z, turn), got {value!r}")
    if kind is int and not all(isinstance(v, int) and not isinstance(v, bool) for v in items):
        raise ParameterError(f"parameter {name}: needs 4 integers, got {items}")
    if kind is float and not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in items
    ):
        raise ParameterError(f"parameter {name}: needs 4 finite numbers, got {items}")
    return tuple(kind(v) for v in items)
