"""``casa learn``: a new intent learned from demonstration logs, into an intent library."""

from __future__ import annotations

import sys

from casa_core import vocabulary
from casa_core.cli._options import example, nonnegative_int, positive_int, scene_option


def register(commands) -> None:
    """Add ``casa learn`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "learn",
        help="learn a new intent from demonstration logs (deep MaxEnt IRL) into a library",
        description="Read the demonstration logs (casa-trial/1) below --demos, learn intent "
        "NAME by deep maximum-entropy IRL and write NAME.intent.json into the library folder.",
        **example(
            "casa learn --demos data/raw/mine/p01 --task unknown_goal --name learned_red "
            "--library intents/p01"
        ),
    )
    command.add_argument("--demos", required=True, metavar="DIR", help="folder of demo logs")
    command.add_argument("--name", required=True, help="name of the new intent")
    command.add_argument("--library", required=True, metavar="DIR", help="the intent library")
    scene_option(command)
    command.add_argument(
        "--seed", type=nonnegative_int, default=0, help="seed of the network (default 0)"
    )
    command.add_argument(
        "--task", choices=vocabulary.TASKS, help="only the logs of this task (default: all)"
    )
    command.add_argument(
        "--phase",
        default="demonstration",
        choices=(*vocabulary.PHASES, "any"),
        help="only the logs of this phase (default: demonstration; 'any' for all)",
    )
    command.add_argument("--participant", help="stored participant (default: from the logs)")
    command.add_argument(
        "--max-iterations", type=positive_int, metavar="N", help="most IRL iterations (default 30)"
    )
    command.set_defaults(func=_learn)


def _learn(args) -> int:
    from casa_core.io import LogError
    from casa_core.learning import IRLConfig, kept_record, stop_reason
    from casa_core.scene import load_scene
    from casa_core.study.learn_from_logs import learn_to_library
    from casa_core.study.learning_evidence import scene_objects

    config = IRLConfig()
    if args.max_iterations is not None:
        # Fewer iterations than the convergence test waits for: it waits for all of them.
        most = args.max_iterations
        config = IRLConfig(max_iterations=most, min_iterations=min(config.min_iterations, most))
    try:
        path, history, seconds = learn_to_library(
            args.demos,
            args.name,
            library=args.library,
            objects=scene_objects(load_scene(args.scene)),
            seed=args.seed,
            task=args.task,
            participant=args.participant,
            config=config,
            phase=None if args.phase == "any" else args.phase,
        )
    except (OSError, ValueError, LogError) as error:
        print(f"casa learn: {error}", file=sys.stderr)
        return 1
    # The words of casa library list: why training stopped, and the intent the file keeps.
    kept = kept_record(history) or history[-1]
    match = kept.get("verified_match")
    ends = "" if match is None else f" (end_match_m={match:.4f})"
    print(
        f"casa learn: {args.name}: {len(history)} iterations in {seconds:.1f} s, "
        f"stopped={stop_reason(history)}; kept iteration {kept['iteration']}{ends} -> {path}"
    )
    return 0
