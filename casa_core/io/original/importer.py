"""A folder of the original implementation's session files as a casa-trial/1 dataset.

``casa import original DIR --out data/raw/NAME`` calls :func:`import_original`: each
``task<N><letter>_data.npz`` of ``DIR`` becomes ``<out>/<participant>/<stem>.json`` and
``.csv`` (:mod:`casa_core.io.original.conversion` converts one file), and the scene of the
original's layout is copied to ``<out>/scene.yaml``, which the pipeline then uses for this
dataset. Names, in ``docs/data-contracts.md``:

* ``task<N>`` is the task: 0 the practice task (``familiarization``), 1 ``known_goal``,
  2 ``unknown_goal``, 4 ``unknown_skill``; the letter the method: ``a`` NA, ``b`` PBA,
  ``c`` CASA; ``task<N>c_learned`` is CASA after learning. The stem is the file name
  without ``_data.npz`` (``task1c``).
* ``task<N>ex_data.npz`` (a worked example) and ``task<N>_demonstrations.npz`` (joint
  angles without time stamps) are skipped, with the reason; so are files that are not
  ``.npz`` and folders. Any other ``.npz`` name is an error naming the file.

Every file is read and converted before anything is written: a bad file stops the
import with every problem listed (or, with ``skip_bad``, is left out and listed);
existing trials are not replaced unless ``force``; ``DIR`` is only read.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from casa_core.defaults import HORIZON
from casa_core.io import Problem, atomic_write_text, check_meta, frame_to_csv_text, write_trial
from casa_core.io.contract import NO_LOGGED_INFERENCE, NO_USER_COMMAND, SCENE_NAME
from casa_core.io.original.conversion import convert_session, inference_steps
from casa_core.io.original.sessions import SessionError, read_session, started_at
from casa_core.io.problems import errors
from casa_core.io.trial_log import inside, trial_files
from casa_core.io.validation import parse_trial_csv
from casa_core.scene import DEFAULT_SCENE, KNOWN_GOALS, load_scene
from casa_core.vocabulary import DEFECTS_PRESET, LEARNED_NAMES, PHASE_METHOD, TASK_PHASES

#: The scene of the original's layout, copied into every imported dataset by default.
ORIGINAL_SCENE = DEFAULT_SCENE.with_name("scene-original.yaml")
#: The original's task numbers.
TASK_NUMBERS = {0: "familiarization", 1: "known_goal", 2: "unknown_goal", 4: "unknown_skill"}
#: The original's method letters.
METHOD_LETTERS = {"a": "NA", "b": "PBA", "c": "CASA"}
_SESSION = re.compile(r"task(?P<task>\d+)(?P<letter>[a-z])(?P<learned>_learned)?_data\.npz")
_SKIPPED = (
    (re.compile(r"task\d+ex_data\.npz"), "a worked example run, not a participant's trial"),
    (re.compile(r"task\d+_demonstrations\.npz"), "demonstrations: joint angles without times"),
)


@dataclass(frozen=True)
class SessionName:
    """What a session file's name says: its ``stem``, ``task``, ``method`` and ``phase``."""

    stem: str
    task: str
    method: str
    phase: str


def parse_name(path: Path | str) -> SessionName | str:
    """The trial a session file name describes, or the reason the file is skipped.

    Raises
    ------
    SessionError
        For an ``.npz`` whose name is neither a session, an example nor demonstrations.

    Examples
    --------
    >>> parse_name("task2c_learned_data.npz")
    SessionName(stem='task2c_learned', task='unknown_goal', method='CASA', phase='after_learning')
    >>> parse_name("task2_demonstrations.npz")
    'demonstrations: joint angles without times'
    """
    path = Path(path)
    for pattern, reason in _SKIPPED:
        if pattern.fullmatch(path.name):
            return reason
    if path.suffix != ".npz":
        return "not an .npz session file"
    match = _SESSION.fullmatch(path.name)
    number = int(match["task"]) if match else None
    task = TASK_NUMBERS.get(number) if number is not None else None
    method = METHOD_LETTERS.get(match["letter"]) if match else None
    learned = bool(match and match["learned"])
    phases = TASK_PHASES.get(task, ()) if task is not None else ()
    if task is None or method is None or (learned and "after_learning" not in phases):
        rule = (
            "expected task<N><letter>_data.npz with N in "
            f"{', '.join(map(str, TASK_NUMBERS))} and the letter a (NA), b (PBA) or c (CASA), "
            "task<N>c_learned_data.npz for an unknown task (2, 4), task<N>ex_data.npz or "
            "task<N>_demonstrations.npz"
        )
        raise SessionError([Problem(str(path), "file name", "session-name", rule)])
    if learned and method != PHASE_METHOD["after_learning"]:
        message = f"after learning the method is {PHASE_METHOD['after_learning']}: use letter c"
        raise SessionError([Problem(str(path), "file name", "session-name", message)])
    phase = "after_learning" if learned else phases[0]
    return SessionName(path.name.removesuffix("_data.npz"), task, method, phase)


