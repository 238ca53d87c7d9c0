"""Replay: offline inference over a recorded casa-trial/1 log.

A replay feeds the logged states and keys to an :class:`~casa_core.assist.assistant.Assistant`
tick by tick, as the closed loop that recorded the trial did: every ``dt`` (0.5 s) the
assistant updates its inference with the logged state, and every control tick it is
told the user's action (from the logged keys, or a device's logged command) and the
authority alpha the arm actually applied (the logged ``alpha``; 1 when the log has none:
the arm was unassisted). So under commanded evidence the robot's share removed from the
evidence is the share the arm really had.

With the trial's own settings (its ``meta["inference"]``, the arbitration of its
method, its intents and scene) a replay of a simulated trial reproduces the logged
beta, belief and alpha exactly. Any setting can be changed: that is a counterfactual.
A trial recorded under NA replayed with arbitration ``"confidence"`` shows what CASA's
confidence and alpha would have been *on that trajectory*; under CASA the robot would
have moved too, so the trajectory itself, and with it everything after the first
assisted step, would have differed. ``docs/replay.md`` describes the outputs.

Examples
--------
>>> import pandas as pd
>>> from casa_core.scene import load_scene
>>> meta = {"participant": "p01", "task": "known_goal", "method": "NA",
...         "phase": "no_misspecification", "source": "human"}
>>> t = [round(0.05 * k, 6) for k in range(21)]
>>> frame = pd.DataFrame({"t": t, "x": [0.45 + 0.0025 * k for k in range(21)],
...                       "y": -0.22, "z": 0.38, "rot": 0.0, "keys": "x+"})
>>> replayed = replay_trial(meta, frame, load_scene())
>>> replayed[["t", "intent", "theta_star", "alpha"]]
     t  intent theta_star  alpha
0  0.5   green      green    1.0
1  0.5  purple      green    1.0
2  1.0   green      green    1.0
3  1.0  purple      green    1.0
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from casa_core.analysis.effort import commanded, held_directions
from casa_core.analysis.replay_intents import (
    goal_position,
    resolve_intents,
)
from casa_core.analysis.replay_settings import (
    ReplayError,
    replay_path,
    trial_point,
    trial_settings,
)
from casa_core.assist.assistant import Assistant
from casa_core.assist.presets import DEFECTS
from casa_core.assist.trial import inference_ticks, scene_assistant
from casa_core.defaults import DT, EPSILON, HORIZON
from casa_core.io.contract import INTENT_PREFIXES, JOINTS
from casa_core.io.original.numerics import original_rows
from casa_core.robot.kinematics import POINT_FRAMES, link_frames, point_position, rot_of
from casa_core.scene import KNOWN_GOALS, Scene
from casa_core.vocabulary import DEFECTS_PRESET

#: The columns of a replay table, in order.
COLUMNS = ("t", "intent", "suboptimality", "beta", "belief", "theta_star", "alpha", "misspecified")


def replay_trial(
    meta: dict,
    frame: pd.DataFrame,
    scene: Scene,
    *,
    preset: str | None = None,
    evidence: str | None = None,
    arbitration: str | None = None,
    point: str | None = None,
    path: str | None = None,
    lam: float | None = None,
    epsilon: float = EPSILON,
    intents: Sequence[str] | None = None,
    learned: Sequence = (),
) -> pd.DataFrame:
    """Redo the inference of one trial over its logged states and keys.

    Parameters
    ----------
    meta, frame : dict, pandas.DataFrame
        The trial as :func:`casa_core.io.read_trial` returns it.
    scene : Scene
        Its goals and keyboard (speeds, control tick).
    preset, evidence, arbitration : str, optional
        Default: the trial's own (:func:`trial_settings`). The preset
        :data:`~casa_core.vocabulary.DEFECTS_PRESET` redoes the original's numerics with
        their defects (:mod:`casa_core.io.original.numerics`) over the scene's goals.
    point : {"tool", "link7"}, optional
        Where the arm is measured (:func:`trial_point`), with the scene's goals at that
        point: the log's positions where they were measured there (the scene's
        ``point``), else that point of the logged joint angles.
    path : {"waypoints", "ticks"}, optional
        What the steps' evidence is read from (:func:`replay_path`): the trial's recorded
        waypoints, each step at its logged start over the waypoints it ran over, or the
        log's state every ``dt``. Default: the waypoints where the trial has them and the
        evidence is the executed path.
    lam : float, optional
        Rate of the prior on beta; default the preset's.
    epsilon : float, default EPSILON
        Misspecification threshold.
    intents : sequence of str, optional
        The intents' names; default ``meta["intents"]``, else the known goals green and
        purple. Resolved by :func:`resolve_intents`.
    learned : sequence of path or Intent
        Learned intents available by name (casa-intent files).

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS`: one row per inference step and intent, in step order, then the
        intents' order; ``t`` is the log's time of the step (its start, on the
        waypoints); ``alpha``, ``theta_star``
        and ``misspecified`` repeat over a step's rows.

    Raises
    ------
    ReplayError
        On settings that do not fit (an unknown intent, a tick that does not divide
        ``dt``); :class:`ValueError` from the assistant on a bad ``lam`` or ``epsilon``.
    """
    chosen, arbitration = trial_settings(
        meta, preset=preset, evidence=evidence, arbitration=arbitration
    )
    point = trial_point(meta, point)
    on_waypoints = replay_path(meta, chosen, path) == "waypoints"
    names = intents if intents is not None else meta.get("intents") or list(KNOWN_GOALS)
    teleop = scene.teleop
    try:
        per_step = inference_ticks(scene)
    except ValueError as error:
        raise ReplayError(str(error)) from None
    t = frame["t"].to_numpy(dtype=float)
    states = _measured_states(frame, point, scene.point)
    # The tick of each row (t = tick * dt); inference runs at each multiple of per_step.
    ticks = np.rint(t / teleop.dt).astype(int)
    recorded: Any = meta.get("inference_steps")
    if on_waypoints:
        logged = list(zip(recorded["started"], recorded["waypoint"], strict=True))
        path_states = _waypoint_states(recorded["waypoints"], point)
    elif chosen is DEFECTS:
        logged, path_states = _tick_steps(t, ticks, per_step, states, recorded)
    if chosen is DEFECTS:
        if lam is not None:
            raise ReplayError(f"preset {DEFECTS_PRESET} has the original's lambda; give no lam")
        chosen_goals = _defect_goals(scene, list(names), point)
        steps = original_rows(
            logged, path_states[:, :3], chosen_goals, list(names), arbitration, epsilon
        )
        return pd.DataFrame(steps, columns=list(COLUMNS))
    built = resolve_intents(list(names), scene, chosen, learned, point=point)
    options = chosen.assistant_options()
    if lam is not None:
        options["lam"] = lam
    assistant = scene_assistant(scene, built, arbitration=arbitration, epsilon=epsilon, **options)
    actions = commanded(frame, speed=teleop.speed, rot_speed=teleop.rot_speed)
    if on_waypoints:
        held = np.array([bool(held) for held in held_directions(frame)])
        return pd.DataFrame(
            _replay_waypoints(assistant, path_states, logged, t, held), columns=list(COLUMNS)
        )
    applied = frame["alpha"].to_numpy(dtype=float) if "alpha" in frame else np.ones(len(t))
    rows = _replay_ticks(assistant, states, t, ticks, actions, applied, scene)
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _replay_ticks(assistant: Assistant, states, t, ticks, actions, applied, scene) -> list[dict]:
    """The assistant fed the log tick by tick, as the closed loop was: an inference step at
    each multiple of the ticks per step, and after every row but the last the user's action
    (the keys' velocity or the device's command) with the authority ``applied`` (the logged
    alpha)."""
    teleop = scene.teleop
    per_step = inference_ticks(scene)
    rows: list[dict] = []
    assistant.reset(states[0])
    done: set[int] = set()
    for i in range(len(t)):
        tick = int(ticks[i])
        if i > 0 and tick > 0 and tick % per_step == 0 and tick not in done:
            done.add(tick)
            rows += _step_rows(float(t[i]), assistant.update(states[i]), assistant.names)
        if i + 1 < len(t):  # the closed loop acts after every row but the last
            elapsed = (tick % per_step) * teleop.dt
            assistant.act(states[i], actions[i], elapsed_in_step=elapsed, alpha=applied[i])
    return rows


def _step_rows(t: float, step, names) -> list[dict]:
    """The replay rows of one inference step, one per intent."""
    return [
        {
            "t": t,
            "intent": name,
            "suboptimality": step.suboptimality[name],
            "beta": step.beta[name],
            "belief": step.belief[name],
            "theta_star": step.intent,
            "alpha": step.alpha,
            "misspecified": step.misspecified,
        }
        for name in names
    ]


def _tick_steps(t, ticks, per_step, states, recorded) -> tuple[list, np.ndarray]:
    """The steps ``(t, w)`` and the path of the log's state every ``dt``: waypoint w at the
    first row of tick ``w * per_step``. The trial's logged steps where it has them
    (``inference_steps``), else one at every ``dt``, at most the horizon's worth."""
    first = {int(tick): i for i, tick in reversed(list(enumerate(ticks)))}
    if isinstance(recorded, dict):
        logged = list(zip(recorded["started"], recorded["waypoint"], strict=True))
        last = max((w for _, w in logged), default=0)
        missing = [w for w in range(last + 1) if w * per_step not in first]
        if missing:
            raise ReplayError(
                f"the log has no tick at t = {missing[0] * DT:g} s (waypoint "
                f"{missing[0]} of its inference steps)"
            )
        index = [first[w * per_step] for w in range(last + 1)]
        return logged, states[index]
    index = [i for tick, i in sorted(first.items()) if tick > 0 and tick % per_step == 0]
    index = index[: int(round(HORIZON / DT))]
    logged = [(float(t[i]), k) for k, i in enumerate(index, start=1)]
    return logged, states[[0, *index]]


def _replay_waypoints(assistant: Assistant, states, logged, t, held) -> list[dict]:
    """The assistant fed the recorded waypoints, one inference step each; a row for each
    logged step, at its start. Waypoint j's step has user input when a key was held (or a
    command given) on a tick in ((j - 1) dt, j dt]."""
    at = {w: start for start, w in logged}
    rows: list[dict] = []
    assistant.reset(states[0])
    for j in range(1, max(at, default=0) + 1):
        interval = (t > (j - 1) * DT + 1e-9) & (t <= j * DT + 1e-9)
        step = assistant.update(states[j], user_input=bool(held[interval].any()))
        if j in at:
            rows += _step_rows(float(at[j]), step, assistant.names)
    return rows


def _waypoint_states(waypoints, point: str) -> np.ndarray:
    """The states ``[x, y, z, rot]`` at ``point`` of recorded waypoints (joint angles)."""
    q = np.asarray(waypoints, dtype=float)
    frames = [link_frames(row) for row in q]
    position = np.array([frame[POINT_FRAMES[point]][:3, 3] for frame in frames])
    rot = np.unwrap([rot_of(frame[-1][:3, :3]) for frame in frames])
    return np.column_stack([position, rot])


def _measured_states(frame: pd.DataFrame, point: str, logged: str) -> np.ndarray:
    """The states ``[x, y, z, rot]`` at ``point``: the log's where it was ``logged`` there
    (the scene's point), else ``point`` of its joint angles."""
    states = frame[["x", "y", "z", "rot"]].to_numpy(dtype=float, copy=True)
    if point != logged:
        missing = [name for name in JOINTS if name not in frame.columns]
        if missing:
            raise ReplayError(f"measured at {point}: the log has no joint angles ({missing[0]})")
        q = frame[list(JOINTS)].to_numpy(dtype=float)
        states[:, :3] = [point_position(row, point) for row in q]
    return states


def _defect_goals(scene: Scene, names: list[str], point: str) -> np.ndarray:
    """The positions of the goals ``names`` at ``point``, for :data:`DEFECTS_PRESET`."""
    unknown = [name for name in names if name not in scene.goals]
    if unknown:
        raise ReplayError(
            f"preset {DEFECTS_PRESET} redoes goals only: {unknown[0]!r} is not a goal of the "
            "scene (the original's learned costs are not in its sessions)"
        )
    return np.array([goal_position(scene, name, point) for name in names])


def replay_differences(frame: pd.DataFrame, replayed: pd.DataFrame) -> dict:
    """The largest absolute difference between a log's inference and its replay.

    Compares the log's ``beta:NAME``, ``belief:NAME`` and ``alpha`` at the replay's
    steps (each at the first tick at or after the step's ``t``, where the log holds its
    result) with the replay, over the intents both have.

    Returns
    -------
    dict
        ``{"beta": float, "belief": float, "alpha": float}``; NaN where the log has no
        such column (or no intent in common) or the replay has no step.

    Examples
    --------
    >>> log = pd.DataFrame({"t": [0.0, 0.5], "alpha": [1.0, 0.75], "beta:green": [0.0, 2.0]})
    >>> replayed = pd.DataFrame({"t": [0.5], "intent": ["green"], "beta": [2.5],
    ...                          "belief": [1.0], "alpha": [0.5]})
    >>> replay_differences(log, replayed)
    {'beta': 0.5, 'belief': nan, 'alpha': 0.25}
    """
    result = dict.fromkeys(("beta", "belief", "alpha"), math.nan)
    if replayed.empty:
        return result
    logged = frame.drop_duplicates("t").reset_index(drop=True)
    times = logged["t"].to_numpy(dtype=float)

    def held(column: str, steps: pd.Series) -> np.ndarray:
        # A step's result is on the log from the first tick at or after its start.
        index = np.searchsorted(times, steps.to_numpy(dtype=float) - 1e-9, side="left")
        values = np.full(len(index), math.nan)
        inside = index < len(times)
        values[inside] = logged[column].to_numpy(dtype=float)[index[inside]]
        return values

    for what in INTENT_PREFIXES:
        gaps = []
        for name, rows in replayed.groupby("intent", sort=False):
            column = f"{what}:{name}"
            if column in logged.columns:
                gaps.append(np.abs(held(column, rows["t"]) - rows[what].to_numpy(dtype=float)))
        if gaps:
            result[what] = float(np.max(np.concatenate(gaps)))
    if "alpha" in logged.columns:
        steps = replayed.drop_duplicates("t")
        gaps = np.abs(held("alpha", steps["t"]) - steps["alpha"].to_numpy(dtype=float))
        result["alpha"] = float(np.max(gaps))
    return result
