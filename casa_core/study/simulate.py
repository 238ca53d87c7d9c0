"""The simulated study and the expert case study, run through the robot in pybullet.

A participant's protocol has three stages: :func:`simulate_before_learning`
(familiarization, Known Goal, the unknown tasks before learning and the
demonstrations), :func:`learn_from_demonstrations` (one per unknown task) and
:func:`simulate_after_learning` (CASA with the learned intents, then the Likert
answers). A workflow can run them as separate jobs, spread over cores, or all in one
job with :func:`simulate_protocol`, which writes the same files. Every random draw
comes from ``seed`` through ``numpy.random.default_rng([seed, participant_index,
stream])``, so a participant's trials do not depend on how many participants there are.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from casa_core.assist.tasks import intended_trajectory
from casa_core.defaults import HORIZON
from casa_core.io import SURVEYS_NAME, write_surveys
from casa_core.io.contract import CASE_STEPS_COLUMNS
from casa_core.scene import Scene
from casa_core.study import likert, protocol
from casa_core.study.closed_loop import known_goal_intents, simulated_trial, trial_intents
from casa_core.study.participants import ParticipantParams, draw_participants
from casa_core.study.settings import Population, StudySettings
from casa_core.vocabulary import ASSISTED_METHODS, LEARNED_NAMES, UNKNOWN_TASKS

#: Stream numbers of default_rng([seed, index, stream]).
PARAMS_STREAM, LIKERT_STREAM = 0, 9999


def check_index(index) -> int:
    """``index``, a participant's 0-based number, if it is an integer >= 0; else ValueError.

    Examples
    --------
    >>> check_index(0)
    0
    >>> check_index(-1)
    Traceback (most recent call last):
    ...
    ValueError: participant index must be an integer >= 0 (0-based), got -1
    """
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise ValueError(f"participant index must be an integer >= 0 (0-based), got {index!r}")
    return int(index)


def participant_id(index: int) -> str:
    """``p01``, ``p02``, ... for the 0-based ``index``.

    Examples
    --------
    >>> participant_id(0), participant_id(11)
    ('p01', 'p12')
    """
    return f"p{check_index(index) + 1:02d}"


def participant_params(index: int, seed: int, population: Population | None) -> ParticipantParams:
    """The participant's operator parameters, drawn from ``population`` with ``seed``."""
    check_index(index)
    if population is None:
        raise ValueError("no population to draw the participant from: give its params")
    rng = np.random.default_rng([seed, index, PARAMS_STREAM])
    return draw_participants(1, population, rng)[0]


def learning_seed(index: int, seed: int) -> int:
    """The seed of learning participant ``index``'s intents: the study's ``seed`` + ``index``.

    Examples
    --------
    >>> learning_seed(2, 2021)
    2023
    """
    return int(seed) + index


def _params(index: int, settings: StudySettings, params: ParticipantParams | None):
    return params or participant_params(index, settings.seed, settings.population)


def _run(scene, spec, settings: StudySettings, params, rng, pid, sim, **options):
    return simulated_trial(
        scene,
        spec,
        intended_trajectory(spec.task, scene),
        params,
        rng,
        participant=pid,
        operator=settings.operator,
        max_duration=settings.max_duration,
        sim=sim,
        inference=settings.inference,
        seed=settings.seed,
        **options,
    )


def _write(result, stem: Path, logs: dict | None) -> Path:
    """Write a trial's log; keep it in ``logs`` by its ``.json`` path, as read back."""
    trial = result.write(stem)
    if logs is not None:
        logs[stem.with_name(f"{stem.name}.json")] = trial
    return stem


def simulate_before_learning(
    index: int,
    scene: Scene,
    *,
    settings: StudySettings,
    out_dir: Path,
    params: ParticipantParams | None = None,
    pid: str | None = None,
    logs: dict | None = None,
) -> list[Path]:
    """Phases 1-3 and the demonstrations of one participant; returns the logs' stems.

    ``logs``, if given, gets each log written by its ``.json`` path, as read back.

    After the CASA trial of each unknown task the robot checks for misspecification
    (:func:`casa_core.study.protocol.misspecification_detected`, noted in the log); with
    ``settings.demonstrations_when == "detected"`` it asks for demonstrations
    only then, with ``"always"`` (the paper's protocol) every time.
    """
    from casa_core.robot.sim import ArmSimulation

    check_index(index)
    pid = pid or participant_id(index)
    params = _params(index, settings, params)
    seed, epsilon = settings.seed, settings.epsilon
    out_dir = Path(out_dir)
    specs = protocol.before_learning(index)
    written = []
    with ArmSimulation(scene) as sim:
        detected = {}
        for stream, spec in enumerate(specs, start=1):
            rng = np.random.default_rng([seed, index, stream])
            result = _run(scene, spec, settings, params, rng, pid, sim)
            if spec.method == "CASA" and spec.phase == "before_learning":
                detected[spec.task] = protocol.misspecification_detected(result.frame, epsilon)
                note = f"misspecification detected: {detected[spec.task]}"
                result.meta["notes"] = "; ".join(filter(None, [result.meta.get("notes"), note]))
            written.append(_write(result, out_dir / spec.stem, logs))
        stream = len(specs) + 1
        for task in protocol.demonstration_tasks(settings.demonstrations_when, detected):
            for spec in protocol.demonstrations(task, settings.demonstrations):
                rng = np.random.default_rng([seed, index, stream])
                stream += 1
                result = _run(scene, spec, settings, params, rng, pid, sim)
                written.append(_write(result, out_dir / spec.stem, logs))
    return written


