"""The simulated study and the expert case study, run through the robot in pybullet.

Each participant is simulated in three separate jobs so that a workflow can
spread them over cores: :func:`simulate_before_learning` (familiarization, Known
Goal, the unknown tasks before learning and the demonstrations),
:func:`learn_from_demonstrations` (one per unknown task) and
:func:`simulate_after_learning` (CASA with the learned intents, then the Likert
answers). Every random draw comes from ``seed`` through
``numpy.random.default_rng([seed, participant_index, stream])``, so a
participant's trials do not depend on how many participants there are.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from casa_core import metrics
from casa_core.config import default
from casa_core.defaults import DEMONSTRATIONS
from casa_core.io import SURVEY_COLUMNS, SURVEYS_NAME, read_trial, write_surveys
from casa_core.presets import DEFAULT_PRESET, Preset, preset
from casa_core.scene import Scene
from casa_core.study import likert, protocol
from casa_core.study.closed_loop import as_preset, known_goal_intents, run_trial, trial_intents
from casa_core.study.participants import ParticipantParams, draw_participants, make_participant
from casa_core.tasks import intended_trajectory
from casa_core.vocabulary import LEARNED_NAMES, UNANALYSED_PHASES, UNKNOWN_TASKS

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


def participant_params(index: int, simulation: dict) -> ParticipantParams:
    """The participant's operator parameters, drawn from the population of the config."""
    check_index(index)
    rng = np.random.default_rng([simulation["seed"], index, PARAMS_STREAM])
    return draw_participants(1, simulation["population"], rng)[0]


def inference_preset(config: dict) -> Preset:
    """The inference preset of a workflow config's ``inference`` block.

    Examples
    --------
    >>> inference_preset({"inference": {"preset": "original", "evidence": None}}).evidence
    'executed'
    """
    settings = config["inference"]
    return preset(settings["preset"], evidence=settings["evidence"])


def _run(scene, spec, settings, params, rng, pid, sim, inference, intents=None):
    reference = intended_trajectory(spec.task, scene)
    # The operator model (casa_core.study.participants); the schema's default if unset.
    operator = settings.get("operator") or default("simulation.operator")
    source = make_participant(params, reference, rng=rng, tick=scene.teleop.dt, operator=operator)
    result = run_trial(
        scene,
        spec.task,
        spec.method,
        source,
        participant=pid,
        intents=intents,
        phase=spec.phase,
        max_duration=settings["max_duration"],
        sim=sim,
        inference=inference,
        seed=int(settings["seed"]),
    )
    return result


def simulate_before_learning(
    index: int,
    scene: Scene,
    *,
    simulation: dict,
    out_dir: Path,
    params: ParticipantParams | None = None,
    pid: str | None = None,
    inference: Preset | str = DEFAULT_PRESET,
) -> list[Path]:
    """Phases 1-3 and the demonstrations of one participant; returns the logs' stems.

    After the CASA trial of each unknown task the robot checks for misspecification
    (:func:`casa_core.study.protocol.misspecification_detected`, noted in the log); with
    ``simulation["demonstrations_when"] == "detected"`` it asks for demonstrations
    only then, with ``"always"`` (the paper's protocol) every time.
    """
    from casa_core.robot.sim import ArmSimulation

    check_index(index)
    pid = pid or participant_id(index)
    params = params or participant_params(index, simulation)
    seed = int(simulation["seed"])
    epsilon = float(simulation["epsilon"])
    out_dir = Path(out_dir)
    specs = protocol.before_learning(index)
    written = []
    with ArmSimulation(scene) as sim:
        detected = {}
        for stream, spec in enumerate(specs, start=1):
            rng = np.random.default_rng([seed, index, stream])
            result = _run(scene, spec, simulation, params, rng, pid, sim, inference)
            if spec.method == "CASA" and spec.phase == "before_learning":
                detected[spec.task] = protocol.misspecification_detected(result.frame, epsilon)
                note = f"misspecification detected: {detected[spec.task]}"
                result.meta["notes"] = "; ".join(filter(None, [result.meta.get("notes"), note]))
            result.write(out_dir / spec.stem)
            written.append(out_dir / spec.stem)
        stream = len(specs) + 1
        for task in protocol.demonstration_tasks(simulation["demonstrations_when"], detected):
            for spec in protocol.demonstrations(task, simulation["demonstrations"]):
                rng = np.random.default_rng([seed, index, stream])
                stream += 1
                result = _run(scene, spec, simulation, params, rng, pid, sim, inference)
                result.write(out_dir / spec.stem)
                written.append(out_dir / spec.stem)
    return written


