"""The trial runner: one task, one assistance method, one key source, pybullet in the loop.

Every control tick (0.05 s) the runner reads the arm's state ``[x, y, z, rot]`` from
pybullet, asks the key source which keys are held, turns them into the user's
Cartesian action (the paper's direct teleoperation T), lets the
:class:`~casa_core.assistant.Assistant` blend it with the robot's action u*, and drives
the arm with the blend for one tick. Every 0.5 s (twice per second, as in the paper)
the assistant first updates its inference with the state reached. The trial ends
when the key source says it is done or at ``max_duration``.

The methods are the paper's: NA (direct teleoperation; the assistant still infers, so
the log shows what it would have believed), PBA (policy blending with distance
arbitration and beta = 1), CASA (confidence arbitration) and BELIEF (arbitration on
the belief in the most likely intent, for the arbitration analysis only: casa-trial/1
has no BELIEF method, so such trials are returned, not written).

A key source is anything with ``keys(t, state) -> iterable of key names`` and a
``done`` attribute, such as :class:`casa_core.study.participants.SimulatedParticipant`,
:class:`ScriptedKeys` or the keyboard of ``casa teleop``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Protocol

import numpy as np
import pandas as pd

from casa_core.assistant import Assistant
from casa_core.intents import GoalIntent, Intent
from casa_core.logs import METHODS as LOG_METHODS
from casa_core.logs import SCHEMA, TASK_PHASES, check_meta, read_trial, write_trial
from casa_core.robot.keys import check_keys, format_keys, keys_to_action
from casa_core.robot.sim import ArmSimulation
from casa_core.robot.teleop import KeyboardKeys, Window
from casa_core.study.protocol import TrialSpec, demonstrations, misspecification_detected

#: Arbitration of the assistant under each method.
METHOD_ARBITRATION = {"NA": "none", "PBA": "distance", "CASA": "confidence", "BELIEF": "belief"}
#: The goals the robot knows from the start (paper, Sec. IV).
KNOWN_GOALS = ("green", "purple")
#: Seconds between inference steps: twice per second (paper, Sec. IV-A).
INFERENCE_PERIOD = 0.5


class KeySource(Protocol):
    """Anything that yields the held keys each tick given the observed state."""

    done: bool

    def keys(self, t: float, state: np.ndarray) -> Iterable[str]:
        """Keys held during the tick starting at ``t`` seconds, given ``[x, y, z, rot]``."""
        ...


@dataclass
class ScriptedKeys:
    """A fixed sequence of held keys: ``[(seconds, keys), ...]``, then done.

    Parameters
    ----------
    script : sequence of (float, iterable of str)
        Each entry holds ``keys`` for ``seconds`` (rounded to whole ticks).
    dt : float
        Control tick, s.
    """

    script: Sequence[tuple[float, Iterable[str]]]
    dt: float = 0.05
    done: bool = field(default=False, init=False)

    def __post_init__(self):
        self._ticks: list[frozenset[str]] = []
        for index, (seconds, keys) in enumerate(self.script):
            if not seconds >= 0:
                raise ValueError(f"script entry {index}: seconds must be >= 0, got {seconds!r}")
            held = check_keys(keys)
            self._ticks += [held] * int(round(seconds / self.dt))
        self._next = 0

    def keys(self, t: float, state) -> frozenset[str]:
        if self._next >= len(self._ticks):
            self.done = True
            return frozenset()
        held = self._ticks[self._next]
        self._next += 1
        return held


@dataclass
class WaypointKeys:
    """A scripted expert: holds the keys toward each waypoint in turn, then is done.

    Holds the key of every axis of ``[x, y, z, rot]`` whose error exceeds the
    tolerance; moves to the next waypoint when all are within it. Deterministic,
    for tests and benchmarks; the study's participants are in
    :mod:`casa_core.study.participants`.
    """

    waypoints: np.ndarray
    tolerance: float = 0.005
    rot_tolerance: float = 0.05
    done: bool = field(default=False, init=False)

    def __post_init__(self):
        self.waypoints = np.asarray(self.waypoints, dtype=float)
        if self.waypoints.ndim != 2 or self.waypoints.shape[1] != 4:
            raise ValueError(f"waypoints must have shape (n, 4), got {self.waypoints.shape}")
        self._index = 0

    def keys(self, t: float, state) -> frozenset[str]:
        tolerance = np.array([self.tolerance] * 3 + [self.rot_tolerance])
        while self._index < len(self.waypoints):
            error = self.waypoints[self._index] - np.asarray(state, dtype=float)
            if np.any(np.abs(error) > tolerance):
                names = (("x+", "x-"), ("y+", "y-"), ("z+", "z-"), ("rot+", "rot-"))
                return frozenset(
                    plus if e > 0 else minus
                    for e, tol, (plus, minus) in zip(error, tolerance, names, strict=True)
                    if abs(e) > tol
                )
            self._index += 1
        self.done = True
        return frozenset()


@dataclass
class TrialResult:
    """A finished trial: its casa-trial/1 metadata and one row per control tick."""

    meta: dict
    frame: pd.DataFrame

    def write(self, stem: Path | str) -> None:
        """Write ``<stem>.json`` and ``<stem>.csv`` through :func:`casa_core.logs.write_trial`."""
        if self.meta["method"] not in LOG_METHODS:
            raise ValueError(
                f"method {self.meta['method']!r} cannot be logged: casa-trial/1 methods are "
                f"{', '.join(LOG_METHODS)}; use the returned frame instead"
            )
        write_trial(stem, self.meta, self.frame)


def known_goal_intents(layout: dict, names: Sequence[str] = KNOWN_GOALS, **options) -> list:
    """Goal intents for the named goals of the scene layout (``goals.NAME``)."""
    goals = layout.get("goals", {})
    missing = [name for name in names if name not in goals]
    if missing:
        raise ValueError(f"scene layout: goals has no {', '.join(missing)}")
    return [GoalIntent(name, goals[name], **options) for name in names]


def trial_intents(layout: dict, learned: Sequence[Path | str] = ()) -> list:
    """What the robot knows: the known goals, then each learned intent file (casa-intent/1).

    Raises
    ------
    casa_core.library.LibraryError
        (a ``ValueError``) naming a learned-intent file that cannot be used.
    """
    intents = known_goal_intents(layout)
    if learned:
        from casa_core.library import load_intent  # torch and the IRL code load only if needed

        intents += [load_intent(path).intent for path in learned]
    return intents


def default_phase(task: str) -> str:
    """The phase of a task's first trial: ``before_learning`` for the unknown tasks."""
    if task not in TASK_PHASES:
        raise ValueError(f"unknown task {task!r}; expected one of {', '.join(TASK_PHASES)}")
    phases = TASK_PHASES[task]
    return "before_learning" if "before_learning" in phases else phases[0]