def learn_from_demonstrations(
    demos_dir: Path, task: str, *, scene: Scene, seed: int, library: Path, pid: str, logs=None
) -> tuple[dict, dict]:
    """Learn the intent of ``task`` from the participant's demonstrations into ``library``.

    Returns the row of ``learning.csv`` (``participant, task, intent,
    endpoint_error_m, final_tilt_deg``; empty values when the participant gave no
    demonstrations of the task) and the row of ``learning_timing.csv``
    (``participant, task, intent, train_seconds``): measured times are kept apart, so
    that the results are the same bytes on every run. The logs in ``logs`` (by the
    ``.json``'s path, as :func:`casa_core.io.write_trial` returns them) are not read again.
    """
    from casa_core.learning.library import load_intent
    from casa_core.study.learn_from_logs import learn_to_library, read_demonstrations
    from casa_core.study.learning_evidence import learning_evidence, scene_objects

    name = LEARNED_NAMES[task]
    which = {"participant": pid, "task": task, "intent": name}
    row = {**which, "endpoint_error_m": np.nan, "final_tilt_deg": np.nan}
    timing = {**which, "train_seconds": np.nan}
    demo_stems = [p for p in Path(demos_dir).glob(f"{task}_demonstration_*.json")]
    if not demo_stems:
        return row, timing
    read = read_demonstrations(demos_dir, task, logs=logs)  # once, for learning and evidence
    options: dict[str, Any] = {
        "seed": seed,
        "task": task,
        "participant": pid,
        "demonstrations": read,
    }
    path, _history, seconds = learn_to_library(
        demos_dir, name, library=library, objects=scene_objects(scene), **options
    )
    evidence = learning_evidence(load_intent(path).intent, read[0], scene=scene)
    row.update(evidence)
    timing["train_seconds"] = seconds
    return row, timing


def simulate_after_learning(
    index: int,
    scene: Scene,
    *,
    settings: StudySettings,
    learned: list[Path],
    before_dir: Path,
    out_dir: Path,
    params: ParticipantParams | None = None,
    pid: str | None = None,
    logs: dict | None = None,
) -> list[Path]:
    """Phase 4 (CASA with every learned intent), then ``surveys.csv`` for all conditions.

    The logs in ``logs`` (:func:`simulate_before_learning`'s) are not read again.
    """
    from casa_core.robot.sim import ArmSimulation

    check_index(index)
    pid = pid or participant_id(index)
    params = _params(index, settings, params)
    seed = settings.seed
    out_dir = Path(out_dir)
    written, logs = [], dict(logs or {})
    if learned:
        intents = trial_intents(scene, learned, inference=settings.inference)
        with ArmSimulation(scene) as sim:
            for offset, spec in enumerate(protocol.after_learning()):
                rng = np.random.default_rng([seed, index, 1000 + offset])
                result = _run(scene, spec, settings, params, rng, pid, sim, intents=intents)
                written.append(_write(result, out_dir / spec.stem, logs))
    surveys = likert.simulated_surveys(
        pid,
        [Path(before_dir), out_dir],
        scene=scene,
        rng=np.random.default_rng([seed, index, LIKERT_STREAM]),
        logs=logs,
    )
    write_surveys(out_dir / SURVEYS_NAME, surveys)
    return written


@dataclass(frozen=True)
class ProtocolRun:
    """What :func:`simulate_protocol` wrote for one participant, and its learning's CPU time.

    ``before`` and ``after`` are the logs' stems (``after`` also holds ``surveys.csv``);
    ``rows`` and ``timings`` are the ``learning.csv`` and ``learning_timing.csv`` rows of
    each unknown task, in :data:`~casa_core.vocabulary.UNKNOWN_TASKS` order; ``learned`` the
    intent files written; ``learning_cpu_s`` the CPU seconds of this process that each
    learning step took (measured, so never written to a result).
    """

    before: list[Path]
    rows: list[dict]
    timings: list[dict]
    learned: list[Path]
    after: list[Path]
    learning_cpu_s: list[float]


