"""``casa simulate`` and ``casa case-study``: the simulated study, one workflow job per call."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from casa_core import vocabulary
from casa_core.cli._options import example, positive_int

if TYPE_CHECKING:
    from casa_core.scene import Scene

#: The config the workflow commands read when no --config is given (working directory).
WORKFLOW_CONFIG = "config/config.yaml"


def register(commands) -> None:
    """Add this module's commands to the ``casa`` subcommands."""
    _add_simulate(commands)
    _add_case_study(commands)


def _load_config(args) -> tuple[dict, Scene]:
    """The validated workflow config (``--config``, repeatable) and the scene it names.

    Read once, here, at the edge; a ConfigError or SceneError names the file and the key.
    """
    from casa_core.config import load_config
    from casa_core.scene import load_scene

    config = load_config(*(args.config or [WORKFLOW_CONFIG]))
    return config, load_scene(config["scene"])


def _add_config_option(command) -> None:
    command.add_argument(
        "--config",
        action="append",
        metavar="YAML",
        help=f"workflow config (default {WORKFLOW_CONFIG}); repeat to overlay files in order, "
        "e.g. --config config/config.yaml --config config/ci.yaml",
    )


def _add_simulate(commands) -> None:
    command = commands.add_parser(
        "simulate",
        help="simulate one participant of the study (one stage, or the whole protocol)",
        description="One stage of one simulated participant, as the workflow runs it "
        "(workflow/rules/study.smk; the workflow chains the stages), or its whole protocol "
        "in one call (protocol: the files of before, learn of each unknown task and after; "
        "workflow/rules/power.smk).",
        **example(
            "casa simulate before --config config/config.yaml --participant 1 "
            "--out data/raw/simulated/p1/before",
            "casa simulate protocol --participant 1 --before raw/p1/before --library intents/p1 \\",
            "    --rows learning/p1_unknown_goal.csv learning/p1_unknown_skill.csv \\",
            "    --out raw/p1/after",
        ),
    )
    command.add_argument(
        "stage",
        choices=["before", "learn", "after", "protocol", "learning-table"],
        help="before: phases 1-3 and demonstrations; learn: one unknown "
        "task's intent; after: CASA after learning and the surveys; protocol: the three, "
        "each unknown task learned; learning-table: gather the learn rows into one CSV",
    )
    _add_config_option(command)
    command.add_argument(
        "--participant",
        type=positive_int,
        default=1,
        metavar="INDEX",
        help="1-based participant number",
    )
    tasks = " ".join(vocabulary.UNKNOWN_TASKS)
    command.add_argument(
        "--rows",
        nargs="*",
        default=[],
        help=f"learning-table: learn CSVs; protocol: the learn CSV to write of each unknown "
        f"task, in the order {tasks}",
    )
    command.add_argument(
        "--timing-rows",
        nargs="*",
        default=[],
        help="learning-table: learn timing CSVs; protocol: the timing CSV to write of each "
        "unknown task, in the same order",
    )
    command.add_argument(
        "--timing",
        help="learn: the CSV of its measured training time; learning-table: the timing table",
    )
    command.add_argument(
        "--out", required=True, help="folder (before, after; protocol: the after one) or CSV"
    )
    command.add_argument(
        "--before", help="the participant's before-learning folder (protocol: written)"
    )
    command.add_argument("--task", choices=vocabulary.UNKNOWN_TASKS, help="learn: task")
    command.add_argument(
        "--library",
        help="learn/after: the participant's intent library; protocol: the folder in which "
        "each unknown task's intent goes to its own <task> folder",
    )
    command.set_defaults(func=_simulate)


#: The options each stage needs besides --out.
STAGE_OPTIONS = {
    "learn": ("before", "task", "library"),
    "after": ("before", "library"),
    "protocol": ("before", "library", "rows"),
}


def _simulate(args) -> int:
    from casa_core.io import LogError

    missing = [f"--{name}" for name in STAGE_OPTIONS.get(args.stage, ()) if not getattr(args, name)]
    if missing:
        print(f"casa simulate {args.stage}: needs {', '.join(missing)}", file=sys.stderr)
        return 2
    if args.stage == "protocol":
        tasks = len(vocabulary.UNKNOWN_TASKS)
        for option, paths in (("--rows", args.rows), ("--timing-rows", args.timing_rows)):
            if paths and len(paths) != tasks:
                print(
                    f"casa simulate protocol: {option} needs one CSV per unknown task "
                    f"({', '.join(vocabulary.UNKNOWN_TASKS)}), got {len(paths)}",
                    file=sys.stderr,
                )
                return 2
    try:
        return _run_stage(args)
    except (LogError, OSError, ValueError) as error:
        # A damaged intent file (LibraryError, a ValueError) or log names itself and its rule.
        print(f"casa simulate {args.stage}: {error}", file=sys.stderr)
        return 2