def run_trial(
    layout: dict,
    task: str,
    method: str,
    source: KeySource,
    *,
    participant: str,
    intents: Sequence[Intent] | None = None,
    phase: str | None = None,
    source_kind: str = "simulated",
    max_duration: float = 30.0,
    sim: ArmSimulation | None = None,
    assistant_options: dict | None = None,
    on_tick: Callable[[float, np.ndarray, frozenset, float], None] | None = None,
    seed: int | None = None,
) -> TrialResult:
    """Run one trial in closed loop with pybullet and return its log.

    Parameters
    ----------
    layout : dict
        Scene layout (``config/scene.yaml``); the arm starts at ``start``.
    task : str
        ``familiarization``, ``known_goal``, ``unknown_goal`` or ``unknown_skill``.
    method : {"NA", "PBA", "CASA", "BELIEF"}
    source : KeySource
        Gives the held keys each tick; the trial ends when ``source.done`` turns true.
    participant : str
        Participant id written to the log.
    intents : sequence of Intent, optional
        What the robot knows; default the known goals green and purple.
    phase : str, optional
        Log phase; default :func:`default_phase` of the task.
    source_kind : {"simulated", "human"}
    max_duration : float
        Seconds after which the trial stops even if the source is not done.
    sim : ArmSimulation, optional
        Simulation to run in (e.g. a window); default a new headless one, closed after.
    assistant_options : dict, optional
        Extra keyword arguments of :class:`~casa_core.assistant.Assistant`.
    on_tick : callable, optional
        ``on_tick(t, state, keys, alpha)`` after each logged tick (windows, pacing).
    seed : int, optional
        Recorded in the metadata.

    Returns
    -------
    TrialResult
    """
    if method not in METHOD_ARBITRATION:
        raise ValueError(f"unknown method {method!r}; expected one of {list(METHOD_ARBITRATION)}")
    phase = default_phase(task) if phase is None else phase
    intents = known_goal_intents(layout) if intents is None else list(intents)
    teleop = layout["teleop"]
    dt = float(teleop["dt"])
    ticks_per_inference = int(round(INFERENCE_PERIOD / dt))
    if ticks_per_inference < 1 or abs(ticks_per_inference * dt - INFERENCE_PERIOD) > 1e-9:
        raise ValueError(
            f"scene layout: teleop.dt = {dt} s must divide the inference period "
            f"{INFERENCE_PERIOD} s into whole ticks"
        )
    assistant = Assistant(
        intents,
        arbitration=METHOD_ARBITRATION[method],
        dt=INFERENCE_PERIOD,
        speed=teleop["speed"],
        rot_speed=teleop["rot_speed"],
        tick=dt,
        **(assistant_options or {}),
    )
    own_sim = sim is None
    sim = ArmSimulation(layout) if own_sim else sim
    try:
        rows = _closed_loop(
            sim, assistant, source, layout, dt, ticks_per_inference, max_duration, on_tick
        )
    finally:
        if own_sim:
            sim.close()
    meta = {
        "participant": str(participant),
        "task": task,
        "method": method,
        "phase": phase,
        "source": source_kind,
        "intents": [intent.name for intent in intents],
    }
    if assistant.arbitration != "none":  # what inference observed (Assistant, evidence)
        meta["notes"] = f"evidence: {assistant.evidence}"
    if seed is not None:
        meta["seed"] = int(seed)
    return TrialResult(meta=meta, frame=pd.DataFrame(rows))