def goal_names(name: SessionName, goals: int) -> list[str]:
    """Our names of a session's goals: green and purple, then the learned intent.

    Examples
    --------
    >>> goal_names(SessionName("task4c_learned", "unknown_skill", "CASA", "after_learning"), 3)
    ['green', 'purple', 'learned_pour']
    """
    names = list(KNOWN_GOALS[:goals])
    for index in range(len(names), goals):
        learned = name.phase == "after_learning" and index == len(KNOWN_GOALS)
        names.append(LEARNED_NAMES[name.task] if learned else f"goal{index}")
    return names


@dataclass
class ImportResult:
    """What :func:`import_original` did: trials ``written`` (stems), ``skipped`` files with
    their reason, the ``bad`` files left out (with ``skip_bad``) and ``warnings`` on
    trials written."""

    written: list[Path] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)
    bad: list[Problem] = field(default_factory=list)
    warnings: list[Problem] = field(default_factory=list)


#: Tool travel (m) beyond which a session without any user command is one the robot drove.
ROBOT_TRAVEL = 0.05


def _robot_drove(session, frame) -> float | None:
    """The tool's travel (m) if the user's command is zero throughout while the arm moves
    more than :data:`ROBOT_TRAVEL`; else None."""
    if np.any(session.command):
        return None
    path = frame[["x", "y", "z"]].to_numpy(dtype=float)
    travel = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))
    return travel if travel > ROBOT_TRAVEL else None


def _import_notes(path, name: SessionName, session, converted) -> str:
    """The trial's ``notes``: where the import took each column from and what it repaired."""
    evidence = "the recorded waypoints" if session.waypoints is not None else "curr_pos"
    ticks = len(converted.frame)
    notes = (
        f"imported from the original implementation's session file {path.name}: "
        f"{converted.samples} samples resampled to {ticks} ticks of 0.05 s; keys from "
        f"joy_cmd; {len(session.steps)} timed inference steps, each held from the tick at or "
        "after its start (inf_start_time), the step after the trial kept in inference_steps; "
        f"alpha recomputed by the {name.method} rule; negative betas written as 0: "
        f"{converted.negative_betas}; belief rows carried from the last good row: "
        f"{converted.bad_beliefs}; beta rows not finite, carried: {converted.bad_betas}"
    )
    if not session.logged_inference:
        notes += (
            "; no beliefs or betas: the session logged no inference result (beta_hist is "
            "empty, belief_hist holds the uniform prior on every row: the posterior of the "
            "original's joint table over goals and beta was never saved)"
        )
        if name.method == "PBA":
            notes += (
                "; PBA's most likely goal recomputed by the original's posterior at beta = 1 "
                f"over {evidence}"
            )
    return notes


def _convert(path, name: SessionName, participant: str, target: Path, scene, warnings: list):
    """The metadata and frame of one session, checked as write_trial will check them;
    ``warnings`` gets what is imported but said (a session the robot drove)."""
    session = read_session(path)
    names = goal_names(name, session.goals)
    converted = convert_session(
        session, name.method, names, scene.goals_at("link7") or None, point=scene.point
    )
    frame = converted.frame
    notes = _import_notes(path, name, session, converted)
    meta = {
        "schema": "casa-trial/1",
        "participant": participant,
        "task": name.task,
        "method": name.method,
        "phase": name.phase,
        "source": "human",
        "intents": names,
        "max_duration": HORIZON,
        # What computed the logged numbers: the original, defects included, at link 7.
        "inference": {"preset": DEFECTS_PRESET, "evidence": "executed", "point": "link7"},
        "inference_steps": inference_steps(session, names),
        "notes": notes,
    }
    flags = [] if session.logged_inference else [NO_LOGGED_INFERENCE]
    travel = _robot_drove(session, frame)
    if travel is not None:
        flags.append(NO_USER_COMMAND)
        warning = (
            f"the user's command is zero on every row while the arm travels {travel:.2f} m: "
            f"the robot drove; imported with the flag {NO_USER_COMMAND}, which analyses of "
            "people's behaviour (calibration) leave out"
        )
        warnings.append(Problem(str(path), "key 'joy_cmd'", NO_USER_COMMAND, warning, "warning"))
    if flags:
        meta["flags"] = flags
    if (start := started_at(session)) is not None:
        meta["started_at"] = start
    json_path, csv_path = trial_files(target)
    problems = check_meta(meta, str(json_path))
    problems += parse_trial_csv(frame_to_csv_text(frame), str(csv_path), meta=meta)[1]
    if errors(problems):
        raise SessionError(errors(problems))
    return meta, frame


