"""``casa ros2``: the assistant and the simulated arm as ROS 2 nodes (docs/ros2.md).

rclpy and the message packages come with the ``ros2`` extra; without them each command
says how to install it and exits 2. Only these handlers import them, so the rest of
``casa`` runs without the extra.
"""

from __future__ import annotations

import sys

from casa_core import vocabulary
from casa_core.cli._options import (
    example,
    learned_intent_option,
    positive_float,
    scene_option,
    trial_options,
)
from casa_core.ros2.parameters import PARAMETERS

#: What to run when the ROS 2 packages are missing.
INSTALL = 'pip install -e ".[ros2]"'
#: The longest trial a node records unless told (s): the scene's trials last under a minute.
DEFAULT_DURATION = 3600.0


def register(commands) -> None:
    """Add ``casa ros2 sim`` and ``casa ros2 assist`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "ros2",
        help="run the assistant or the simulated arm as ROS 2 nodes (needs the ros2 extra)",
        **example(
            "casa ros2 sim",
            "casa ros2 assist --task known_goal --method CASA "
            "--participant P01 --out data/raw/lab/P01 --duration 60",
        ),
    )
    nodes = command.add_subparsers(dest="node", metavar="NODE", required=True)
    _add_sim(nodes)
    _add_assist(nodes)


def _add_sim(nodes) -> None:
    """Add ``casa ros2 sim``: the simulated arm's node."""
    sim = nodes.add_parser(
        "sim",
        help="the pybullet JACO behind joint_states and velocity_controller/commands",
        description="Publishes the simulated JACO's seven joints on joint_states "
        "(sensor_msgs/JointState, 20 Hz) and drives them with the joint velocities (rad/s) "
        "of velocity_controller/commands (std_msgs/Float64MultiArray). A command older than "
        "0.25 s is not acted on: the arm holds still.",
        **example("casa ros2 sim --remap joint_states:=/arm/joint_states"),
    )
    scene_option(sim)
    _common(sim)
    sim.set_defaults(func=_sim)


def _add_assist(nodes) -> None:
    """Add ``casa ros2 assist``: the assistant's node, which records the trial."""
    assist = nodes.add_parser(
        "assist",
        help="the assistant on joint_states and cmd_vel; blended joint velocities out; "
        "records the trial",
        description="Takes the arm's joint_states (sensor_msgs/JointState) and the user's "
        "cmd_vel (geometry_msgs/Twist: linear x, y, z in m/s in the base frame, angular z "
        "the wrist turn in rad/s; or TwistStamped, or sensor_msgs/Joy on joy, by the "
        "user_input parameter), publishes the blended joint velocities on "
        "velocity_controller/commands (and, with twist_output, a TwistStamped on "
        "servo_node/delta_twist_cmds) on each user command and at 20 Hz, and the "
        "assistant's state on casa/state (std_msgs/String, JSON). Writes "
        "OUT/<task>_<phase>_<method>.json and .csv (casa-trial/1) at --duration or on "
        "SIGINT. Parameters (docs/ros2.md): " + ", ".join(PARAMETERS) + ".",
        **example(
            "casa ros2 assist --task known_goal --method CASA --participant P01 "
            "--out data/raw/lab/P01 --duration 60"
        ),
    )
    from casa_core.assist.presets import DEFAULT_PRESET

    trial_options(assist)
    assist.add_argument(
        "--preset",
        choices=vocabulary.PRESET_NAMES,
        default=DEFAULT_PRESET,
        help="the inference settings (docs/departures.md) (default %(default)s)",
    )
    learned_intent_option(assist)
    assist.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME:=VALUE",
        help="set a node parameter, as ros2 run's -p does; repeatable",
    )
    assist.add_argument(
        "--params-file",
        metavar="YAML",
        help="a ROS 2 parameters file (section casa_assist or /**)",
    )
    scene_option(assist)
    _common(assist)
    assist.set_defaults(func=_assist)


