"""``casa import rosbag``: a rosbag2 recording of ``casa ros2 assist`` as a casa-trial/1 trial."""

from __future__ import annotations

import sys

from casa_core import vocabulary
from casa_core.cli._options import example


def register_rosbag(formats) -> None:
    """Add ``casa import rosbag`` to the formats of ``casa import``."""
    rosbag = formats.add_parser(
        "rosbag",
        help="a rosbag2 recording (sqlite3 or MCAP) of joint_states, cmd_vel and casa/state",
        description="Convert one recorded trial (BAG, a rosbag2 folder, only read) into "
        "OUT/<participant>/<task>_<phase>_<method>.json and .csv: one row per 20 Hz tick "
        "from the first joint state to the last (docs/ros2.md). Task, method, phase and "
        "participant come from the recorded casa/trial topic, each overridden by its "
        "option. A damaged or incomplete bag exits 2 naming the topic and the message; "
        "nothing is written then. Needs the ros2 extra (rosbags).",
        **example("casa import rosbag bags/P01_known_goal --out data/raw/lab"),
    )
    rosbag.add_argument("bag", metavar="BAG", help="the rosbag2 folder")
    rosbag.add_argument("--out", required=True, metavar="DIR", help="the dataset folder")
    recorded = "(default: the recorded casa/trial topic's)"
    rosbag.add_argument("--participant", metavar="ID", help=f"participant id {recorded}")
    rosbag.add_argument("--task", choices=vocabulary.TASKS, help=f"the task {recorded}")
    rosbag.add_argument("--method", choices=vocabulary.METHODS, help=f"the method {recorded}")
    rosbag.add_argument("--phase", choices=vocabulary.PHASES, help=f"the phase {recorded}")
    rosbag.add_argument("--source", choices=vocabulary.SOURCES, help="default: human")
    for role, default in (
        ("joint-states", "joint_states"),
        ("user-command", "cmd_vel"),
        ("state", "casa/state"),
        ("trial", "casa/trial"),
    ):
        rosbag.add_argument(
            f"--{role}-topic", metavar="TOPIC", help=f"(default: the recorded {default})"
        )
    rosbag.add_argument("--force", action="store_true", help="replace the trial if there")
    rosbag.set_defaults(func=_import_rosbag)


def _import_rosbag(args) -> int:
    try:
        import rosbags  # noqa: F401
    except ImportError as error:
        from casa_core.cli.ros2 import INSTALL

        print(
            f"casa import rosbag: rosbags is not installed ({error}); install it with: {INSTALL}",
            file=sys.stderr,
        )
        return 2
    from casa_core.io import CONDITION_KEYS, LogError
    from casa_core.ros2.bag import BagError, import_bag

    topics = {
        "joint_states": args.joint_states_topic,
        "user_command": args.user_command_topic,
        "state": args.state_topic,
        "trial": args.trial_topic,
    }
    meta = {key: getattr(args, key) for key in CONDITION_KEYS}
    meta["source"] = args.source
    try:
        stem = import_bag(args.bag, args.out, force=args.force, topics=topics, meta=meta)
    except (BagError, LogError) as error:
        print(f"casa import rosbag: {error}", file=sys.stderr)
        return 2
    print(f"casa import rosbag: wrote {stem}.json and {stem}.csv")
    return 0
