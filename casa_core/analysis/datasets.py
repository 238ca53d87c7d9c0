"""One raw dataset folder in, its processed tables out.

A dataset is a folder of casa-trial/1 logs (``data/raw/<dataset>/``, read only
through :mod:`casa_core.io`). It becomes four tables, the contract with users
(``docs/data-contracts.md``):

- ``trials.csv``: one row per trial with its metrics (:mod:`casa_core.analysis.metrics`),
  columns :data:`TRIAL_COLUMNS`;
- ``steps.csv``: one row per tick and intent for trials that logged
  ``alpha``, ``beta:NAME`` or ``belief:NAME``, columns :data:`STEP_COLUMNS`;
- ``likert.csv``: every ``surveys.csv`` answer, columns :data:`LIKERT_COLUMNS`;
- ``validation.csv``: every file checked, its status and each problem,
  columns :data:`VALIDATION_COLUMNS`.

Rows are sorted on their identifying columns and written atomically
(:mod:`casa_core.io.atomic`; the first three together, all or none), so the same
raw files give the same bytes. Paths in the tables are relative to the dataset folder.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from casa_core.analysis import metrics
from casa_core.assist import tasks
from casa_core.io import CONDITION_KEYS, FileCheck, Problem, check_paths
from casa_core.io.atomic import atomic_paths, frame_to_csv_text, write_csv
from casa_core.io.contract import CASE_STEPS_COLUMNS, INTENT_PREFIXES
from casa_core.scene import Scene
from casa_core.vocabulary import ANSWERED_BY

TRIAL_COLUMNS = (
    "dataset",
    "participant",
    "task",
    "method",
    "phase",
    "source",
    "error",
    "efficiency",
    "effort",
    "effort_ticks",
    "relative_effort",
    "duration",
    # Beyond the contract: the rotation error and cost, the original's relative
    # effort, the number of ticks and the trial's stem, to trace a row to its file.
    "error_rot",
    "efficiency_rot",
    "relative_effort_ticks",
    "ticks",
    "trial",
    # The inference settings the trial was run with (metadata "inference"; empty when
    # its log does not say them).
    "preset",
    "evidence",
    # The trial's flags (metadata "flags", space-separated; io.contract.TRIAL_FLAGS).
    "flags",
    # The device the person drove with (metadata "input"; keyboard when it has none), and
    # the command's time and magnitude (casa_core.analysis.effort), for keys and devices.
    "input",
    "command_time",
    "command_integral",
    # Whether the trial ran to its time limit (empty when its log does not say the
    # limit), whether it ended where the task intends and since when it stayed there
    # (empty when it did not; casa_core.analysis.metrics).
    "timed_out",
    "success",
    "arrival",
)
# The case study's per-tick columns, then where each row comes from.
STEP_COLUMNS = (*CASE_STEPS_COLUMNS, "dataset", "trial")
LIKERT_COLUMNS = (
    "dataset",
    "participant",
    "task",
    "method",
    "phase",
    "question",
    "score",
    "source",
    # "model" for a simulated participant's answers (a formula's output), "participant"
    # for a person's (casa_core.vocabulary.ANSWERED_BY), else "unknown".
    "answered_by",
)
VALIDATION_COLUMNS = ("file", "kind", "status", "rule", "where", "message")


class DatasetInvalid(ValueError):
    """A dataset has bad files; ``problems`` lists every problem in all of them."""

    def __init__(self, dataset: str, problems: list[Problem]):
        self.dataset = dataset
        self.problems = problems
        lines = "\n".join(f"  {p}" for p in problems)
        super().__init__(
            f"dataset {dataset!r}: {len(problems)} problem(s) in "
            f"{len({p.file for p in problems})} file(s); fix them or rerun with "
            f"allow_invalid=true to exclude those files:\n{lines}"
        )


@dataclass
class DatasetTables:
    """The processed tables of one dataset."""

    trials: pd.DataFrame
    steps: pd.DataFrame
    likert: pd.DataFrame
    validation: pd.DataFrame


def _relative(path: Path, root: Path) -> str:
    try:
        return path.relative_to(root).as_posix()
    except ValueError:
        return path.as_posix()


def validation_table(
    checks: list[FileCheck], root: Path, *, allow_invalid: bool = False
) -> pd.DataFrame:
    """Every checked file with its status: ``ok``, ``ignored`` (not a log), ``invalid``
    (stops the build) or ``excluded`` (with ``allow_invalid``); one row per problem.
    """
    rows = []
    for check in checks:
        file = _relative(check.file, root)
        if check.kind == "other" and not check.problems:
            rows.append((file, check.kind, "ignored", "", "", "not a .csv or .json: not read"))
        elif check.kind == "intent":
            rows.append((file, check.kind, "ignored", "", "", "a learned intent: read by replay"))
        elif not check.problems:
            rows.append((file, check.kind, "ok", "", "", ""))
        else:
            # A warning's row says "warning"; an error's, what happens to the file (for a
            # surveys.csv, to the lines the problem names).
            error_status = "excluded" if allow_invalid else "invalid"
            for problem in check.problems:
                status = error_status if problem.is_error else "warning"
                where = problem.where
                if _relative(Path(problem.file), root) != file:
                    # The problem is in the trial's other file (its .json).
                    where = f"{_relative(Path(problem.file), root)}: {where}".rstrip(": ")
                rows.append((file, check.kind, status, problem.rule, where, problem.message))
    return pd.DataFrame(rows, columns=list(VALIDATION_COLUMNS))


def check_dataset(raw_dir: Path | str) -> list[FileCheck]:
    """Check every file of a dataset folder (see :func:`casa_core.io.check_paths`)."""
    return check_paths([Path(raw_dir)])


def build_tables(
    raw_dir: Path | str,
    scene: Scene,
    *,
    dataset: str | None = None,
    allow_invalid: bool = False,
) -> DatasetTables:
    """Check a dataset folder and compute its tables.

    Parameters
    ----------
    raw_dir : path
        The dataset's folder; only read.
    scene : Scene
        The study's scene (:func:`casa_core.scene.load_scene`): the tasks' intended
        trajectories and the control tick ``teleop.dt``.
    dataset : str, optional
        The dataset's name in the tables; the folder's name by default.
    allow_invalid : bool
        Exclude bad files (listed in the validation table) instead of raising.

    Raises
    ------
    DatasetInvalid
        When a file breaks the contract and ``allow_invalid`` is false; lists every problem.
    """
    root = Path(raw_dir)
    dataset = dataset or root.resolve().name
    checks = check_dataset(root)
    problems = [p for check in checks for p in check.errors]
    if problems and not allow_invalid:
        raise DatasetInvalid(dataset, problems)
    good = [check for check in checks if check.ok]
    trials, steps = _trials_and_steps([c for c in good if c.kind == "trial"], root, scene, dataset)
    # A surveys.csv's frame holds its good rows: one bad answer does not drop the others.
    surveys = [c for c in checks if c.kind == "surveys" and c.frame is not None]
    likert = _likert(surveys, trials, dataset)
    return DatasetTables(
        trials, steps, likert, validation_table(checks, root, allow_invalid=allow_invalid)
    )


def _trials_and_steps(
    checks: list[FileCheck], root: Path, scene: Scene, dataset: str
) -> tuple[pd.DataFrame, pd.DataFrame]:
    dt = scene.teleop.dt
    intended = {}
    rows, step_parts = [], []
    for check in checks:
        meta, frame = check.meta, check.frame  # parsed and checked by check_paths
        assert meta is not None and frame is not None
        task = meta["task"]
        if task not in intended:
            intended[task] = tasks.intended_trajectory(task, scene)
        trial = _relative(check.file, root).removesuffix(".csv")
        condition = {key: meta[key] for key in CONDITION_KEYS}
        rows.append(
            {
                "dataset": dataset,
                **condition,
                "source": meta["source"],
                **metrics.trial_metrics(
                    frame,
                    intended[task],
                    dt=dt,
                    max_duration=meta.get("max_duration"),
                    input=meta.get("input", "keyboard"),
                    speed=scene.teleop.speed,
                    rot_speed=scene.teleop.rot_speed,
                ),
                "trial": trial,
                **_inference(meta),
                "flags": " ".join(meta.get("flags", ())),
            }
        )
        step_parts.append(_steps(frame, condition, dataset, trial, goals=scene.goals))
    trials = pd.DataFrame(rows, columns=[c for c in TRIAL_COLUMNS if "relative" not in c])
    trials["relative_effort"] = metrics.relative_effort(trials, "effort")
    trials["relative_effort_ticks"] = metrics.relative_effort(trials, "effort_ticks")
    trials = trials.astype({"effort": int, "effort_ticks": int, "ticks": int})
    trials = trials[list(TRIAL_COLUMNS)].sort_values([*CONDITION_KEYS, "trial"], kind="stable")
    steps = [part for part in step_parts if len(part)]
    steps = pd.concat(steps) if steps else pd.DataFrame(columns=list(STEP_COLUMNS))
    steps = steps[list(STEP_COLUMNS)].sort_values([*CONDITION_KEYS, "trial", "t", "intent"])
    return trials.reset_index(drop=True), steps.reset_index(drop=True)


def _inference(meta: dict) -> dict:
    """The trial's inference preset and evidence, empty when its metadata does not say."""
    settings = meta.get("inference") or {}
    return {key: settings.get(key, "") for key in ("preset", "evidence")}