def _run_stage(args) -> int:
    from pathlib import Path

    import pandas as pd

    from casa_core.io.atomic import write_csv
    from casa_core.study import simulate
    from casa_core.study.settings import StudySettings

    if args.stage == "learning-table":
        from casa_core.io import read_table

        for paths, out in ((args.rows, args.out), (args.timing_rows, args.timing)):
            if out:
                rows = [read_table(path) for path in sorted(paths)]
                table = pd.concat(rows, ignore_index=True).sort_values(["participant", "task"])
                write_csv(out, table)
                print(f"casa simulate learning-table: {len(table)} learned intent(s) -> {out}")
        return 0
    config, scene = _load_config(args)
    settings = StudySettings.from_config(config)
    index = args.participant - 1
    pid = simulate.participant_id(index)
    if args.stage == "protocol":
        written = _protocol(args, index, scene, settings=settings)
    elif args.stage == "before":
        written = simulate.simulate_before_learning(
            index, scene, settings=settings, out_dir=Path(args.out)
        )
    elif args.stage == "learn":
        row, timing = simulate.learn_from_demonstrations(
            Path(args.before),
            args.task,
            scene=scene,
            seed=simulate.learning_seed(index, settings.seed),
            library=Path(args.library),
            pid=pid,
        )
        write_csv(args.out, pd.DataFrame([row]))
        written = [args.out]
        if args.timing:
            write_csv(args.timing, pd.DataFrame([timing]))
            written.append(args.timing)
    else:
        learned = sorted(Path(args.library).rglob("*.intent.json"))
        written = simulate.simulate_after_learning(
            index,
            scene,
            settings=settings,
            learned=learned,
            before_dir=Path(args.before),
            out_dir=Path(args.out),
        )
    print(f"casa simulate {args.stage}: participant {pid}, {len(written)} file(s)")
    return 0


def _protocol(args, index: int, scene: Scene, *, settings) -> list:
    """``casa simulate protocol``: every folder is filled aside and renamed when all are done."""
    from pathlib import Path

    import pandas as pd

    from casa_core.io.atomic import atomic_folders, write_csv
    from casa_core.study import simulate

    tasks = vocabulary.UNKNOWN_TASKS
    folders = [Path(args.before), Path(args.out), *(Path(args.library) / task for task in tasks)]
    with atomic_folders(*folders) as (before, after, *libraries):
        run = simulate.simulate_protocol(
            index,
            scene,
            settings=settings,
            before_dir=before,
            after_dir=after,
            libraries=dict(zip(tasks, libraries, strict=True)),
        )
    tables = [*zip(args.rows, run.rows, strict=True)]
    if args.timing_rows:
        tables += zip(args.timing_rows, run.timings, strict=True)
    for path, row in tables:
        write_csv(path, pd.DataFrame([row]))
    return [*run.before, *run.learned, *run.after, *(path for path, _ in tables)]


def _add_case_study(commands) -> None:
    command = commands.add_parser(
        "case-study",
        help="the expert case study and the arbitration comparison",
        description="Run the simulated expert through the tasks (learning included) and the "
        "three arbitrations along one trajectory; write steps.csv and arbitration.csv.",
        **example(
            "casa case-study --work data/interim/case_study "
            "--steps data/processed/case_study/steps.csv \\",
            "    --arbitration data/processed/case_study/arbitration.csv",
        ),
    )
    _add_config_option(command)
    command.add_argument("--work", required=True, help="folder for the expert's logs and intents")
    command.add_argument("--steps", required=True, help="steps.csv to write")
    command.add_argument("--arbitration", required=True, help="arbitration.csv to write")
    command.set_defaults(func=_case_study)


def _case_study(args) -> int:
    from pathlib import Path

    from casa_core.io import LogError
    from casa_core.io.atomic import write_csv
    from casa_core.study import simulate
    from casa_core.study.settings import StudySettings

    config, scene = _load_config(args)
    try:
        steps, arbitration = simulate.run_case_study(
            scene,
            StudySettings.from_case_study(config),
            work_dir=Path(args.work),
        )
    except (LogError, OSError, ValueError) as error:
        print(f"casa case-study: {error}", file=sys.stderr)
        return 2
    write_csv(args.steps, steps)
    write_csv(args.arbitration, arbitration)
    print(f"casa case-study: {len(steps)} step row(s), {len(arbitration)} arbitration row(s)")
    return 0