def _existing(target: Path) -> list[Problem]:
    return [
        Problem(str(path), "", "exists", "already there: not replaced without --force")
        for path in trial_files(target)
        if path.exists()
    ]


def import_original(
    folder: Path | str,
    out: Path | str,
    *,
    participant: str | None = None,
    scene: Path | str | None = None,
    force: bool = False,
    skip_bad: bool = False,
) -> ImportResult:
    """Convert the session files of ``folder`` into the dataset folder ``out``.

    Parameters
    ----------
    folder : path
        One participant's session files (only read; its sub-folders are not searched).
    out : path
        The dataset folder, e.g. ``data/raw/original``; trials go to ``out/<participant>/``.
    participant : str, optional
        Default: the name of ``folder``.
    scene : path, optional
        The scene copied to ``out/scene.yaml``; default :data:`ORIGINAL_SCENE`.
    force : bool
        Replace trials (and a different ``scene.yaml``) already in ``out``.
    skip_bad : bool
        Leave out files that cannot be converted (listed in ``bad``) instead of stopping.

    Raises
    ------
    SessionError
        Listing every problem; nothing is written then.
    casa_core.scene.SceneError
        If ``scene`` cannot be used.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp()) / "p01"
    >>> folder.mkdir()
    >>> _ = (folder / "task1ex_data.npz").write_bytes(b"")
    >>> result = import_original(folder, folder.parent / "out")
    >>> result.written, result.skipped
    ([], [('task1ex_data.npz', "a worked example run, not a participant's trial")])
    >>> (folder.parent / "out" / "scene.yaml").is_file()
    True
    """
    folder, out = Path(folder), Path(out)
    if not folder.is_dir():
        raise SessionError([Problem(str(folder), "", "exists", "no such folder")])
    if inside(out, folder):
        message = f"the output {out} is inside it: the session folder is only read"
        raise SessionError([Problem(str(folder), "", "read-only", message)])
    participant = participant or folder.resolve().name
    scene_path = ORIGINAL_SCENE if scene is None else Path(scene)
    scene_used = load_scene(scene_path)  # a SceneError names the file and the key
    scene_text = scene_path.read_text(encoding="utf-8")
    result, trials = ImportResult(), []
    problems: list[Problem] = []
    warnings: list[Problem] = []
    for path in sorted(folder.iterdir()):
        if path.name.startswith("."):
            continue
        if path.is_dir():
            result.skipped.append((path.name, "a folder: not searched"))
            continue
        try:
            name = parse_name(path)
            if isinstance(name, str):
                result.skipped.append((path.name, name))
                continue
            target = out / participant / name.stem
            converted = _convert(path, name, participant, target, scene_used, warnings)
            trials.append((target, *converted))
        except SessionError as error:
            (result.bad if skip_bad else problems).extend(error.problems)
    if not force:
        problems += [p for target, _, _ in trials for p in _existing(target)]
        copy = out / SCENE_NAME
        if copy.exists() and copy.read_text(encoding="utf-8") != scene_text:
            problems.append(Problem(str(copy), "", "exists", "a different scene: use --force"))
    if problems:
        raise SessionError(problems)
    atomic_write_text(out / SCENE_NAME, scene_text)
    for target, meta, frame in trials:
        write_trial(target, meta, frame)
        result.written.append(target)
    result.warnings = warnings
    return result


def describe(result: ImportResult, out: Path | str) -> str:
    """One line per written trial, skipped and bad file, then a summary line.

    Examples
    --------
    >>> print(describe(ImportResult(skipped=[("notes.txt", "not an .npz session file")]), "x"))
    skipped notes.txt: not an .npz session file
    0 trial(s) written to x, 1 file(s) skipped, 0 bad file(s) left out
    """
    lines = [f"wrote {os.fspath(target)}.json, .csv" for target in result.written]
    lines += [f"skipped {name}: {reason}" for name, reason in result.skipped]
    lines += [f"left out: {problem}" for problem in result.bad]
    lines += [str(problem) for problem in result.warnings]
    bad_files = len({problem.file for problem in result.bad})
    lines.append(
        f"{len(result.written)} trial(s) written to {out}, {len(result.skipped)} file(s) "
        f"skipped, {bad_files} bad file(s) left out"
    )
    return "\n".join(lines)