def _steps(
    frame: pd.DataFrame, condition: dict, dataset: str, trial: str, *, goals: Mapping
) -> pd.DataFrame:
    """The long per-tick table of one trial: one row per tick and intent.

    ``distance`` is the logged point's distance to the intent's goal where ``goals`` (the
    scene's, at the point the trial logs) names it, else NaN.
    """
    names = []
    for column in frame.columns:
        prefix, _, name = column.partition(":")
        if prefix in INTENT_PREFIXES and name not in names:
            names.append(name)
    if not names and "alpha" not in frame.columns:
        return pd.DataFrame(columns=list(STEP_COLUMNS))
    alpha = frame["alpha"] if "alpha" in frame.columns else float("nan")
    parts = []
    for name in names or [""]:
        part = pd.DataFrame({"t": frame["t"], "alpha": alpha, "intent": name})
        for quantity in INTENT_PREFIXES:
            column = f"{quantity}:{name}"
            part[quantity] = frame[column] if column in frame.columns else float("nan")
        part["distance"] = _distance(frame, goals.get(name))
        parts.append(part)
    steps = pd.concat(parts, ignore_index=True)
    for key, value in {**condition, "dataset": dataset, "trial": trial}.items():
        steps[key] = value
    return steps


def _distance(frame: pd.DataFrame, goal) -> np.ndarray | float:
    """Per tick, the distance from the logged ``x, y, z`` to ``goal``; NaN without one."""
    if goal is None:
        return float("nan")
    d = frame[["x", "y", "z"]].to_numpy(dtype=float) - np.asarray(goal, dtype=float)
    # Summed in a fixed order: the same bytes on every CPU.
    return np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])