def _closed_loop(sim, assistant, source, layout, dt, ticks_per_inference, max_duration, on_tick):
    teleop = layout["teleop"]
    start = np.array([*layout["start"]["position"], layout["start"]["rot"]], dtype=float)
    state = sim.reset(start)
    assistant.reset(state)
    names = assistant.names
    # No evidence before the first inference step: beta_hat = 0, uniform belief.
    beta = dict.fromkeys(names, 0.0)
    belief = dict.fromkeys(names, 1.0 / len(names))
    alpha = 1.0
    rows = []
    for tick in range(int(round(max_duration / dt)) + 1):
        t = tick * dt
        if tick > 0 and tick % ticks_per_inference == 0:
            inference = assistant.update(state)
            beta, belief, alpha = inference.beta, inference.belief, inference.alpha
        held = check_keys(source.keys(t, state))
        row = {"t": round(t, 6), "x": state[0], "y": state[1], "z": state[2], "rot": state[3]}
        row["keys"] = format_keys(held)
        row["alpha"] = alpha
        row.update({f"q{i + 1}": angle for i, angle in enumerate(sim.q)})
        row.update({f"beta:{name}": beta[name] for name in names})
        row.update({f"belief:{name}": belief[name] for name in names})
        rows.append(row)
        if on_tick is not None:
            on_tick(t, state, held, alpha)
        if getattr(source, "done", False):
            break
        user_action = keys_to_action(held, teleop["speed"], teleop["rot_speed"])
        elapsed = (tick % ticks_per_inference) * dt
        action = assistant.act(state, user_action, elapsed_in_step=elapsed)
        state = sim.step(action)
    return rows


def run_teleop(
    layout: dict,
    task: str,
    method: str,
    participant: str,
    out: Path | str,
    *,
    phase: str | None = None,
    gui: bool = True,
    key_source=None,
    countdown: int = 3,
    realtime: bool = True,
    max_duration: float = 60.0,
    intents=None,
    repeat: int = 0,
    title: str | None = None,
    assistant_options: dict | None = None,
) -> Path:
    """Run one teleoperated trial and write its log; return the log's stem.

    The log goes to ``OUT/<task>_<phase>_<method>`` (``_<repeat + 1>`` added for a
    demonstration), the protocol's naming (:class:`casa_core.study.protocol.TrialSpec`).

    Parameters
    ----------
    layout : dict
        Scene layout (``config/scene.yaml``).
    task, method, participant, phase :
        As in :func:`casa_core.study.trial.run_trial`.
    out : path
        Folder of the log (created); an existing log there is never overwritten.
    gui : bool
        Open a window; False runs headless (tests).
    key_source : KeySource, optional
        Default the window's keyboard (:class:`KeyboardKeys`); a scripted source makes
        the trial reproducible and its log's source "simulated".
    countdown : int
        Seconds of countdown before the trial starts.
    realtime : bool
        Pace the loop at 20 Hz in the window (off for tests).
    max_duration : float
        Seconds after which the trial ends if Enter was not pressed.
    intents : sequence of Intent, optional
        What the robot knows; default the known goals green and purple.
    repeat : int
        Which demonstration this is (0-based), for the log's name.
    title : str, optional
        Shown in the window before the countdown; default task and method.
    assistant_options : dict, optional
        Extra keyword arguments of :class:`~casa_core.assistant.Assistant` (e.g.
        ``evidence``).

    Raises
    ------
    FileExistsError
        If the log already exists in ``out``.
    ValueError
        If task, method, phase or participant would not make a casa-trial/1 log.
    """
    phase = default_phase(task) if phase is None else phase
    stem = Path(out) / TrialSpec(task, method, phase, repeat).stem
    source_kind = "human" if key_source is None else "simulated"
    # Refuse before the person starts, not after: the log must be writable.
    planned = {"schema": SCHEMA, "participant": participant, "task": task, "method": method}
    problems = check_meta({**planned, "phase": phase, "source": source_kind}, f"{stem}.json")
    if problems:
        raise ValueError("cannot run this trial: " + "; ".join(str(x) for x in problems))
    for suffix in (".json", ".csv"):
        if stem.with_suffix(suffix).exists():
            raise FileExistsError(
                f"{stem.with_suffix(suffix)} exists; logs are never overwritten: "
                "choose another --out or move the old log"
            )
    with ArmSimulation(layout, gui=gui) as sim:
        window = Window(sim, realtime)
        source = KeyboardKeys(sim.client) if key_source is None else key_source
        window.intro(title or f"{task}  ({method})", countdown)
        started = datetime.now(UTC).isoformat(timespec="seconds")
        result = run_trial(
            layout,
            task,
            method,
            source,
            participant=participant,
            intents=intents,
            phase=phase,
            source_kind=source_kind,
            max_duration=max_duration,
            sim=sim,
            assistant_options=assistant_options,
            on_tick=window.on_tick,
        )
        result.meta["started_at"] = started
        result.write(stem)
        window.finish(f"saved {stem.name}")
    return stem


