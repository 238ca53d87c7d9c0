"""``casa replay``: inference over trial logs (:mod:`casa_core.analysis.replay`)."""

from __future__ import annotations

import sys
from pathlib import Path

from casa_core import vocabulary
from casa_core.cli._errors import fail
from casa_core.cli._options import dataset_scene, example, nonnegative_float, positive_float
from casa_core.defaults import EPSILON
from casa_core.io.contract import NO_LOGGED_INFERENCE

#: The columns of ``replay.csv``, one row per trial.
SUMMARY_COLUMNS = [
    "trial",
    "participant",
    "task",
    "method",
    "phase",
    "preset",
    "evidence",
    "point",
    "path",
    "arbitration",
    "steps",
    "max_diff_beta",
    "max_diff_belief",
    "max_diff_alpha",
    "status",
    "reason",
]


#: The options that replay a trial under settings other than its own: a counterfactual.
COUNTERFACTUAL_OPTIONS = ("preset", "evidence", "arbitration", "lam", "epsilon", "intents")


def register(commands) -> None:
    """Add this module's commands to the ``casa`` subcommands."""
    command = commands.add_parser(
        "replay",
        help="redo the inference of recorded trials offline, with their own or other settings",
        description="Replay the inference over each trial's logged states and keys; write "
        "OUT/<stem>.replay.csv, FIGURES/<stem>.replay.png (the replayed alpha over the "
        "logged one), FIGURES/<stem>.path.png (the logged path over the task's intended "
        "path; stems mirror the trial's path below the folder given) and OUT/replay.csv "
        "(one row per trial, with the largest difference from the log's "
        "beta/belief/alpha). Default settings: each trial's own. "
        "Trials found in folders are replayed when their method is one of --methods; a file "
        "named is always replayed. Exit 1 if a log is invalid, 2 on bad arguments. "
        "See docs/replay.md.",
        **example(
            "casa replay data/raw/simulated --out data/processed/simulated/replay",
            "casa replay data/raw/simulated/p1/before/known_goal_no_misspecification_NA.csv \\",
            "    --arbitration confidence --out cf",
        ),
    )
    command.add_argument(
        "paths", nargs="+", metavar="PATH", help="a trial (file or stem) or a folder"
    )
    command.add_argument("--out", required=True, metavar="DIR", help="folder of the tables")
    command.add_argument("--figures", metavar="DIR", help="folder of the figures (default: --out)")
    _add_settings(command)
    _add_selection(command)
    command.set_defaults(func=_replay)


def _add_settings(command) -> None:
    """Add the inference settings a trial is replayed under (default: the trial's own)."""
    command.add_argument(
        "--preset",
        choices=vocabulary.REPLAY_PRESETS,
        help=f"inference preset ({vocabulary.DEFECTS_PRESET}: the original's numerics with "
        "their defects, to check imported sessions against their logs)",
    )
    command.add_argument("--evidence", choices=vocabulary.EVIDENCE, help="what the evidence is")
    command.add_argument(
        "--point",
        choices=vocabulary.POINTS,
        help="where the arm is measured: the tool point or link 7 (from the joint angles; "
        "default: the trial's own, else tool)",
    )
    command.add_argument(
        "--path",
        choices=vocabulary.REPLAY_PATHS,
        help="what the steps' evidence is read from: the trial's recorded waypoints (imported "
        "sessions) or the log's state every 0.5 s (default: the waypoints where the trial has "
        "them and the evidence is the executed path)",
    )
    command.add_argument(
        "--arbitration", help="confidence, distance, belief or none (default: the method's)"
    )
    command.add_argument("--lam", type=nonnegative_float, help="rate of the prior on beta")
    command.add_argument(
        "--epsilon", type=positive_float, help=f"misspecification threshold (default {EPSILON:g})"
    )
    command.add_argument(
        "--intents",
        metavar="LIBRARY",
        help="learned intents: a *.intent.json or a folder of them (a subfolder named after "
        "a trial's participant serves that participant's trials); default: the intents the "
        "dataset keeps in the trial's participant folder (docs/replay.md)",
    )


def _add_selection(command) -> None:
    """Add the options of the scene and of which trials found in folders are replayed."""
    command.add_argument(
        "--scene",
        metavar="YAML",
        help="scene (default: the folder's scene.yaml if it has one, else the package's)",
    )
    command.add_argument(
        "--methods",
        nargs="+",
        choices=vocabulary.METHODS,
        default=list(vocabulary.ASSISTED_METHODS),
        help="methods of the trials found in folders to replay (default: PBA CASA)",
    )
    command.add_argument(
        "--allow-invalid", action="store_true", help="list invalid logs in replay.csv and go on"
    )