def simulate_protocol(
    index: int,
    scene: Scene,
    *,
    settings: StudySettings,
    before_dir: Path,
    after_dir: Path,
    libraries: Mapping[str, Path],
    params: ParticipantParams | None = None,
    pid: str | None = None,
) -> ProtocolRun:
    """One participant's whole protocol, the three stages one after the other, in one process.

    :func:`simulate_before_learning` into ``before_dir``; :func:`learn_from_demonstrations`
    of each unknown task into the folder ``libraries[task]``, with the seed
    :func:`learning_seed` (as ``casa simulate learn``); then
    :func:`simulate_after_learning` with the intents learned into ``after_dir``. The files
    are the bytes the three stages write when run as separate jobs.

    Examples
    --------
    >>> import tempfile
    >>> from dataclasses import replace
    >>> from casa_core.config import DEFAULT_CONFIG, load_config
    >>> from casa_core.scene import load_scene
    >>> settings = StudySettings.from_config(load_config(DEFAULT_CONFIG))
    >>> settings = replace(settings, demonstrations=0, max_duration=0.5)  # nothing to learn
    >>> work = Path(tempfile.mkdtemp())
    >>> run = simulate_protocol(
    ...     0, load_scene(), settings=settings, before_dir=work / "before",
    ...     after_dir=work / "after", libraries={t: work / t for t in UNKNOWN_TASKS})
    >>> len(run.before), [row["task"] for row in run.rows], run.learned, run.after
    (10, ['unknown_goal', 'unknown_skill'], [], [])
    """
    from casa_core.learning.library import intent_path

    pid = pid or participant_id(index)
    params = _params(index, settings, params)
    options: dict[str, Any] = {"settings": settings, "params": params, "pid": pid}
    options["logs"] = {}  # each log as written, for the surveys
    before = simulate_before_learning(index, scene, out_dir=before_dir, **options)
    rows, timings, learned, seconds = [], [], [], []
    for task in UNKNOWN_TASKS:
        began = time.process_time()
        row, timing = learn_from_demonstrations(
            before_dir,
            task,
            scene=scene,
            seed=learning_seed(index, settings.seed),
            library=libraries[task],
            pid=pid,
            logs=options["logs"],
        )
        seconds.append(time.process_time() - began)
        rows.append(row)
        timings.append(timing)
        if not np.isnan(timing["train_seconds"]):  # learned from demonstrations
            learned.append(intent_path(libraries[task], LEARNED_NAMES[task]))
    after = simulate_after_learning(
        index, scene, learned=learned, before_dir=before_dir, out_dir=after_dir, **options
    )
    return ProtocolRun(before, rows, timings, learned, after, seconds)


#: The case study's expert: short delay, little noise, no lapses or wrong keys.
EXPERT = ParticipantParams(
    reaction_time=0.25,
    perception_noise=0.003,
    deadband=0.008,
    lapse_rate=0.0,
    lapse_duration=0.5,
    wrong_key=0.0,
    max_keys=3,
)


def run_case_study(
    scene: Scene, settings: StudySettings, *, work_dir: Path
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The expert case study (paper, Sec. IV) and the arbitration comparison.

    The expert does each task with PBA and CASA before learning, demonstrates the
    unknown tasks ``settings.demonstrations`` times (5, :meth:`StudySettings.from_case_study`),
    and does them again with CASA after learning. Logs and the learned intents go to
    ``work_dir``.

    Returns
    -------
    steps : DataFrame
        Per tick and intent: ``participant, task, method, phase, t, alpha, intent,
        beta, belief``.
    arbitration : DataFrame
        :func:`casa_core.study.arbitration_comparison.compare_arbitrations` along the
        optimal trajectory to the red goal, known goals green and purple.
    """
    from casa_core.analysis.datasets import build_tables
    from casa_core.assist.assistant import Assistant
    from casa_core.assist.intents import GoalIntent
    from casa_core.study.arbitration_comparison import compare_arbitrations

    work_dir = Path(work_dir)
    after = work_dir / "logs" / "after"
    simulate_protocol(
        0,
        scene,
        settings=settings,
        before_dir=work_dir / "logs" / "before",
        after_dir=after,
        libraries=dict.fromkeys(UNKNOWN_TASKS, work_dir / "library"),
        params=EXPERT,
        pid="expert",
    )
    (after / SURVEYS_NAME).unlink()  # the expert answers no survey
    steps = build_tables(work_dir / "logs", scene, dataset="case_study").steps
    steps = steps[
        steps["method"].isin(list(ASSISTED_METHODS)) & (steps["phase"] != "demonstration")
    ]
    steps = steps[list(CASE_STEPS_COLUMNS)].reset_index(drop=True)

    inference = settings.inference
    trajectory = GoalIntent("red", scene.goals["red"]).optimal_trajectory(
        scene.start_state, HORIZON
    )
    intents = known_goal_intents(scene, **inference.goal_options())
    arbitration = compare_arbitrations(
        Assistant(intents, **inference.assistant_options()), trajectory
    )
    return steps, arbitration
