"""``casa simulate``: participants of the simulated study, one workflow job per call."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from casa_core import vocabulary
from casa_core.cli._options import counted, example, positive_int
from casa_core.cli._workflow import add_config_option, load_workflow_config

if TYPE_CHECKING:
    from casa_core.scene import Scene


def register(commands) -> None:
    """Add ``casa simulate`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "simulate",
        help="simulate one participant of the study (one stage, or the whole protocol)",
        description="One stage of one simulated participant, as the workflow runs it "
        "(workflow/rules/study.smk; the workflow chains the stages), or its whole protocol "
        "in one call (protocol: the files of before, learn of each unknown task and after), "
        "of one participant or of several in turn, paying the process's start-up once "
        "(workflow/rules/power.smk: a replicate's participants): then every path holds "
        "{p}, which is replaced by each participant's number.",
        **example(
            "casa simulate before --participant 1 --out data/raw/simulated/p1/before",
            "casa simulate protocol --participant 1 --before raw/p1/before --library intents/p1 \\",
            "    --rows learning/p1_unknown_goal.csv learning/p1_unknown_skill.csv \\",
            "    --out raw/p1/after",
            "casa simulate protocol --participant 1 2 3 --before 'raw/p{p}/before' \\",
            "    --library 'intents/p{p}' --rows 'learning/p{p}_unknown_goal.csv' \\",
            "    'learning/p{p}_unknown_skill.csv' --out 'raw/p{p}/after'",
        ),
    )
    command.add_argument(
        "stage",
        choices=["before", "learn", "after", "protocol", "learning-table"],
        help="before: phases 1-3 and demonstrations; learn: one unknown "
        "task's intent; after: CASA after learning and the surveys; protocol: the three, "
        "each unknown task learned; learning-table: gather the learn rows into one CSV",
    )
    add_config_option(command)
    command.add_argument(
        "--participant",
        type=positive_int,
        nargs="+",
        default=[1],
        metavar="INDEX",
        help="1-based participant number; protocol: one or more, the paths then holding {p}",
    )
    _add_learning_tables(command)
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


def _add_learning_tables(command) -> None:
    """Add the options of the learn rows and their training times, per unknown task."""
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
        if problem := _participant_paths_problem(args):
            print(f"casa simulate protocol: {problem}", file=sys.stderr)
            return 2
    elif len(args.participant) > 1:
        print(
            f"casa simulate {args.stage}: takes one --participant (protocol takes several)",
            file=sys.stderr,
        )
        return 2
    try:
        return _run_stage(args)
    except (LogError, OSError, ValueError) as error:
        # A damaged intent file (LibraryError, a ValueError) or log names itself and its rule.
        print(f"casa simulate {args.stage}: {error}", file=sys.stderr)
        return 2


#: The placeholder of a participant's number in the paths of a protocol of several.
PARTICIPANT_FIELD = "{p}"


def _participant_paths_problem(args) -> str | None:
    """Why the protocol's paths cannot keep each participant's files apart, or None."""
    paths = {"--before": [args.before], "--out": [args.out], "--library": [args.library]}
    paths |= {"--rows": args.rows, "--timing-rows": args.timing_rows}
    if len(set(args.participant)) != len(args.participant):
        return f"--participant names a participant twice: {args.participant}"
    if len(args.participant) == 1:
        return None
    for option, values in paths.items():
        for value in values:
            if PARTICIPANT_FIELD not in value:
                return (
                    f"{option} {value}: with several participants every path holds "
                    f"{PARTICIPANT_FIELD}, the participant's number, so that their files "
                    "stay apart"
                )
    return None


def _for_participant(path: str, number: int) -> str:
    return path.replace(PARTICIPANT_FIELD, str(number))


def _run_stage(args) -> int:
    from pathlib import Path

    import numpy as np
    import pandas as pd

    from casa_core.io.atomic import write_csv
    from casa_core.io.contract import SURVEYS_NAME
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
    config, scene = load_workflow_config(args)
    settings = StudySettings.from_config(config)
    if args.stage == "protocol":
        runs = [_protocol(args, number, scene, settings=settings) for number in args.participant]
        total = [(sum(run[i][0] for run in runs), what) for i, (_, what) in enumerate(runs[0])]
        ids = ", ".join(simulate.participant_id(number - 1) for number in args.participant)
        who = "participants" if len(runs) > 1 else "participant"
        print(f"casa simulate protocol: {who} {ids}, {counted(total)} written")
        return 0
    index = args.participant[0] - 1
    pid = simulate.participant_id(index)
    # What the stage wrote, each count named: a trial is a .json and a .csv.
    written: list[tuple[int, str]]
    if args.stage == "before":
        trials = simulate.simulate_before_learning(
            index, scene, settings=settings, out_dir=Path(args.out)
        )
        written = [(len(trials), "trial(s)")]
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
        if args.timing:
            write_csv(args.timing, pd.DataFrame([timing]))
        learned = int(not np.isnan(timing["train_seconds"]))  # NaN: no demonstrations
        written = [(learned, "learned intent(s)"), (1 + bool(args.timing), "table(s)")]
    else:
        learned_files = sorted(Path(args.library).rglob("*.intent.json"))
        trials = simulate.simulate_after_learning(
            index,
            scene,
            settings=settings,
            learned=learned_files,
            before_dir=Path(args.before),
            out_dir=Path(args.out),
        )
        written = [(len(trials), "trial(s)"), (1, SURVEYS_NAME)]
    print(f"casa simulate {args.stage}: participant {pid}, {counted(written)} written")
    return 0


def _protocol(args, number: int, scene: Scene, *, settings) -> list[tuple[int, str]]:
    """``casa simulate protocol`` of participant ``number`` (1-based), its paths with
    :data:`PARTICIPANT_FIELD` replaced: every folder is filled aside and renamed when all
    are done.

    Returns what was written, each count named (:func:`casa_core.cli._options.counted`).
    """
    from pathlib import Path

    import pandas as pd

    from casa_core.io.atomic import atomic_folders, write_csv
    from casa_core.io.contract import SURVEYS_NAME
    from casa_core.study import simulate

    def own(template: str) -> Path:
        return Path(_for_participant(template, number))

    tasks = vocabulary.UNKNOWN_TASKS
    library = own(args.library)
    folders = [own(args.before), own(args.out), *(library / task for task in tasks)]
    with atomic_folders(*folders) as (before, after, *libraries):
        run = simulate.simulate_protocol(
            number - 1,
            scene,
            settings=settings,
            before_dir=before,
            after_dir=after,
            libraries=dict(zip(tasks, libraries, strict=True)),
        )
    tables = [*zip(map(own, args.rows), run.rows, strict=True)]
    if args.timing_rows:
        tables += zip(map(own, args.timing_rows), run.timings, strict=True)
    for path, row in tables:
        write_csv(path, pd.DataFrame([row]))
    trials = len(run.before) + len(run.after)
    return [
        (trials, "trial(s)"),
        (len(run.learned), "learned intent(s)"),
        (1, SURVEYS_NAME),
        (len(tables), "table(s)"),
    ]