def learn_from_demonstrations(
    demos_dir: Path, task: str, *, scene: Scene, seed: int, library: Path, pid: str
) -> tuple[dict, dict]:
    """Learn the intent of ``task`` from the participant's demonstrations into ``library``.

    Returns the row of ``learning.csv`` (``participant, task, intent,
    endpoint_error_m, final_tilt_deg``; empty values when the participant gave no
    demonstrations of the task) and the row of ``learning_timing.csv``
    (``participant, task, intent, train_seconds``): measured times are kept apart, so
    that the results are the same bytes on every run.
    """
    from casa_core.library import load_intent
    from casa_core.study.learn_from_logs import learn_to_library, read_demonstrations
    from casa_core.study.learning_evidence import learning_evidence, scene_objects

    name = LEARNED_NAMES[task]
    row = {
        "participant": pid,
        "task": task,
        "intent": name,
        "endpoint_error_m": np.nan,
        "final_tilt_deg": np.nan,
    }
    timing = {"participant": pid, "task": task, "intent": name, "train_seconds": np.nan}
    demo_stems = [p for p in Path(demos_dir).glob(f"{task}_demonstration_*.json")]
    if not demo_stems:
        return row, timing
    path, _history, seconds = learn_to_library(
        demos_dir,
        name,
        library=library,
        objects=scene_objects(scene),
        seed=seed,
        task=task,
        participant=pid,
    )
    demos, _ = read_demonstrations(demos_dir, task)
    evidence = learning_evidence(load_intent(path).intent, demos)
    row.update(evidence)
    timing["train_seconds"] = seconds
    return row, timing


def simulate_after_learning(
    index: int,
    scene: Scene,
    *,
    simulation: dict,
    learned: list[Path],
    before_dir: Path,
    out_dir: Path,
    params: ParticipantParams | None = None,
    pid: str | None = None,
    inference: Preset | str = DEFAULT_PRESET,
) -> list[Path]:
    """Phase 4 (CASA with every learned intent), then ``surveys.csv`` for all conditions."""
    from casa_core.robot.sim import ArmSimulation

    check_index(index)
    pid = pid or participant_id(index)
    params = params or participant_params(index, simulation)
    seed = int(simulation["seed"])
    out_dir = Path(out_dir)
    written = []
    if learned:
        intents = trial_intents(scene, learned, inference=inference)
        with ArmSimulation(scene) as sim:
            for offset, spec in enumerate(protocol.after_learning()):
                rng = np.random.default_rng([seed, index, 1000 + offset])
                result = _run(
                    scene, spec, simulation, params, rng, pid, sim, inference, intents=intents
                )
                result.write(out_dir / spec.stem)
                written.append(out_dir / spec.stem)
    surveys = simulated_surveys(
        pid,
        [Path(before_dir), out_dir],
        scene=scene,
        rng=np.random.default_rng([seed, index, LIKERT_STREAM]),
    )
    write_surveys(out_dir / SURVEYS_NAME, surveys)
    return written


