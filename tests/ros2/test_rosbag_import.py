"""``casa import rosbag``: bags written here with ``rosbags`` (sqlite3 and MCAP) become
casa-trial/1 trials that validate and build; damaged or incomplete bags are refused
naming the topic and the message."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from casa_core.cli import main
from casa_core.io import read_trial
from casa_core.robot.keys import keys_to_action, parse_keys
from casa_core.ros2.messages import JOINT_NAMES
from casa_core.study.closed_loop import run_trial
from casa_core.study.key_sources import WaypointKeys

rosbags = pytest.importorskip("rosbags", reason="the ros2 extra is not installed")
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

STORE = get_typestore(Stores.ROS2_JAZZY)
T = STORE.types
STORAGE = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}
#: Bag times start here (ns): a robot's clock, not zero.
EPOCH = 1_700_000_000 * 10**9


@pytest.fixture(scope="module")
def trial(scene):
    """An in-process Known Goal trial under CASA: what the bag records."""
    expert = WaypointKeys([[*scene.goals["green"][:3], 0.0]], rot_tolerance=1e9)
    return run_trial(scene, "known_goal", "CASA", expert, participant="P02", max_duration=8)


def header(ns: int):
    stamp = T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
    return T["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link")


def joint_state(ns: int, q, names=JOINT_NAMES):
    q = np.asarray(q, dtype=float)
    empty = np.zeros(0)
    return T["sensor_msgs/msg/JointState"](
        header=header(ns), name=list(names), position=q, velocity=empty, effort=empty
    )


def twist(action):
    vector = T["geometry_msgs/msg/Vector3"]
    return T["geometry_msgs/msg/Twist"](
        linear=vector(x=action[0], y=action[1], z=action[2]), angular=vector(x=0, y=0, z=action[3])
    )


def twist_stamped(ns: int, action):
    return T["geometry_msgs/msg/TwistStamped"](header=header(ns), twist=twist(action))


def text(value) -> object:
    return T["std_msgs/msg/String"](data=json.dumps(value))


def write_bag(
    path, trial, *, storage="sqlite3", meta=True, joint_type=None, spoil=None, user_as="twist"
):
    """The trial as a rosbag2: joint states and commands per tick, the state at each.

    ``user_as``: the user's command as a ``twist`` or ``twist_stamped`` on cmd_vel, or
    only in each state (``state``: a joystick session recorded without cmd_vel)."""
    frame = trial.frame
    q_columns = [f"q{i}" for i in range(1, 8)]
    with Writer(path, version=9, storage_plugin=STORAGE[storage]) as writer:
        joints = writer.add_connection(
            "/joint_states", joint_type or "sensor_msgs/msg/JointState", typestore=STORE
        )
        kind = {"twist": "Twist", "twist_stamped": "TwistStamped"}.get(user_as)
        if kind:
            user = writer.add_connection("/cmd_vel", f"geometry_msgs/msg/{kind}", typestore=STORE)
        state = writer.add_connection("/casa/state", "std_msgs/msg/String", typestore=STORE)
        if meta:
            info = writer.add_connection("/casa/trial", "std_msgs/msg/String", typestore=STORE)
            writer.write(info, EPOCH, STORE.serialize_cdr(text(trial.meta), info.msgtype))
        names = trial.meta["intents"]
        for index, row in frame.iterrows():
            # As the node's bags have them: the command, then the joint state, before the
            # tick; the assistant's state of the tick just after it.
            ns = EPOCH + int(round(row["t"] * 1e9))
            q = row[q_columns].to_numpy(dtype=float)
            message = spoil(index, q) if spoil else joint_state(ns, q)
            if joint_type is None:
                writer.write(joints, ns - 5_000_000, STORE.serialize_cdr(message, joints.msgtype))
            action = keys_to_action(parse_keys(row["keys"]))
            if kind:
                command = twist(action) if kind == "Twist" else twist_stamped(ns, action)
                writer.write(user, ns - 6_000_000, STORE.serialize_cdr(command, user.msgtype))
            value = {"alpha": row["alpha"], "user": action.tolist()}
            value["beta"] = {n: row[f"beta:{n}"] for n in names}
            value["belief"] = {n: row[f"belief:{n}"] for n in names}
            writer.write(state, ns + 1_000_000, STORE.serialize_cdr(text(value), state.msgtype))
    return path


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_imports_into_a_dataset_that_builds(tmp_path, trial, storage, capsys):
    bag = write_bag(tmp_path / "bag", trial, storage=storage)
    raw = tmp_path / "raw"
    assert main(["import", "rosbag", str(bag), "--out", str(raw)]) == 0
    meta, frame = read_trial(raw / "P02" / "known_goal_no_misspecification_CASA")
    assert (meta["task"], meta["method"], meta["participant"]) == ("known_goal", "CASA", "P02")
    expected = trial.frame
    assert len(frame) == len(expected)
    # The kinematics' tool point is pybullet's within a millimetre.
    position = ["x", "y", "z"]
    assert np.abs(frame[position].to_numpy() - expected[position].to_numpy()).max() < 1e-3
    assert frame["keys"].tolist() == expected["keys"].tolist()
    assert np.allclose(frame["alpha"], expected["alpha"])
    assert np.allclose(frame["beta:green"], expected["beta:green"])
    capsys.readouterr()
    assert main(["validate", str(raw)]) == 0
    assert main(["process", str(raw), "--out", str(tmp_path / "processed")]) == 0
    trials = pd.read_csv(tmp_path / "processed" / "trials.csv")
    assert bool(trials["success"].iloc[0])


@pytest.mark.parametrize("user_as", ["twist_stamped", "state"])
def test_the_users_keys_from_a_twist_stamped_or_the_assistants_state(tmp_path, trial, user_as):
    bag = write_bag(tmp_path / "bag", trial, user_as=user_as)
    raw = tmp_path / "raw"
    assert main(["import", "rosbag", str(bag), "--out", str(raw)]) == 0
    _, frame = read_trial(raw / "P02" / "known_goal_no_misspecification_CASA")
    assert frame["keys"].tolist() == trial.frame["keys"].tolist()
    assert set(frame["keys"]) != {""}


def test_options_give_and_override_the_metadata(tmp_path, trial):
    bag = write_bag(tmp_path / "bag", trial, meta=False)
    raw = tmp_path / "raw"
    args = ["import", "rosbag", str(bag), "--out", str(raw), "--participant", "P05"]
    assert (
        main([*args, "--task", "known_goal", "--method", "PBA", "--phase", "no_misspecification"])
        == 0
    )
    meta, _ = read_trial(raw / "P05" / "known_goal_no_misspecification_PBA")
    assert meta["method"] == "PBA" and meta["source"] == "human"


def refused(capsys, argv) -> str:
    assert main(argv) == 2
    return capsys.readouterr().err


def test_a_bag_without_its_metadata_names_the_missing_keys(tmp_path, trial, capsys):
    bag = write_bag(tmp_path / "bag", trial, meta=False)
    err = refused(capsys, ["import", "rosbag", str(bag), "--out", str(tmp_path / "raw")])
    assert "no participant, task, method, phase" in err and "--participant" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_truncated_bag_is_refused(tmp_path, trial, storage, capsys):
    bag = write_bag(tmp_path / "bag", trial, storage=storage)
    data = next(p for p in bag.iterdir() if p.suffix in (".db3", ".mcap"))
    data.write_bytes(data.read_bytes()[: data.stat().st_size // 2])
    err = refused(capsys, ["import", "rosbag", str(bag), "--out", str(tmp_path / "raw")])
    assert f"casa import rosbag: {bag}" in err and "Traceback" not in err
    assert not (tmp_path / "raw").exists()


def test_a_bad_message_is_named_by_topic_and_number(tmp_path, trial, capsys):
    def spoil(index, q):
        q = q.copy()
        if index == 6:
            q[2] = np.nan
        return joint_state(EPOCH, q)

    bag = write_bag(tmp_path / "bag", trial, spoil=spoil)
    err = refused(capsys, ["import", "rosbag", str(bag), "--out", str(tmp_path / "raw")])
    assert "topic 'joint_states', message 7" in err or "topic '/joint_states', message 7" in err
    assert "non-finite position of joint_3" in err


def test_missing_joints_and_a_wrong_type_are_named(tmp_path, trial, capsys):
    bag = write_bag(
        tmp_path / "a", trial, spoil=lambda i, q: joint_state(EPOCH, q[:6], JOINT_NAMES[:6])
    )
    err = refused(capsys, ["import", "rosbag", str(bag), "--out", str(tmp_path / "raw")])
    assert "message 1" in err and "joints joint_7 missing" in err
    bag = write_bag(tmp_path / "b", trial, joint_type="std_msgs/msg/String")
    err = refused(capsys, ["import", "rosbag", str(bag), "--out", str(tmp_path / "raw")])
    assert "carries std_msgs/msg/String, expected sensor_msgs/msg/JointState" in err


def test_a_bag_without_joint_states_is_incomplete(tmp_path, capsys):
    with Writer(tmp_path / "bag", version=9) as writer:
        user = writer.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=STORE)
        writer.write(user, EPOCH, STORE.serialize_cdr(twist([0, 0, 0, 0]), user.msgtype))
    err = refused(capsys, ["import", "rosbag", str(tmp_path / "bag"), "--out", str(tmp_path / "r")])
    assert "has 0 message(s)" in err and "joint_states" in err