def _replay(args) -> int:
    from casa_core.assist.assistant import ARBITRATIONS
    from casa_core.scene import load_scene

    if args.arbitration is not None and args.arbitration not in ARBITRATIONS:
        return fail(
            "replay",
            f"--arbitration {args.arbitration!r}: expected one of {', '.join(ARBITRATIONS)}",
        )
    if args.intents is not None and not Path(args.intents).exists():
        return fail("replay", f"--intents {args.intents}: no such file or folder")
    given = load_scene(args.scene) if args.scene else None
    trials, problems, missing = _collect(args.paths)
    if missing:
        return fail(
            "replay", "; ".join(f"{path}: no such trial, file or folder" for path in missing)
        )
    for problem in problems:
        print(problem, file=sys.stderr)
    if any(problem.is_error for problem in problems) and not args.allow_invalid:
        print(
            "casa replay: invalid log(s); see casa validate (or --allow-invalid)", file=sys.stderr
        )
        return 1
    seen: dict[Path, Path] = {}
    for trial in trials:
        if trial["stem"] in seen:
            return fail(
                "replay",
                f"{trial['file']} and {seen[trial['stem']]} would both be written as "
                f"{trial['stem']}.replay.csv; replay them separately",
            )
        seen[trial["stem"]] = trial["file"]
    scenes: dict[Path, object] = {}
    epsilon = EPSILON if args.epsilon is None else args.epsilon
    out, figures = Path(args.out), Path(args.figures or args.out)
    figures.mkdir(parents=True, exist_ok=True)  # there even when no trial is replayed
    rows = []
    for trial in trials:
        root = trial["root"]
        if given is None and root not in scenes:
            # A folder's own scene.yaml; a file given alone: the package's.
            scenes[root] = load_scene(dataset_scene(root, None) if trial["folder"] else None)
        scene = given or scenes[root]
        rows.append(_replay_one(trial, scene, args, epsilon, out, figures))
    changed = [f"--{name}" for name in COUNTERFACTUAL_OPTIONS if getattr(args, name) is not None]
    return _summarise(rows, out, changed)


def _collect(paths) -> tuple[list[dict], list, list[str]]:
    """The trials below the paths (with their output stems), the problems, missing paths."""
    from casa_core.io import check_paths, trial_files, trial_stem

    trials, problems, missing = [], [], []
    for text in paths:
        path = Path(text)
        if not path.exists() and trial_files(path)[1].is_file():
            path = trial_files(path)[1]  # a stem names its trial
        if not path.exists():
            missing.append(text)
            continue
        folder = path.is_dir()
        root = path if folder else path.parent
        for check in check_paths([path]):
            problems += check.problems
            if check.kind != "trial":
                continue
            stem = trial_stem(check.file).relative_to(root)
            trials.append(
                {"file": check.file, "root": root, "folder": folder, "stem": stem, "check": check}
            )
    return trials, problems, missing