def teleop_session(
    layout: dict,
    task: str,
    method: str,
    participant: str,
    out: Path | str,
    *,
    n_demonstrations: int = 5,
    epsilon: float = 1.0,
    make_key_source: Callable[[], KeySource] | None = None,
    **options,
) -> tuple[list[Path], bool]:
    """A teleoperated trial and, if CASA finds its intents misspecified, the demonstrations.

    After a CASA trial of the ``before_learning`` phase in which every known
    intent's beta_hat stayed below ``epsilon`` at the end
    (:func:`casa_core.study.protocol.misspecification_detected`), the robot asks the
    person, in the window, for ``n_demonstrations`` demonstrations of the task
    without assistance, and records each (phase ``demonstration``, method NA),
    as the protocol does for simulated participants.

    Parameters
    ----------
    make_key_source : callable, optional
        Makes the key source of each trial; default the window's keyboard.
    **options
        Passed to :func:`run_teleop` for every trial (``phase``, ``gui``,
        ``countdown``, ``realtime``, ``max_duration``, ``intents``,
        ``assistant_options``).

    Returns
    -------
    stems : list of Path
        The logs written, the trial's first.
    detected : bool
        Whether misspecification was detected (and demonstrations recorded).
    """

    def source():
        return None if make_key_source is None else make_key_source()

    stem = run_teleop(layout, task, method, participant, out, key_source=source(), **options)
    stems = [stem]
    _, frame = read_trial(stem)
    phase = options.get("phase") or default_phase(task)
    detected = (
        method == "CASA"
        and phase == "before_learning"
        and n_demonstrations > 0
        and misspecification_detected(frame, epsilon)
    )
    if detected:
        demo_options = {**options, "phase": "demonstration", "intents": None}
        for spec in demonstrations(task, n_demonstrations):
            title = (
                "The robot could not tell what you wanted. Please show it: "
                f"demonstration {spec.repeat + 1} of {n_demonstrations}, no assistance"
            )
            stems.append(
                run_teleop(
                    layout,
                    task,
                    "NA",
                    participant,
                    out,
                    key_source=source(),
                    repeat=spec.repeat,
                    title=title,
                    **demo_options,
                )
            )
    return stems, detected


class _ExpertThenRest(WaypointKeys):
    """:class:`WaypointKeys` that rests at the last waypoint instead of finishing."""

    def keys(self, t: float, state) -> frozenset[str]:
        held = super().keys(t, state)
        self.done = False
        return held


def trial_realtime_factor(
    layout: dict, duration: float = 15.0, repeats: int = 3, reuse_simulation: bool = False
) -> tuple[float, float]:
    """Simulated seconds per second of a whole CASA trial, pybullet included.

    The Unknown Goal task driven by :class:`WaypointKeys` for ``duration`` seconds
    (the expert rests at the goal once there). By default each trial creates and
    tears down its own simulation inside the timing (about 30 ms, mostly
    ``pybullet.connect``); with ``reuse_simulation`` one simulation, created before
    the timing, runs every trial, as a study runner that keeps it open would.

    Returns
    -------
    (float, float)
        Medians over ``repeats`` trials of simulated seconds per CPU second of this
        process (what one core achieves, whatever else runs on the machine) and per
        wall-clock second.
    """
    from casa_core.tasks import task_waypoints

    shared = ArmSimulation(layout) if reuse_simulation else None
    per_cpu, per_wall = [], []
    try:
        for _ in range(repeats):
            source = _ExpertThenRest(task_waypoints("unknown_goal", layout)[1:])
            cpu, wall = time.process_time(), time.perf_counter()
            run_trial(
                layout,
                "unknown_goal",
                "CASA",
                source,
                participant="bench",
                max_duration=duration,
                sim=shared,
            )
            per_cpu.append(duration / (time.process_time() - cpu))
            per_wall.append(duration / (time.perf_counter() - wall))
    finally:
        if shared is not None:
            shared.close()
    return float(np.median(per_cpu)), float(np.median(per_wall))
