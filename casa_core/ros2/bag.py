"""A rosbag2 recording (sqlite3 or MCAP) as a casa-trial/1 trial (``casa import rosbag``).

The bag is read with ``rosbags`` (pure Python, the ``ros2`` extra; no ROS installation).
The trial's rows are the control ticks (20 Hz) from the first joint state to the last;
at each tick the newest joint state and user command received by then count, and the
newest assistant's state received before the next tick (the node publishes it just after
the tick it describes):

- the joint state (``sensor_msgs/msg/JointState``): ``q1..q7`` and, through the arm's
  kinematics, ``x, y, z, rot``;
- the user command (``geometry_msgs/msg/Twist`` or ``TwistStamped``): the ``keys`` it
  amounts to (:func:`~casa_core.ros2.messages.action_keys`), none once it is older than
  :data:`~casa_core.ros2.messages.MAX_COMMAND_AGE`; in a bag without it (a session driven
  by a joystick), the keys come from the user's action each ``casa/state`` carries;
- the assistant's state (``casa/state``, a JSON ``std_msgs/msg/String``): ``alpha``,
  ``beta:NAME`` and ``belief:NAME``; before its first message, and in a bag without it,
  the user has full control and nothing is inferred.

The metadata are the node's (``casa/trial``, latched), each key overridden by the
options. Times are the bag's receive times. A message that cannot be read, or one whose
content breaks a rule, is refused naming the topic, the message's number and the rule.
"""

from __future__ import annotations

import json
import math
from bisect import bisect_right
from pathlib import Path

import pandas as pd

from casa_core.defaults import TICK
from casa_core.io.contract import CONDITION_KEYS
from casa_core.robot import kinematics as kin
from casa_core.ros2.messages import (
    JOINT_STATES_TOPIC,
    MAX_COMMAND_AGE,
    STATE_TOPIC,
    TRIAL_TOPIC,
    USER_COMMAND_TOPIC,
    MessageError,
    action_keys,
    joint_positions,
    user_action,
)

#: The message types each topic may carry.
TOPIC_TYPES = {
    "joint_states": ("sensor_msgs/msg/JointState",),
    "user_command": ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"),
    "state": ("std_msgs/msg/String",),
    "trial": ("std_msgs/msg/String",),
}


class BagError(ValueError):
    """A bag that cannot be converted; the text names the bag, topic and message."""


def read_bag(
    bag: Path | str,
    *,
    topics: dict | None = None,
    meta: dict | None = None,
) -> tuple[dict, pd.DataFrame]:
    """The trial recorded in ``bag``: its casa-trial/1 metadata and rows.

    Parameters
    ----------
    bag : path
        The rosbag2 folder (``metadata.yaml`` and its sqlite3 or MCAP file).
    topics : dict, optional
        Topic names by role (``joint_states``, ``user_command``, ``state``, ``trial``),
        over the defaults of :mod:`casa_core.ros2.messages`.
    meta : dict, optional
        Metadata over the recorded ``casa/trial`` (None values are ignored).

    Raises
    ------
    BagError
        Naming the bag, the topic and the message that cannot be used.
    """
    names = {
        "joint_states": JOINT_STATES_TOPIC,
        "user_command": USER_COMMAND_TOPIC,
        "state": STATE_TOPIC,
        "trial": TRIAL_TOPIC,
    }
    names.update({k: v for k, v in (topics or {}).items() if v})
    messages = _messages(Path(bag), names)
    joints = messages["joint_states"]
    if len(joints) < 2:
        raise BagError(
            f"{bag}: topic {names['joint_states']!r} has {len(joints)} message(s); a trial "
            "needs the arm's joint states over at least two control ticks"
        )
    recorded = messages["trial"][-1][1] if messages["trial"] else {}
    given = {k: v for k, v in (meta or {}).items() if v is not None}
    merged = {**recorded, **given}
    missing = [key for key in CONDITION_KEYS if key not in merged]
    if missing:
        raise BagError(
            f"{bag}: no {', '.join(missing)}: the bag has no {names['trial']!r} message "
            f"saying it; give --{' --'.join(missing)}"
        )
    merged.setdefault("source", "human")
    frame = _ticks(joints, messages["user_command"], messages["state"])
    intents = [c.split(":", 1)[1] for c in frame.columns if c.startswith("belief:")]
    if intents:
        merged["intents"] = intents
    return merged, frame


