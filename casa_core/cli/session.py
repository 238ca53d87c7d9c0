"""``casa session``: one real participant's whole protocol in one window (docs/session.md)."""

from __future__ import annotations

import sys

from casa_core.cli._options import example, input_options, open_input_device, scene_option
from casa_core.cli._workflow import add_config_option


def register(commands) -> None:
    """Add ``casa session`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "session",
        help="run one participant's whole study in one window: practice, every task and "
        "method, demonstrations, learning, the questionnaire; resumes where it stopped",
        description="Runs the paper's protocol for one participant in one pybullet window "
        "(docs/session.md): familiarization, Known Goal, Unknown Goal and Unknown Skill "
        "with the three methods under neutral labels (robot A, B, C), the demonstrations, "
        "learning while the participant rests, then the unknown tasks after learning; the "
        "7-point questions after each condition. The method order is counterbalanced from "
        "the number the participant id ends in, as in the simulated study. Logs go to "
        "OUT/<participant>/ (casa-trial/1 and surveys.csv), each written when complete; "
        "the same command again resumes at the first step not recorded. P pauses (Escape "
        "closes pybullet's window: it is reopened, paused).",
        **example("casa session --participant P07 --out data/raw/mylab"),
    )
    command.add_argument("--participant", required=True, metavar="ID", help="e.g. P07")
    command.add_argument(
        "--out", required=True, metavar="DIR", help="the dataset's folder, e.g. data/raw/mylab"
    )
    add_config_option(
        command,
        "workflow config whose session, simulation (demonstrations, demonstrations_when, "
        "epsilon, seed) and inference blocks are used",
    )
    scene_option(command)
    input_options(command, default=None)
    command.add_argument(
        "--quiet",
        action="store_true",
        help="keep the blinding on the console too: the method order and each trial's method "
        "go to the session log (OUT/<participant>/.session/session.log) only",
    )
    command.set_defaults(func=_session)


def _session(args) -> int:
    from dataclasses import replace
    from pathlib import Path

    import torch

    from casa_core.config import load_config
    from casa_core.io import LogError
    from casa_core.scene import DEFAULT_SCENE, load_scene
    from casa_core.study.session import SessionSettings
    from casa_core.study.session_run import COMPLETE, run_session

    torch.set_num_threads(1)  # the window's renderer keeps a core; learning is single-threaded
    # Paths given are the user's, from the working directory; the defaults are the
    # package's own (its config's defaults, its scene), so the command works from any folder.
    config = load_config(*(args.config or ()))
    scene_path = Path(args.scene) if args.scene else DEFAULT_SCENE
    scene = load_scene(scene_path)  # a SceneError is reported by casa_core.cli.main
    settings = SessionSettings.from_config(config)
    if args.input is not None:
        settings = replace(settings, input=args.input)
    device = None
    try:
        device = open_input_device(
            settings.input, deadzone=settings.deadzone, trace=args.device_trace
        )
        outcome = run_session(
            scene,
            args.participant,
            Path(args.out),
            settings=settings,
            scene_source=scene_path,
            quiet=args.quiet,
            device=device,
        )
    except (FileExistsError, LogError, RuntimeError, ValueError) as error:
        print(f"casa session: {error}", file=sys.stderr)
        return 2
    finally:
        if device is not None:
            device.close()
    if outcome == COMPLETE:
        print(f"casa session: participant {args.participant} complete in {args.out}")
    else:
        print(
            f"casa session: stopped; what was recorded is kept. Run the same command again "
            f"to continue: casa session --participant {args.participant} --out {args.out}"
        )
    return 0