def _likert(checks: list[FileCheck], trials: pd.DataFrame, dataset: str) -> pd.DataFrame:
    """All survey answers; without a ``source`` column, the participant's trials' source."""
    sources = trials.groupby("participant")["source"].agg(
        lambda s: s.iloc[0] if s.nunique() == 1 else "unknown"
    )
    parts = []
    for check in checks:
        assert check.frame is not None  # parsed and checked by check_paths
        answers = check.frame.copy()
        if "source" not in answers.columns:
            answers["source"] = answers["participant"].map(sources).fillna("unknown")
        answers["dataset"] = dataset
        answers["answered_by"] = answers["source"].map(ANSWERED_BY).fillna("unknown")
        parts.append(answers)
    if not parts:
        return pd.DataFrame(columns=list(LIKERT_COLUMNS))
    likert = pd.concat(parts, ignore_index=True)[list(LIKERT_COLUMNS)]
    return likert.sort_values([*CONDITION_KEYS, "question"], kind="stable").reset_index(drop=True)


def write_tables(tables: DatasetTables, out_dir: Path | str) -> list[Path]:
    """Write ``trials.csv``, ``steps.csv`` and ``likert.csv`` together; return their paths.

    The three belong together: all are written to temporary files first and renamed
    only when all are written, so a full disk or a killed run leaves the old three.
    """
    names = ("trials", "steps", "likert")
    paths = [Path(out_dir) / f"{name}.csv" for name in names]
    texts = [frame_to_csv_text(getattr(tables, name)) for name in names]
    with atomic_paths(*paths) as temporaries:
        for tmp, text in zip(temporaries, texts, strict=True):
            tmp.write_bytes(text.encode("utf-8"))
    return paths


def write_validation(
    paths: list[Path | str], out_csv: Path | str, *, allow_invalid: bool = False
) -> list[FileCheck]:
    """Check files and folders, write their validation table atomically, return the checks.

    Paths in the table are relative to the folder given when exactly one folder
    is given. The table is written whatever the outcome.
    """
    given = [Path(p) for p in paths]
    root = given[0] if len(given) == 1 and given[0].is_dir() else Path(".")
    checks = check_paths(given)
    write_csv(out_csv, validation_table(checks, root, allow_invalid=allow_invalid))
    return checks
