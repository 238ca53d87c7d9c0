"""What travels on the topics, without ROS: names, defaults, checks and conversions.

Everything here is plain Python and numpy, so that it runs (and is tested) without the
``ros2`` extra; :mod:`casa_core.ros2.nodes` moves these values in and out of ROS
messages. The defaults are what a lab's launch files can rely on (all remappable, see
``docs/ros2.md``).

Examples
--------
>>> user_action([0.2, 0.0, -0.01], 0.1)
array([ 0.05,  0.  , -0.01,  0.1 ])
>>> action_keys(user_action([0.05, 0.0, -0.05], -0.5))
'x+ z- rot-'
>>> joint_positions(JOINT_NAMES[::-1], range(7)).tolist()
[6.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.0]
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence

import numpy as np

from casa_core.defaults import ROT_SPEED, SPEED, TICK
from casa_core.robot.keys import AXIS_KEYS, format_keys
from casa_core.robot.kinematics import N_JOINTS

#: The arm's joints as ``sensor_msgs/JointState`` names them: the URDF's (robot/j2s7s300.urdf),
#: which are also ros2_kortex's names of the Gen3's seven joints.
JOINT_NAMES = tuple(f"joint_{i}" for i in range(1, N_JOINTS + 1))

#: Default topic names (relative, so a namespace or a remap moves them).
JOINT_STATES_TOPIC = "joint_states"
JOINT_COMMANDS_TOPIC = "velocity_controller/commands"
USER_COMMAND_TOPIC = "cmd_vel"
#: The user's command as a joystick's ``sensor_msgs/Joy`` (joy_node's topic).
JOY_TOPIC = "joy"
#: The optional Cartesian output: MoveIt Servo's input (``geometry_msgs/TwistStamped``).
TWIST_OUTPUT_TOPIC = "servo_node/delta_twist_cmds"
STATE_TOPIC = "casa/state"
#: The trial's metadata (task, method, phase, ...), latched for ``ros2 bag record``.
TRIAL_TOPIC = "casa/trial"

#: The ``Joy.axes`` read as ``[x, y, z, rot]`` by default: joy's game_controller_node
#: layout (0 left stick horizontal, 1 left stick vertical, 2 right stick horizontal,
#: 3 right stick vertical; left and up positive): the left stick moves the tool forward,
#: back and sideways, the right stick up and down and turns the wrist.
JOY_AXES = (1, 0, 3, 2)

#: A user command older than this (s) is not acted on: five control ticks (a keyboard or
#: joystick driver publishing at 20 Hz may drop four messages in a row).
MAX_COMMAND_AGE = 5 * TICK
#: A joint state older than this (s) stops the robot's share: two control ticks.
MAX_JOINT_STATE_AGE = 2 * TICK
#: The rate (Hz) of ``casa ros2 sim``'s joint states and of the assistant's control loop.
CONTROL_RATE = 1.0 / TICK

#: Why the robot's share is stopped at a tick (``casa/state``'s ``fault``).
FAULTS = {
    "joint-state-stale": "no joint state for longer than the stated age: the robot's share "
    "and the user's command stop (zero joint velocities)",
    "joint-state-invalid": "the last joint state has the wrong joints or a non-finite value: "
    "the robot's share and the user's command stop",
    "user-silent": "no user command for longer than the stated age: alpha 1 and a zero "
    "command (the arm holds still)",
    "user-invalid": "the last user command has a non-finite value: treated as silent",
}


class MessageError(ValueError):
    """A message that cannot be used; the text names what is wrong with it."""


def joint_positions(names: Sequence[str], positions: Sequence[float]) -> np.ndarray:
    """The seven arm joints' angles (rad) in :data:`JOINT_NAMES` order, from a joint state.

    Joints are matched by name (a driver may publish them in any order, and the gripper's
    too); a message without names must carry the seven in order.

    Raises
    ------
    MessageError
        Naming the missing joints, the wrong count or the non-finite value.
    """
    values = [float(v) for v in positions]
    names = list(names)
    if not names:
        if len(values) != N_JOINTS:
            raise MessageError(
                f"a joint state without names must have {N_JOINTS} positions, got {len(values)}"
            )
        picked = values
    else:
        if len(names) != len(values):
            raise MessageError(f"{len(names)} joint names but {len(values)} positions")
        index = {name: i for i, name in enumerate(names)}
        missing = [name for name in JOINT_NAMES if name not in index]
        if missing:
            raise MessageError(
                f"joints {', '.join(missing)} missing (got {', '.join(names)}); remap or name "
                f"the arm's joints {', '.join(JOINT_NAMES)}"
            )
        picked = [values[index[name]] for name in JOINT_NAMES]
    bad = [name for name, v in zip(JOINT_NAMES, picked, strict=True) if not math.isfinite(v)]
    if bad:
        raise MessageError(f"non-finite position of {', '.join(bad)}")
    return np.array(picked)


def joint_command(values: Sequence[float]) -> np.ndarray:
    """The seven joint velocities (rad/s) of a ``Float64MultiArray`` command, checked.

    Raises
    ------
    MessageError
        On another count or a non-finite value.
    """
    command = np.asarray(values, dtype=float)
    if command.shape != (N_JOINTS,):
        raise MessageError(f"{command.size} values, expected {N_JOINTS} joint velocities")
    if not np.isfinite(command).all():
        raise MessageError(f"a non-finite joint velocity: {command.tolist()}")
    return command


def user_action(
    linear: Sequence[float], angular_z: float, speed: float = SPEED, rot_speed: float = ROT_SPEED
) -> np.ndarray:
    """The user's action T(a) ``[vx, vy, vz, vrot]`` from a twist, each axis within the limits.

    Each axis is clipped to ``speed`` (m/s) and the turn to ``rot_speed`` (rad/s), the
    limits of a held key, so that a joystick at full deflection commands what a key does.

    Raises
    ------
    MessageError
        On a non-finite component.
    """
    values = [float(v) for v in linear] + [float(angular_z)]
    if len(values) != 4 or not all(math.isfinite(v) for v in values):
        raise MessageError(f"a user command must be 4 finite numbers, got {values}")
    limits = np.array([speed, speed, speed, rot_speed])
    return np.clip(np.array(values), -limits, limits)


def joy_action(
    axes: Sequence[float],
    buttons: Sequence[int],
    *,
    axis_map: Sequence[int] = JOY_AXES,
    scales: Sequence[float] = (1.0, 1.0, 1.0, 1.0),
    enable_button: int = -1,
    speed: float = SPEED,
    rot_speed: float = ROT_SPEED,
) -> np.ndarray:
    """The user's action ``[vx, vy, vz, vrot]`` from a joystick's axes and buttons.

    Axis ``axis_map[i]`` (in [-1, 1], clipped) times ``scales[i]`` is the fraction of a
    key's speed on action axis ``i``. With ``enable_button`` >= 0 the sticks count only
    while that button is held; otherwise the action is zero (a user holding still).

    Raises
    ------
    MessageError
        On too few axes or buttons for the map, or a non-finite axis.

    Examples
    --------
    >>> joy_action([0.0, 1.0, 0.0, -0.5], [], speed=0.05).tolist()
    [0.05, 0.0, -0.025, 0.0]
    >>> joy_action([0.0, 1.0, 0.0, -0.5], [0, 0], enable_button=1).tolist()
    [0.0, 0.0, 0.0, 0.0]
    """
    axes = [float(v) for v in axes]
    needed = max(axis_map) + 1
    if len(axes) < needed:
        raise MessageError(f"{len(axes)} axes, the axis map {list(axis_map)} needs {needed}")
    if enable_button >= 0:
        if len(buttons) <= enable_button:
            raise MessageError(
                f"{len(buttons)} buttons, the enable button is number {enable_button}"
            )
        if not buttons[enable_button]:
            return np.zeros(4)
    picked = [axes[i] for i in axis_map]
    if not all(math.isfinite(v) for v in picked):
        raise MessageError(f"a non-finite axis: {picked}")
    fractions = np.clip(picked, -1.0, 1.0) * np.asarray(scales, dtype=float)
    limits = np.array([speed, speed, speed, rot_speed])
    return np.clip(fractions * limits, -limits, limits)


def action_keys(action, speed: float = SPEED, rot_speed: float = ROT_SPEED) -> str:
    """The keys a user action amounts to, as the log's ``keys`` column writes them.

    An axis counts as a held key from half its limit on: the log's keys say which way
    the user pushed, the efficiency and effort metrics count them.
    """
    limits = [speed, speed, speed, rot_speed]
    held = [
        plus if value > 0 else minus
        for value, limit, (plus, minus) in zip(action, limits, AXIS_KEYS, strict=True)
        if abs(value) >= limit / 2
    ]
    return format_keys(held)


def state_json(
    t: float,
    alpha: float,
    inference,
    state: Iterable[float],
    fault: str | None,
    user: Iterable[float] = (),
) -> str:
    """The text of a ``casa/state`` message (a JSON object, ``docs/ros2.md``).

    Keys: ``t`` (s since the trial started), ``alpha`` (the authority applied), ``beta``
    and ``belief`` (per intent name), ``intent`` (theta*), ``misspecified``, ``state``
    (``[x, y, z, rot]``), ``user`` (the user's action T(a) taken at the tick, whatever
    the input device; empty before the arm is known) and ``fault`` (a key of
    :data:`FAULTS`, or null).
    """
    message = {
        "t": round(float(t), 6),
        "alpha": float(alpha),
        "beta": dict(inference.beta) if inference is not None else {},
        "belief": dict(inference.belief) if inference is not None else {},
        "intent": inference.intent if inference is not None else None,
        "misspecified": bool(inference.misspecified) if inference is not None else False,
        "state": [float(v) for v in state],
        "user": [float(v) for v in user],
        "fault": fault,
    }
    return json.dumps(message, sort_keys=True)