def _common(command) -> None:
    """Add the options both nodes take: how long they run and the topics' names."""
    command.add_argument(
        "--duration",
        type=positive_float,
        default=DEFAULT_DURATION,
        metavar="SECONDS",
        help="stop after this long (default %(default)g; SIGINT stops it too)",
    )
    command.add_argument(
        "--remap",
        action="append",
        default=[],
        metavar="FROM:=TO",
        help="rename a topic, as ros2 run's -r does; repeatable",
    )


def ros2_missing(command: str) -> str | None:
    """Why the ROS 2 packages cannot be loaded (and how to install them), or None."""
    try:
        import geometry_msgs.msg  # noqa: F401
        import rclpy  # noqa: F401
        import sensor_msgs.msg  # noqa: F401
        import std_msgs.msg  # noqa: F401
    except ImportError as error:
        return (
            f"casa {command}: the ROS 2 packages are not installed ({error}); install them "
            f"with: {INSTALL}"
        )
    return None


def _check(args) -> int | None:
    bad = [remap for remap in args.remap if ":=" not in remap]
    if bad:
        print(f"casa ros2: --remap {bad[0]!r} is not FROM:=TO", file=sys.stderr)
        return 2
    missing = ros2_missing(f"ros2 {args.node}")
    if missing:
        print(missing, file=sys.stderr)
        return 2
    return None


def _sim(args) -> int:
    if (status := _check(args)) is not None:
        return status
    from casa_core.ros2.nodes import run_sim
    from casa_core.scene import load_scene

    return run_sim(load_scene(args.scene), remaps=args.remap, duration=args.duration)


def _assist(args) -> int:
    if (status := _check(args)) is not None:
        return status
    from pathlib import Path

    from casa_core.assist.presets import preset
    from casa_core.io import LogError, trial_files
    from casa_core.ros2.loop import AssistLoop
    from casa_core.ros2.nodes import run_assist
    from casa_core.ros2.parameters import ParameterError, check_overrides
    from casa_core.ros2.stats import LoopStats
    from casa_core.scene import load_scene
    from casa_core.study.closed_loop import default_phase

    scene = load_scene(args.scene)  # a SceneError is reported by casa_core.cli.main
    try:
        check_overrides(args.param, args.params_file)
        phase = args.phase or default_phase(args.task)
    except (ParameterError, ValueError) as error:
        print(f"casa ros2 assist: {error}", file=sys.stderr)
        return 2
    stem = Path(args.out) / f"{args.task}_{phase}_{args.method}"
    existing = [path for path in trial_files(stem) if path.exists()]
    if existing:
        print(f"casa ros2 assist: {existing[0]} exists; not replaced", file=sys.stderr)
        return 2
    ros_args = [part for param in args.param for part in ("-p", param)]
    ros_args += ["--params-file", str(args.params_file)] if args.params_file else []

    def make_loop(parameters) -> AssistLoop:
        return AssistLoop(
            scene,
            task=args.task,
            method=args.method,
            participant=args.participant,
            phase=phase,
            inference=preset(args.preset),
            learned=args.intent,
            max_duration=args.duration,
            max_command_age=parameters.max_command_age,
            max_joint_state_age=parameters.max_joint_state_age,
        )

    stats = LoopStats()
    try:
        loop = run_assist(
            make_loop, remaps=args.remap, ros_args=ros_args, duration=args.duration, stats=stats
        )
    except ValueError as error:  # a parameter, a learned intent or a trial casa-trial/1 refuses
        print(f"casa ros2 assist: {error}", file=sys.stderr)
        return 2
    print(f"casa ros2 assist: {stats.text()}")
    try:
        loop.result().write(stem)
    except LogError as error:
        print(f"casa ros2 assist: the trial cannot be written: {error}", file=sys.stderr)
        return 2
    print(f"casa ros2 assist: wrote {stem}.json and {stem}.csv")
    return 0
