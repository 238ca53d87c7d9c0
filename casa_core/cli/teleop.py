"""``casa teleop``: drive the simulated arm from the keyboard or a device in a window; write
the log."""

from __future__ import annotations

import sys

from casa_core import vocabulary
from casa_core.cli._options import (
    example,
    input_options,
    learned_intent_option,
    nonnegative_float,
    nonnegative_int,
    open_input_device,
    positive_float,
    scene_option,
    trial_options,
)
from casa_core.robot.devices import DEADZONE


def register(commands) -> None:
    """Add ``casa teleop`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "teleop",
        help="drive the simulated JACO arm from the keyboard (or a gamepad or SpaceMouse) in a "
        "window; write the trial log",
        description="Open a pybullet window with the task scene; after a countdown, drive the "
        "cup with the arrows (x, y), W/S (z) and A/D (pour); Enter ends the trial. The log "
        "goes to OUT/<task>_<phase>_<method>.{json,csv} (casa-trial/1).",
        **example(
            "casa teleop --task known_goal --method CASA --participant p01 --out data/raw/mine/p01"
        ),
    )
    trial_options(command)
    scene_option(command)
    command.add_argument(
        "--teleop-mode",
        choices=vocabulary.TELEOP_MODES,
        help="how the keys move the arm (docs/departures.md): the tool orientation held, or "
        "the original implementation's position-only IK of link 7 (default: the scene's)",
    )
    command.add_argument(
        "--max-duration",
        type=positive_float,
        default=60.0,
        metavar="SECONDS",
        help="end the trial after this long, done or not (default %(default)g)",
    )
    input_options(command, default="keyboard")
    command.add_argument(
        "--deadzone",
        type=nonnegative_float,
        default=DEADZONE,
        help="a device's deadzone, a share of full deflection (default %(default)g)",
    )
    _add_assistant_options(command)
    command.set_defaults(func=_teleop)


def _add_assistant_options(command) -> None:
    """Add the options of the assistant: its intents, demonstrations and inference."""
    # The model's defaults, written once in the assistant.
    from casa_core.assist.presets import DEFAULT_PRESET
    from casa_core.defaults import DEMONSTRATIONS, EPSILON

    learned_intent_option(command)
    command.add_argument(
        "--demonstrations",
        type=nonnegative_int,
        default=DEMONSTRATIONS,
        metavar="N",
        help="after a CASA trial before learning that finds every known intent's confidence "
        "below --epsilon, ask for and record N demonstrations (default %(default)s; 0: never)",
    )
    command.add_argument(
        "--epsilon",
        type=positive_float,
        default=EPSILON,
        help="misspecification threshold (default %(default)s)",
    )
    command.add_argument(
        "--preset",
        choices=vocabulary.PRESET_NAMES,
        default=DEFAULT_PRESET,
        help="how the assistant infers (docs/departures.md): this project's choices, the "
        "original implementation's or the paper's as written (default %(default)s)",
    )
    command.add_argument(
        "--evidence",
        choices=vocabulary.EVIDENCE,
        help="what inference observes, over the preset's choice: the user's commanded motion "
        "or the arm's executed motion, the robot's share included",
    )


def _teleop(args) -> int:
    from casa_core.assist.presets import preset
    from casa_core.scene import load_scene
    from casa_core.study.closed_loop import trial_intents
    from casa_core.study.teleop_session import teleop_session

    # A SceneError is reported by casa_core.cli.main.
    scene = load_scene(args.scene).with_teleop_mode(args.teleop_mode)
    inference = preset(args.preset, evidence=args.evidence)
    device = None
    try:
        device = open_input_device(args.input, deadzone=args.deadzone, trace=args.device_trace)
        stems, detected = teleop_session(
            scene,
            args.task,
            args.method,
            args.participant,
            args.out,
            n_demonstrations=args.demonstrations,
            epsilon=args.epsilon,
            phase=args.phase,
            max_duration=args.max_duration,
            intents=trial_intents(scene, args.intent, inference=inference),
            inference=inference,
            device=device,
            input=args.input,
        )
    except (FileExistsError, RuntimeError, ValueError) as error:
        print(f"casa teleop: {error}", file=sys.stderr)
        return 2
    finally:
        if device is not None:
            device.close()
    for stem in stems:
        print(f"casa teleop: wrote {stem}.json and {stem}.csv")
    if detected:
        print(
            f"casa teleop: misspecification detected; {len(stems) - 1} demonstrations "
            f"recorded. Learn the new intent with: casa learn --demos {args.out} "
            f"--task {args.task} --name NAME --library DIR"
        )
    return 0
