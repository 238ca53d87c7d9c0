"""The ``casa`` command line: thin wrappers over the package."""

from __future__ import annotations

import argparse
import sys

from casa_core import __version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="casa",
        description="Confidence-Aware Shared Autonomy: simulation, study and analysis tools.",
    )
    parser.add_argument("--version", action="version", version=f"casa {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_validate(commands)
    _add_process(commands)
    _add_stats(commands)
    _add_teleop(commands)
    _add_bench(commands)
    _add_figure(commands)
    _add_learn(commands)
    _add_library(commands)
    _add_simulate(commands)
    _add_case_study(commands)
    return parser


def _add_validate(commands) -> None:
    command = commands.add_parser(
        "validate",
        help="check trial logs and surveys against the casa-trial/1 contract",
        description="Check files and folders (recursively) against casa-trial/1; print every "
        "problem with file, row or key, and rule; exit 1 if any (0 with --allow-invalid).",
    )
    command.add_argument("paths", nargs="+", metavar="PATH", help="a log file or a folder")
    command.add_argument("--report", metavar="CSV", help="also write validation.csv here")
    command.add_argument(
        "--allow-invalid",
        action="store_true",
        help="report bad files as excluded and exit 0 (the DAG then leaves them out)",
    )
    command.set_defaults(func=_validate)


def _validate(args) -> int:
    from casa_core import datasets, logs

    if args.report:
        checks = datasets.write_validation(
            args.paths, args.report, allow_invalid=args.allow_invalid
        )
    else:
        checks = logs.check_paths(args.paths)
    problems = [problem for check in checks for problem in check.problems]
    for problem in problems:
        print(problem, file=sys.stderr)
    verdict = "excluded" if args.allow_invalid else "invalid"
    bad_files = sum(not check.ok for check in checks)
    print(
        f"casa validate: {len(checks)} file(s) checked, {bad_files} {verdict}, "
        f"{len(problems)} problem(s)",
        file=sys.stderr,
    )
    return 1 if problems and not args.allow_invalid else 0


def _add_process(commands) -> None:
    command = commands.add_parser(
        "process",
        help="turn one raw dataset folder into trials.csv, steps.csv and likert.csv",
    )
    command.add_argument("raw", metavar="RAW_DIR", help="the dataset folder, e.g. data/raw/mine")
    command.add_argument("--out", required=True, metavar="DIR", help="folder of the tables")
    command.add_argument("--scene", required=True, metavar="YAML", help="config/scene.yaml")
    command.add_argument("--dataset", help="dataset name in the tables (default: folder name)")
    command.add_argument(
        "--allow-invalid", action="store_true", help="exclude bad files instead of failing"
    )
    command.set_defaults(func=_process)


def _process(args) -> int:
    import yaml

    from casa_core import datasets

    try:
        with open(args.scene, encoding="utf-8") as handle:
            scene = yaml.safe_load(handle)
    except (OSError, yaml.YAMLError) as error:
        print(f"casa process: cannot read the scene {args.scene}: {error}", file=sys.stderr)
        return 1
    try:
        tables = datasets.process_dataset(
            args.raw, args.out, scene, dataset=args.dataset, allow_invalid=args.allow_invalid
        )
    except datasets.DatasetInvalid as error:
        print(f"casa process: {error}", file=sys.stderr)
        return 1
    print(
        f"casa process: {len(tables.trials)} trial(s), {len(tables.steps)} step row(s), "
        f"{len(tables.likert)} Likert answer(s) -> {args.out}"
    )
    return 0


def _add_stats(commands) -> None:
    command = commands.add_parser(
        "stats",
        help="the study's statistics (H1-H4): stats.csv and an APA-style Markdown report",
    )
    command.add_argument("--trials", required=True, metavar="CSV", help="trials.csv")
    command.add_argument("--likert", metavar="CSV", help="likert.csv (optional)")
    command.add_argument("--out-csv", required=True, metavar="CSV", help="stats.csv to write")
    command.add_argument("--out-md", required=True, metavar="MD", help="report to write")
    command.set_defaults(func=_stats)


def _stats(args) -> int:
    from casa_core import datasets, logs, stats

    try:
        # read_table keeps the method "NA" as text (pandas' default would make it missing).
        trials = datasets.read_table(args.trials)
        likert = datasets.read_table(args.likert) if args.likert else None
        table = stats.analyze_study(trials, likert)
    except (OSError, ValueError) as error:
        print(f"casa stats: {error}", file=sys.stderr)
        return 1
    logs.atomic_write_text(args.out_csv, logs.frame_to_csv_text(table))
    logs.atomic_write_text(args.out_md, stats.report_markdown(table))
    # A test that ran has a p-value or an estimate; a skipped one has neither.
    skipped = int((table["p"].isna() & table["estimate"].isna()).sum())
    print(f"casa stats: {len(table)} row(s) -> {args.out_csv}, {args.out_md}")
    if skipped:
        print(f"casa stats: {skipped} test(s) skipped, see their note", file=sys.stderr)
    return 0


def _add_teleop(commands) -> None:
    command = commands.add_parser(
        "teleop",
        help="drive the simulated JACO arm from the keyboard in a window; write the trial log",
        description="Open a pybullet window with the task scene; after a countdown, drive the "
        "cup with the arrows (x, y), W/S (z) and A/D (pour); Enter ends the trial. The log "
        "goes to OUT/<task>_<phase>_<method>.{json,csv} (casa-trial/1).",
    )
    command.add_argument("--task", required=True, help="familiarization, known_goal, ...")
    command.add_argument("--method", required=True, help="NA, PBA or CASA")
    command.add_argument("--participant", required=True, metavar="ID")
    command.add_argument("--out", required=True, metavar="DIR", help="folder of the log")
    command.add_argument("--phase", help="log phase (default: the task's first)")
    command.add_argument("--scene", default="config/scene.yaml", metavar="YAML")
    command.add_argument("--max-duration", type=float, default=60.0, metavar="SECONDS")
    command.add_argument(
        "--intent",
        action="append",
        default=[],
        metavar="FILE",
        help="a learned intent (casa-intent/1 file) the robot also knows; repeatable "
        "(for the after_learning phase)",
    )
    command.add_argument(
        "--demonstrations",
        type=int,
        default=5,
        metavar="N",
        help="after a CASA trial before learning that finds every known intent's confidence "
        "below --epsilon, ask for and record N demonstrations (default 5; 0: never)",
    )
    command.add_argument(
        "--epsilon", type=float, default=1.0, help="misspecification threshold (default 1.0)"
    )
    command.add_argument(
        "--evidence",
        choices=("commanded", "executed"),
        help="what inference observes: the user's commanded motion (the default) or the "
        "arm's executed motion, the robot's share included (the original implementation's)",
    )
    command.set_defaults(func=_teleop)


def _teleop(args) -> int:
    import yaml

    from casa_core.study.trial import teleop_session, trial_intents

    with open(args.scene, encoding="utf-8") as handle:
        layout = yaml.safe_load(handle)
    try:
        stems, detected = teleop_session(
            layout,
            args.task,
            args.method,
            args.participant,
            args.out,
            n_demonstrations=args.demonstrations,
            epsilon=args.epsilon,
            phase=args.phase,
            max_duration=args.max_duration,
            intents=trial_intents(layout, args.intent),
            assistant_options={"evidence": args.evidence} if args.evidence else None,
        )
    except (FileExistsError, RuntimeError, ValueError) as error:
        print(f"casa teleop: {error}", file=sys.stderr)
        return 2
    for stem in stems:
        print(f"casa teleop: wrote {stem}.json and {stem}.csv")
    if detected:
        print(
            f"casa teleop: misspecification detected; {len(stems) - 1} demonstrations "
            f"recorded. Learn the new intent with: casa learn --demos {args.out} "
            f"--task {args.task} --name NAME --library DIR"
        )
    return 0


def _add_bench(commands) -> None:
    command = commands.add_parser(
        "bench",
        help="time the assistance step and a whole simulated trial",
        description="Print a table; with --json, also one JSON object on the last line with "
        "step_us_goal3, step_us_neural1, scaling and trial_realtime_factor (one CPU thread).",
    )
    command.add_argument("--json", action="store_true", help="print the JSON line last")
    command.add_argument("--scene", default="config/scene.yaml", metavar="YAML")
    command.add_argument("--seed", type=int, default=0)
    command.set_defaults(func=_bench)


def _bench(args) -> int:
    import json

    import torch
    import yaml

    from casa_core.robot import bench
    from casa_core.study.trial import trial_realtime_factor

    torch.set_num_threads(1)  # the targets are for one core
    with open(args.scene, encoding="utf-8") as handle:
        layout = yaml.safe_load(handle)
    results = bench.assistance_benchmarks(
        layout, lambda: bench.untrained_neural_intent(layout, args.seed), seed=args.seed
    )
    factor_cpu, factor_wall = trial_realtime_factor(layout)
    results["trial_realtime_factor"] = factor_cpu
    results["trial_realtime_factor_wall"] = factor_wall
    results["trial_realtime_factor_reused_sim"] = trial_realtime_factor(
        layout, reuse_simulation=True
    )[0]
    print(bench.format_table(results))
    if args.json:
        print(json.dumps(results))
    return 0


def _add_figure(commands) -> None:
    command = commands.add_parser(
        "figure",
        help="draw one of the paper's figures from the processed tables (PDF + 200 dpi PNG)",
        description="Write PREFIX.pdf and PREFIX.png (scene: the PNG only).",
    )
    figures = command.add_subparsers(dest="figure", metavar="NAME", required=True)
    objective = figures.add_parser("objective", help="error, efficiency and effort per task")
    objective.add_argument("--trials", required=True, metavar="CSV", help="trials.csv")
    objective.add_argument("--stats", metavar="CSV", help="stats.csv (Tukey brackets)")
    likert = figures.add_parser("likert", help="Likert scores per task and question")
    likert.add_argument("--likert", required=True, metavar="CSV", help="likert.csv")
    arbitration = figures.add_parser("arbitration", help="belief, confidence and alpha")
    arbitration.add_argument("--arbitration", required=True, metavar="CSV")
    case_study = figures.add_parser("case_study", help="confidence and alpha per task")
    case_study.add_argument("--steps", required=True, metavar="CSV", help="steps.csv")
    case_study.add_argument("--participant", help="whose runs (default: the first)")
    for sub in (arbitration, case_study):
        sub.add_argument("--epsilon", type=float, help="draw the confidence threshold")
    scene = figures.add_parser("scene", help="the arm and scene, pybullet-rendered")
    scene.add_argument("--scene", default="config/scene.yaml", metavar="YAML")
    for sub in (objective, likert, arbitration, case_study, scene):
        sub.add_argument("--out", required=True, metavar="PREFIX", help="output path")
        sub.set_defaults(func=_figure)


def _figure(args) -> int:
    from casa_core.figures.build import INPUTS, build_figure

    options = ("epsilon", "participant")
    inputs = {k: getattr(args, k) for k in (*INPUTS[args.figure], *options) if hasattr(args, k)}
    try:
        written = build_figure(args.figure, args.out, **inputs)
    except (OSError, ValueError) as error:
        print(f"casa figure {args.figure}: {error}", file=sys.stderr)
        return 1
    print(f"casa figure {args.figure}: " + ", ".join(str(path) for path in written))
    return 0


def _add_learn(commands) -> None:
    command = commands.add_parser(
        "learn",
        help="learn a new intent from demonstration logs (deep MaxEnt IRL) into a library",
        description="Read the demonstration logs (casa-trial/1) below --demos, learn intent "
        "NAME by deep maximum-entropy IRL and write NAME.intent.json into the library folder.",
    )
    command.add_argument("--demos", required=True, metavar="DIR", help="folder of demo logs")
    command.add_argument("--name", required=True, help="name of the new intent")
    command.add_argument("--library", required=True, metavar="DIR", help="the intent library")
    command.add_argument("--scene", default="config/scene.yaml", metavar="YAML")
    command.add_argument("--seed", type=int, default=0, help="seed of the network (default 0)")
    command.add_argument("--task", help="only the logs of this task (default: all)")
    command.add_argument(
        "--phase",
        default="demonstration",
        help="only the logs of this phase (default: demonstration; 'any' for all)",
    )
    command.add_argument("--participant", help="stored participant (default: from the logs)")
    command.add_argument(
        "--max-iterations", type=int, metavar="N", help="most IRL iterations (default 50)"
    )
    command.set_defaults(func=_learn)


def _learn(args) -> int:
    import yaml

    from casa_core import library, logs
    from casa_core.irl import IRLConfig

    config = IRLConfig()
    if args.max_iterations is not None:
        config = IRLConfig(max_iterations=args.max_iterations)
    try:
        with open(args.scene, encoding="utf-8") as handle:
            layout = yaml.safe_load(handle)
        path, history, seconds = library.learn_to_library(
            args.demos,
            args.name,
            args.library,
            layout,
            seed=args.seed,
            task=args.task,
            participant=args.participant,
            config=config,
            phase=None if args.phase == "any" else args.phase,
        )
    except (OSError, ValueError, logs.LogError) as error:
        print(f"casa learn: {error}", file=sys.stderr)
        return 1
    last = history[-1]
    print(
        f"casa learn: {args.name}: {len(history)} iterations in {seconds:.1f} s, "
        f"converged={'yes' if last.get('converged') else 'no'}, "
        f"D^phi ends {last['end_distance_m'] * 100:.1f} cm from the demos' -> {path}"
    )
    return 0


def _add_library(commands) -> None:
    command = commands.add_parser("library", help="inspect an intent library")
    actions = command.add_subparsers(dest="action", metavar="ACTION", required=True)
    listing = actions.add_parser(
        "list",
        help="one line per learned intent; damaged files are reported, not fatal",
        description="Print one line per intent file; report each unusable file on stderr "
        "with the rule it breaks; exit 1 if any file is unusable.",
    )
    listing.add_argument("library", metavar="DIR")
    listing.set_defaults(func=_library_list)


def _library_list(args) -> int:
    from casa_core import library

    entries, problems = library.scan_library(args.library)
    for entry in entries:
        print(entry.summary())
    for problem in problems:
        print(f"casa library: {problem}", file=sys.stderr)
    return 1 if problems else 0


def _load_config(path: str) -> tuple[dict, dict]:
    """The workflow config and the scene layout it names (read once, at the edge)."""
    import yaml

    with open(path) as handle:
        config = yaml.safe_load(handle)
    with open(config["scene"]) as handle:
        scene = yaml.safe_load(handle)
    return config, scene


def _add_simulate(commands) -> None:
    command = commands.add_parser(
        "simulate", help="simulate one participant of the study (one stage per call)"
    )
    command.add_argument(
        "stage",
        choices=["before", "learn", "after", "learning-table"],
        help="before: phases 1-3 and demonstrations; learn: one unknown "
        "task's intent; after: CASA after learning and the surveys; "
        "learning-table: gather the learn rows into one CSV",
    )
    command.add_argument("--config", default="config/config.yaml", help="workflow config")
    command.add_argument(
        "--participant", type=int, default=1, metavar="INDEX", help="1-based participant number"
    )
    command.add_argument("--rows", nargs="*", default=[], help="learning-table: learn CSVs")
    command.add_argument("--out", required=True, help="folder (before/after) or CSV (learn)")
    command.add_argument("--before", help="the participant's before-learning folder")
    command.add_argument("--task", choices=["unknown_goal", "unknown_skill"], help="learn: task")
    command.add_argument("--library", help="learn/after: the participant's intent library")
    command.set_defaults(func=_simulate)


def _simulate(args) -> int:
    from pathlib import Path

    import pandas as pd

    from casa_core import logs
    from casa_core.study import simulate

    if args.stage == "learning-table":
        from casa_core.datasets import read_table

        rows = [read_table(path) for path in sorted(args.rows)]
        table = pd.concat(rows, ignore_index=True).sort_values(["participant", "task"])
        logs.atomic_write_text(args.out, logs.frame_to_csv_text(table))
        print(f"casa simulate learning-table: {len(table)} learned intent(s) -> {args.out}")
        return 0
    config, scene = _load_config(args.config)
    simulation = config["simulation"]
    index = args.participant - 1
    pid = simulate.participant_id(index)
    if args.stage == "before":
        written = simulate.simulate_before_learning(index, scene, simulation, Path(args.out))
    elif args.stage == "learn":
        row = simulate.learn_from_demonstrations(
            Path(args.before),
            args.task,
            scene,
            int(simulation["seed"]) + index,
            Path(args.library),
            pid,
        )
        logs.atomic_write_text(args.out, logs.frame_to_csv_text(pd.DataFrame([row])))
        written = [args.out]
    else:
        learned = sorted(Path(args.library).rglob("*.intent.json"))
        written = simulate.simulate_after_learning(
            index, scene, simulation, learned, Path(args.before), Path(args.out)
        )
    print(f"casa simulate {args.stage}: participant {pid}, {len(written)} file(s)")
    return 0


def _add_case_study(commands) -> None:
    command = commands.add_parser(
        "case-study", help="the expert case study and the arbitration comparison"
    )
    command.add_argument("--config", default="config/config.yaml", help="workflow config")
    command.add_argument("--work", required=True, help="folder for the expert's logs and intents")
    command.add_argument("--steps", required=True, help="steps.csv to write")
    command.add_argument("--arbitration", required=True, help="arbitration.csv to write")
    command.set_defaults(func=_case_study)


def _case_study(args) -> int:
    from pathlib import Path

    from casa_core import logs
    from casa_core.study import simulate

    config, scene = _load_config(args.config)
    steps, arbitration = simulate.run_case_study(scene, config["case_study"], Path(args.work))
    logs.atomic_write_text(args.steps, logs.frame_to_csv_text(steps))
    logs.atomic_write_text(args.arbitration, logs.frame_to_csv_text(arbitration))
    print(f"casa case-study: {len(steps)} step row(s), {len(arbitration)} arbitration row(s)")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