def _replay_one(trial, scene, args, epsilon, out: Path, figures: Path) -> dict:
    from casa_core.analysis.replay import replay_differences, replay_trial
    from casa_core.analysis.replay_settings import replay_path, trial_point, trial_settings
    from casa_core.io import write_csv
    from casa_core.io.contract import CONDITION_KEYS

    check = trial["check"]
    meta = check.meta or {}
    row = {key: meta.get(key, "") for key in CONDITION_KEYS}
    row["trial"] = trial["stem"].as_posix()
    if not check.ok:
        return {**row, "status": "invalid", "reason": str(check.errors[0])}
    if trial["folder"] and meta["method"] not in args.methods:
        reason = f"method {meta['method']} is not in --methods ({' '.join(args.methods)})"
        return {**row, "status": "skipped", "reason": reason}
    try:
        chosen, arbitration = trial_settings(
            meta, preset=args.preset, evidence=args.evidence, arbitration=args.arbitration
        )
        point = trial_point(meta, args.point)
        path = replay_path(meta, chosen, args.path)
        row.update(
            preset=chosen.name,
            evidence=chosen.evidence,
            point=point,
            path=path,
            arbitration=arbitration,
        )
        replayed = replay_trial(
            meta,
            check.frame,
            scene,
            preset=args.preset,
            evidence=args.evidence,
            arbitration=args.arbitration,
            point=point,
            path=path,
            lam=args.lam,
            epsilon=epsilon,
            learned=_learned(trial, args.intents, meta["participant"]),
        )
    except ValueError as error:  # ReplayError, LibraryError: the trial is left out, said why
        return {**row, "status": "skipped", "reason": f"{trial['file']}: {error}"}
    stem = trial["stem"]
    write_csv(out / stem.parent / f"{stem.name}.replay.csv", replayed)
    title = (
        f"{stem.as_posix()}: {meta['method']} trial of {meta['participant']} "
        f"({meta['task']}, {meta['phase']}) replayed with preset {chosen.name}, evidence "
        f"{chosen.evidence}, point {point}, arbitration {arbitration}"
    )
    _figures(trial, replayed, scene, epsilon, title, figures)
    reason = ""
    if NO_LOGGED_INFERENCE in meta.get("flags", ()):
        reason = (
            f"nothing compared: the trial is flagged {NO_LOGGED_INFERENCE}, its log holds no "
            "inference result to compare with"
        )
    else:
        differences = replay_differences(check.frame, replayed)
        row.update({f"max_diff_{key}": value for key, value in differences.items()})
    return {**row, "steps": int(replayed["t"].nunique()), "status": "replayed", "reason": reason}


def _figures(trial: dict, replayed, scene, epsilon: float, title: str, figures: Path) -> None:
    """FIGURES/<stem>.replay.png, with the log's alpha, and FIGURES/<stem>.path.png: the
    logged path over the intended path of the trial's task."""
    import pandas as pd

    from casa_core.assist.tasks import intended_trajectory
    from casa_core.figures.path import COLUMNS as PATH_COLUMNS
    from casa_core.figures.path import path_figure
    from casa_core.figures.replay import replay_figure
    from casa_core.figures.style import save_figure

    meta, frame = trial["check"].meta, trial["check"].frame
    stem = figures / trial["stem"].parent / trial["stem"].name
    logged = frame if "alpha" in frame.columns else None
    fig = replay_figure(
        replayed, epsilon=epsilon, title=title, logged=logged, source=meta.get("source")
    )
    save_figure(fig, stem.with_name(f"{stem.name}.replay"), formats=("png",))
    intended = pd.DataFrame(intended_trajectory(meta["task"], scene), columns=PATH_COLUMNS)
    fig = path_figure(
        frame,
        intended,
        method=meta["method"],
        title=f"{trial['stem'].as_posix()}: {meta['method']} trial of {meta['participant']} "
        f"({meta['task']}, {meta['phase']})",
        source=meta.get("source"),
    )
    save_figure(fig, stem.with_name(f"{stem.name}.path"), formats=("png",))


def _learned(trial: dict, intents: str | None, participant: str) -> list[Path]:
    """``--intents`` when given, else the intents the dataset keeps for the trial."""
    from casa_core.analysis.replay_intents import kept_intent_files, library_files

    if intents is not None:
        return library_files(intents, participant)
    return kept_intent_files(trial["file"], trial["root"])


def _summarise(rows: list[dict], out: Path, changed: list[str]) -> int:
    import pandas as pd

    from casa_core.io import write_csv

    table = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
    table["steps"] = table["steps"].astype("Int64")  # empty, not NaN, where not replayed
    write_csv(out / "replay.csv", table)
    counts = table["status"].value_counts()
    for _, row in table[table["status"] != "replayed"].iterrows():
        if row["status"] != "skipped" or not str(row["reason"]).startswith("method "):
            print(f"casa replay: {row['trial']} {row['status']}: {row['reason']}", file=sys.stderr)
    largest = table[["max_diff_beta", "max_diff_belief", "max_diff_alpha"]].max()
    if changed:
        expected = f"expected: {' '.join(changed)} changed the settings the trials ran with"
    else:
        expected = "0 where the trials' own settings are reproduced"
    print(
        f"casa replay: {int(counts.get('replayed', 0))} trial(s) replayed, "
        f"{int(counts.get('skipped', 0))} skipped, {int(counts.get('invalid', 0))} invalid "
        f"-> {out}; largest difference from the logs ({expected}): beta {largest.iloc[0]:.3g}, "
        f"belief {largest.iloc[1]:.3g}, alpha {largest.iloc[2]:.3g}"
    )
    return 0
