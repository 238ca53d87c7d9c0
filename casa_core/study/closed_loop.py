"""The closed loop: one task, one assistance method, one key source, pybullet in the loop.

Every control tick (0.05 s) :func:`run_trial` reads the arm's state ``[x, y, z, rot]``
from pybullet, asks the key source (:mod:`casa_core.study.key_sources`) which keys are
held, turns them into the user's action (the paper's direct teleoperation T), lets the
:class:`~casa_core.assist.assistant.Assistant` blend it with the robot's action u*, and
drives the arm with the blend for one tick, the way the scene's ``teleop.mode`` says
(:mod:`casa_core.study.drive`). Every 0.5 s (twice per second, as in
the paper) the assistant first updates its inference with the state reached. The trial
ends when the key source says it is done or at ``max_duration``; in a scene with a
``trial_length`` (the original's protocol) it runs exactly that long, whatever the source
says.

The methods are the paper's: NA (direct teleoperation; the assistant still infers, so
the log shows what it would have believed), PBA (policy blending with distance
arbitration and beta = 1), CASA (confidence arbitration) and BELIEF (arbitration on
the belief in the most likely intent, for the arbitration analysis only: casa-trial/1
has no BELIEF method, so such trials are returned, not written).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from casa_core.assist.assistant import Assistant
from casa_core.assist.intents import GoalIntent, Intent
from casa_core.assist.presets import DEFAULT_PRESET, Preset, preset
from casa_core.assist.trial import inference_ticks, scene_assistant
from casa_core.io import write_trial
from casa_core.io.contract import COMMAND_COLUMNS
from casa_core.robot.keys import check_keys, format_keys
from casa_core.robot.sim import ArmSimulation
from casa_core.scene import KNOWN_GOALS, Scene
from casa_core.study.command_sources import CommandSource, checked_command, is_continuous
from casa_core.study.drive import scene_drive
from casa_core.study.key_sources import KeySource
from casa_core.study.participants import ParticipantParams, make_participant
from casa_core.vocabulary import METHODS, POINTS, TASK_PHASES, TRIAL_ARBITRATION


@dataclass
class TrialResult:
    """A finished trial: its casa-trial/1 metadata and one row per control tick."""

    meta: dict
    frame: pd.DataFrame

    def write(self, stem: Path | str) -> tuple[dict, pd.DataFrame]:
        """Write ``<stem>.json`` and ``<stem>.csv`` through :func:`casa_core.io.write_trial`.

        Returns the trial as :func:`casa_core.io.read_trial` reads it back.
        """
        if self.meta["method"] not in METHODS:
            raise ValueError(
                f"method {self.meta['method']!r} cannot be logged: casa-trial/1 methods are "
                f"{', '.join(METHODS)}; use the returned frame instead"
            )
        return write_trial(stem, self.meta, self.frame)


def known_goal_intents(scene: Scene, names: Sequence[str] = KNOWN_GOALS, **options) -> list:
    """Goal intents for the named goals of the scene (``scene.goals``).

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> [intent.name for intent in known_goal_intents(load_scene())]
    ['green', 'purple']
    """
    missing = [name for name in names if name not in scene.goals]
    if missing:
        raise ValueError(f"scene: goals has no {', '.join(missing)}")
    return [GoalIntent(name, scene.goals[name], **options) for name in names]


def trial_intents(
    scene: Scene, learned: Sequence[Path | str] = (), *, inference: Preset | str = DEFAULT_PRESET
) -> list:
    """What the robot knows: the known goals, then each learned intent file (casa-intent).

    The goals' cost is the one of the ``inference`` preset (:mod:`casa_core.assist.presets`).

    Raises
    ------
    casa_core.learning.library.LibraryError
        (a ``ValueError``) naming a learned-intent file that cannot be used.
    """
    intents = known_goal_intents(scene, **as_preset(inference).goal_options())
    if learned:
        from casa_core.learning.library import (
            load_intent,  # torch and the IRL code load only if needed
        )

        intents += [load_intent(path).intent for path in learned]
    return intents


def as_preset(inference: Preset | str) -> Preset:
    """The preset itself, or the preset of that name."""
    return inference if isinstance(inference, Preset) else preset(inference)


def default_phase(task: str) -> str:
    """The phase of a task's first trial: ``before_learning`` for the unknown tasks.

    Examples
    --------
    >>> default_phase("known_goal"), default_phase("unknown_skill")
    ('no_misspecification', 'before_learning')
    """
    if task not in TASK_PHASES:
        raise ValueError(f"unknown task {task!r}; expected one of {', '.join(TASK_PHASES)}")
    phases = TASK_PHASES[task]
    return "before_learning" if "before_learning" in phases else phases[0]


def run_trial(
    scene: Scene,
    task: str,
    method: str,
    source: KeySource | CommandSource,
    *,
    participant: str,
    intents: Sequence[Intent] | None = None,
    phase: str | None = None,
    source_kind: str = "simulated",
    max_duration: float = 30.0,
    sim: ArmSimulation | None = None,
    inference: Preset | str = DEFAULT_PRESET,
    assistant_options: dict | None = None,
    on_tick: Callable[[float, np.ndarray, frozenset, float], None] | None = None,
    seed: int | None = None,
) -> TrialResult:
    """Run one trial in closed loop with pybullet and return its log.

    Parameters
    ----------
    scene : Scene
        The task scene; the arm starts at ``scene.start_state``.
    task : str
        ``familiarization``, ``known_goal``, ``unknown_goal`` or ``unknown_skill``.
    method : {"NA", "PBA", "CASA", "BELIEF"}
    source : KeySource or CommandSource
        Gives the held keys each tick, or a continuous device's commanded velocity
        (:mod:`casa_core.study.command_sources`: the log then has the command columns and
        its metadata the device, ``input``). The trial ends when ``source.done`` turns true,
        unless the scene fixes the trial's length (``scene.trial_length``); a device
        lost (``source.lost``) ends it in either case, the arm stopped.
    participant : str
        Participant id written to the log.
    intents : sequence of Intent, optional
        What the robot knows; default the known goals green and purple, with the
        goal cost of the ``inference`` preset.
    phase : str, optional
        Log phase; default :func:`default_phase` of the task.
    source_kind : {"simulated", "human"}
    max_duration : float
        Seconds after which the trial stops even if the source is not done; a scene's
        ``trial_length`` takes its place.
    sim : ArmSimulation, optional
        Simulation to run in (e.g. a window); default a new headless one, closed after.
    inference : Preset or str, default "casa"
        The inference preset (:mod:`casa_core.assist.presets`): the assistant's evidence,
        prior, suboptimality scale and goal cost.
    assistant_options : dict, optional
        Extra keyword arguments of :class:`~casa_core.assist.assistant.Assistant`, over the
        preset's.
    on_tick : callable, optional
        ``on_tick(t, state, keys, alpha)`` after each logged tick (windows, pacing).
    seed : int, optional
        Recorded in the metadata.

    Returns
    -------
    TrialResult
    """
    if method not in TRIAL_ARBITRATION:
        raise ValueError(f"unknown method {method!r}; expected one of {list(TRIAL_ARBITRATION)}")
    phase = default_phase(task) if phase is None else phase
    inference = as_preset(inference)
    if intents is None:
        intents = known_goal_intents(scene, **inference.goal_options())
    intents = list(intents)
    ticks_per_inference = inference_ticks(scene)
    if scene.trial_length is not None:
        max_duration = scene.trial_length
    assistant = trial_assistant(scene, method, intents, inference, assistant_options)
    own_sim = sim is None
    if sim is None:
        sim = ArmSimulation(scene)
    try:
        rows = _closed_loop(
            sim, assistant, source, scene, ticks_per_inference, max_duration, on_tick
        )
    finally:
        if own_sim:
            sim.close()
    meta = trial_meta(
        participant,
        task,
        method,
        phase,
        source_kind,
        assistant,
        inference,
        max_duration,
        point=scene.point,
    )
    if seed is not None:
        meta["seed"] = int(seed)
    if is_continuous(source):
        meta["input"] = source.input
    return TrialResult(meta=meta, frame=pd.DataFrame(rows))


def simulated_trial(
    scene: Scene,
    planned,
    reference,
    params: ParticipantParams,
    rng: np.random.Generator,
    *,
    participant: str,
    operator: str,
    max_duration: float,
    sim: ArmSimulation | None,
    inference: Preset | str,
    **options,
) -> TrialResult:
    """:func:`run_trial` of ``planned`` (its task, method and phase) by a simulated participant.

    The participant (:func:`~casa_core.study.participants.make_participant`, operator
    model ``operator``) has ``params``, draws from ``rng`` and follows ``reference``, the
    task's intended trajectory, at the scene's tick and speeds; ``options`` go to
    :func:`run_trial`.
    """
    teleop = scene.teleop
    source = make_participant(
        params,
        reference,
        rng=rng,
        tick=teleop.dt,
        operator=operator,
        speed=teleop.speed,
        rot_speed=teleop.rot_speed,
    )
    return run_trial(
        scene,
        planned.task,
        planned.method,
        source,
        participant=participant,
        phase=planned.phase,
        max_duration=max_duration,
        sim=sim,
        inference=inference,
        **options,
    )


def trial_assistant(
    scene: Scene,
    method: str,
    intents: Sequence[Intent],
    inference: Preset,
    assistant_options: dict | None = None,
) -> Assistant:
    """The :class:`Assistant` of one trial (:func:`~casa_core.assist.trial.scene_assistant`):
    the method's arbitration, the preset's inference (``assistant_options`` over it)."""
    return scene_assistant(
        scene,
        intents,
        arbitration=TRIAL_ARBITRATION[method],
        **{**inference.assistant_options(), **(assistant_options or {})},
    )


def trial_meta(
    participant: str,
    task: str,
    method: str,
    phase: str,
    source_kind: str,
    assistant: Assistant,
    inference: Preset,
    max_duration: float,
    *,
    point: str = POINTS[0],
) -> dict:
    """A trial's casa-trial/1 metadata, what inference assumed included: ``point`` is
    where the arm was measured (the scene's), written when it is not the tool point."""
    meta = {
        "participant": str(participant),
        "task": task,
        "method": method,
        "phase": phase,
        "source": source_kind,
        "intents": list(assistant.names),
        "max_duration": float(max_duration),  # so a reader can tell a trial that ran out
    }
    # What inference assumed, so that a replay can redo it (casa_core.analysis.replay).
    measured: dict[str, str] = {"preset": inference.name, "evidence": assistant.evidence}
    if point != POINTS[0]:
        measured["point"] = point
    meta["inference"] = measured
    return meta


def _closed_loop(sim, assistant, source, scene, ticks_per_inference, max_duration, on_tick):
    dt = scene.teleop.dt
    until_done = scene.trial_length is None
    drive = scene_drive(sim, scene)
    continuous = is_continuous(source)
    state = drive.start()
    assistant.reset(state)
    names = assistant.names
    beta, belief, alpha = assistant.beta, assistant.belief, assistant.alpha  # before inference
    rows = []
    # Column names made once (the row's columns, in the log's order).
    q_columns = [f"q{i + 1}" for i in range(len(sim.q))]
    beta_columns = [(f"beta:{name}", name) for name in names]
    belief_columns = [(f"belief:{name}", name) for name in names]
    for tick in range(int(round(max_duration / dt)) + 1):
        t = tick * dt
        if tick > 0 and tick % ticks_per_inference == 0:
            assistant.update(state)
            beta, belief, alpha = assistant.beta, assistant.belief, assistant.alpha
        x, y, z, rot = state.tolist()
        if continuous:
            held, command = frozenset(), checked_command(source.command(t, state))
            row = {"t": round(t, 6), "x": x, "y": y, "z": z, "rot": rot, "keys": ""}
            row.update(zip(COMMAND_COLUMNS, command.tolist(), strict=True))
        else:
            held, command = check_keys(source.keys(t, state)), None
            row = {"t": round(t, 6), "x": x, "y": y, "z": z, "rot": rot}
            row["keys"] = format_keys(held)
        row["alpha"] = alpha
        row.update(zip(q_columns, sim.q.tolist(), strict=True))
        for column, name in beta_columns:
            row[column] = beta[name]
        for column, name in belief_columns:
            row[column] = belief[name]
        rows.append(row)
        if on_tick is not None:
            on_tick(t, state, held, alpha)
        # A trial ended at once still has its start and one tick (the log's two-rows rule).
        if tick > 0 and _ends(source, until_done):
            break
        elapsed = (tick % ticks_per_inference) * dt
        state = drive.tick(assistant, state, held, elapsed, command=command)
    return rows


def _ends(source, until_done: bool) -> bool:
    """Whether the source ends the trial: when done, or, in a trial of fixed length, only
    when it stops it (a person's pause, ``paused``, or a device lost, ``lost``)."""
    if getattr(source, "lost", None):
        return True
    return bool(getattr(source, "done" if until_done else "paused", False))