def _messages(bag: Path, names: dict) -> dict:
    """``role -> [(nanoseconds, value), ...]`` in receive order, each message checked."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    found: dict = {role: [] for role in names}
    # Recorded names are absolute (/joint_states); the defaults are relative to the root.
    role_of = {topic.lstrip("/"): role for role, topic in names.items()}
    try:
        with Reader(bag) as reader:
            for connection in reader.connections:
                role = role_of.get(connection.topic.lstrip("/"))
                if role is not None and connection.msgtype not in TOPIC_TYPES[role]:
                    raise BagError(
                        f"{bag}: topic {connection.topic!r} carries {connection.msgtype}, "
                        f"expected {' or '.join(TOPIC_TYPES[role])}"
                    )
            wanted = [c for c in reader.connections if c.topic.lstrip("/") in role_of]
            for connection, stamp, raw in reader.messages(connections=wanted):
                role = role_of[connection.topic.lstrip("/")]
                number = len(found[role]) + 1
                where = f"{bag}: topic {connection.topic!r}, message {number}"
                try:
                    message = store.deserialize_cdr(raw, connection.msgtype)
                    value = _value(role, message)
                except BagError:
                    raise
                except Exception as error:  # a damaged message: any decoding error
                    raise BagError(f"{where}: cannot be used: {error}") from None
                found[role].append((stamp, value))
    except BagError:
        raise
    except Exception as error:  # rosbags' errors, sqlite's, a truncated MCAP's
        raise BagError(f"{bag}: not a readable rosbag2 recording: {error}") from None
    return found


def _value(role: str, message):
    """What a message says, checked: joint angles, a user action, or a JSON object."""
    if role == "joint_states":
        return joint_positions(list(message.name), list(message.position))
    if role == "user_command":
        twist = getattr(message, "twist", message)  # TwistStamped or Twist
        linear = (twist.linear.x, twist.linear.y, twist.linear.z)
        return user_action(linear, twist.angular.z)
    try:
        value = json.loads(message.data)
    except json.JSONDecodeError as error:
        raise MessageError(f"not JSON: {error}") from None
    if not isinstance(value, dict):
        raise MessageError("not a JSON object")
    return value


def _latest(stream: list, stamps: list, when: float):
    """The newest ``(nanoseconds, value)`` of ``stream`` (received at ``stamps``) at or before
    ``when``, or None."""
    index = bisect_right(stamps, when)
    return stream[index - 1] if index else None


def _ticks(joints: list, commands: list, states: list) -> pd.DataFrame:
    # In integer nanoseconds: a tick and a message at the same instant compare equal.
    start, end = joints[0][0], joints[-1][0]
    tick_ns, max_age = round(TICK * 1e9), round(MAX_COMMAND_AGE * 1e9)
    intents: list[str] = []
    for _, state in states:
        intents += [name for name in state.get("belief", {}) if name not in intents]
    stamps = [[s for s, _ in stream] for stream in (joints, commands, states)]
    rows = []
    rot = None
    for tick in range((end - start) // tick_ns + 1):
        when = start + tick * tick_ns
        q = _latest(joints, stamps[0], when)[1]
        pose = kin.forward_kinematics(q)
        angle = kin.rot_of(pose[:3, :3])
        if rot is not None:  # unwrapped, as the arm's own state is
            angle += 2 * math.pi * round((rot - angle) / (2 * math.pi))
        rot = angle
        x, y, z = pose[:3, 3].tolist()
        # The node publishes a tick's state just after the tick: what came within it.
        state = _latest(states, stamps[2], when + tick_ns - 1)
        state = state[1] if state is not None else {}
        row = {"t": round(tick * TICK, 6), "x": x, "y": y, "z": z, "rot": rot}
        if commands:
            command = _latest(commands, stamps[1], when)
            fresh = command is not None and when - command[0] <= max_age
            row["keys"] = action_keys(command[1]) if fresh else ""
        else:
            row["keys"] = _state_keys(state)
        row.update({f"q{i + 1}": float(v) for i, v in enumerate(q)})
        if intents:
            row["alpha"] = float(state.get("alpha", 1.0))
            for name in intents:
                row[f"beta:{name}"] = float(state.get("beta", {}).get(name, 0.0))
            for name in intents:
                belief = state.get("belief", {})
                row[f"belief:{name}"] = float(belief.get(name, 1.0 / len(intents)))
        rows.append(row)
    return pd.DataFrame(rows)


def _state_keys(state: dict) -> str:
    """The keys of the user's action a ``casa/state`` carries ("" if none)."""
    user = state.get("user") or []
    if len(user) != 4 or not all(isinstance(v, int | float) and math.isfinite(v) for v in user):
        return ""
    return action_keys(user)


def import_bag(bag: Path | str, out: Path | str, *, force: bool = False, **options) -> Path:
    """Convert ``bag`` into ``OUT/<participant>/<task>_<phase>_<method>`` (casa-trial/1).

    ``options`` are :func:`read_bag`'s. Returns the trial's stem.

    Raises
    ------
    BagError
        As :func:`read_bag`, or when the trial exists and ``force`` is not given.
    casa_core.io.LogError
        When the converted trial breaks a rule of casa-trial/1 (nothing is written).
    """
    from casa_core.io import trial_files, write_trial

    meta, frame = read_bag(bag, **options)
    stem = Path(out) / str(meta["participant"]) / f"{meta['task']}_{meta['phase']}_{meta['method']}"
    existing = [path for path in trial_files(stem) if path.exists()]
    if existing and not force:
        raise BagError(f"{existing[0]} exists; give --force to replace it")
    write_trial(stem, meta, frame)
    return stem