def simulated_surveys(
    pid: str, folders: list[Path], *, scene: Scene, rng: np.random.Generator
) -> pd.DataFrame:
    """Likert answers (:mod:`casa_core.study.likert`) for every condition of one participant."""
    dt = scene.teleop.dt
    trials = {}
    for folder in folders:
        for json_path in sorted(Path(folder).glob("*.json")):
            meta, frame = read_trial(json_path.with_suffix(""))
            if meta["phase"] in UNANALYSED_PHASES:
                continue
            measured = metrics.trial_metrics(frame, intended_trajectory(meta["task"], scene), dt=dt)
            trials[(meta["task"], meta["method"], meta["phase"])] = (measured, frame)
    bias = 0.5 * rng.standard_normal()
    rows = []
    for (task, method, phase), (measured, frame) in sorted(trials.items()):
        reference = next(
            (m for (t, me, _), (m, _f) in trials.items() if t == task and me == "NA"), measured
        )
        effort_gain = 1 - measured["effort"] / max(reference["effort"], 1)
        error_gain = 1 - measured["error"] / reference["error"] if reference["error"] > 0 else 0.0
        felt = likert.experience(frame)
        latent = likert.latent_impressions(felt["help"], felt["fight"], effort_gain, error_gain)
        for question, score in likert.answer(latent, bias, rng).items():
            rows.append(
                {
                    "participant": pid,
                    "task": task,
                    "method": method,
                    "phase": phase,
                    "question": question,
                    "score": score,
                    "source": "simulated",
                }
            )
    return pd.DataFrame(rows, columns=[*SURVEY_COLUMNS, "source"])


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
    scene: Scene,
    case_study: dict,
    *,
    work_dir: Path,
    inference: Preset | str = DEFAULT_PRESET,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The expert case study (paper, Sec. IV) and the arbitration comparison.

    The expert does each task with PBA and CASA before learning, demonstrates the
    unknown tasks 5 times, and does them again with CASA after learning. Logs and
    the learned intents go to ``work_dir``.

    Returns
    -------
    steps : DataFrame
        Per tick and intent: ``participant, task, method, phase, t, alpha, intent,
        beta, belief``.
    arbitration : DataFrame
        :func:`casa_core.study.arbitration_comparison.compare_arbitrations` along the
        optimal trajectory to the red goal, known goals green and purple.
    """
    from casa_core.assistant import Assistant
    from casa_core.datasets import build_tables
    from casa_core.intents import GoalIntent
    from casa_core.study.arbitration_comparison import compare_arbitrations

    work_dir = Path(work_dir)
    settings = {
        "seed": case_study["seed"],
        "max_duration": case_study["max_duration"],
        "demonstrations": DEMONSTRATIONS,
        "demonstrations_when": "always",
        "epsilon": case_study["epsilon"],
        "operator": case_study.get("operator") or default("case_study.operator"),
    }
    before = work_dir / "logs" / "before"
    simulate_before_learning(
        0,
        scene,
        simulation=settings,
        out_dir=before,
        params=EXPERT,
        pid="expert",
        inference=inference,
    )
    learned = []
    for task in UNKNOWN_TASKS:
        learn_from_demonstrations(
            before,
            task,
            scene=scene,
            seed=case_study["seed"],
            library=work_dir / "library",
            pid="expert",
        )
        learned.append(work_dir / "library" / f"{LEARNED_NAMES[task]}.intent.json")
    after = work_dir / "logs" / "after"
    simulate_after_learning(
        0,
        scene,
        simulation=settings,
        learned=learned,
        before_dir=before,
        out_dir=after,
        params=EXPERT,
        pid="expert",
        inference=inference,
    )
    (after / SURVEYS_NAME).unlink()  # the expert answers no survey
    steps = build_tables(work_dir / "logs", scene, dataset="case_study").steps
    steps = steps[steps["method"].isin(["PBA", "CASA"]) & (steps["phase"] != "demonstration")]
    columns = ["participant", "task", "method", "phase", "t", "alpha", "intent", "beta", "belief"]
    steps = steps[columns].reset_index(drop=True)

    inference = as_preset(inference)
    trajectory = GoalIntent("red", scene.goals["red"]).optimal_trajectory(scene.start_state, 15.0)
    intents = known_goal_intents(scene, **inference.goal_options())
    arbitration = compare_arbitrations(
        Assistant(intents, **inference.assistant_options()), trajectory
    )
    return steps, arbitration
