"""One session of the original implementation as a casa-trial/1 trial.

:func:`convert_session` gives the time series, :func:`inference_steps` the metadata of the
logged inference steps (``inference_steps``: when each started, the waypoints it ran over,
the step after the trial). The rules are ``docs/data-contracts.md`` ("Importing the
original implementation's sessions"); in short:

* **Ticks.** The original logged its control loop at about 18 Hz, irregularly
  (``cmdpos_time``); casa-trial/1 has one row per 0.05 s tick. Rows are written at
  ``t = 0, 0.05, ...`` up to the last sample. Joint angles (``curr_pos``, unwrapped over
  the trial: a jump of more than pi between two samples is a wrap, not motion) are
  interpolated linearly; keys hold the value of the last sample at or before the tick.
* **Positions.** ``q1..q7`` are the joint angles; ``x, y, z`` the scene's point (its
  ``point``: link 7's origin on the authors' layout, the original's end effector; the
  tool point by default) and ``rot`` the turn of the tool about its axis
  (:func:`~casa_core.robot.kinematics.rot_of`, unwrapped), both through our kinematics of
  the same JACO (joint angles mean the same).
* **Keys.** The user's command ``joy_cmd`` is a joint velocity. Its velocity at the same
  point, ``J(q)[:3] @ joy_cmd``, gives ``x+``/``x-`` (and ``y``, ``z``) on each axis where it
  exceeds :data:`KEY_FRACTION` of the key speed 0.05 m/s; a joint-7 velocity beyond the
  same fraction of 0.5 rad/s gives ``rot-`` (positive) or ``rot+`` (negative: our rotate
  key turns joint 7 backwards, see :mod:`casa_core.robot.sim`). Joint 7 moves neither the
  tool point nor link 7, so the two parts do not mix. An all-zero command is no key.
* **Inference.** Timed step ``k``'s betas and beliefs hold from the first tick at or after
  its start ``inf_start_time[k]``, the moment of the evidence it saw, to the next step's
  start; before the first, beta is 0, the belief uniform and alpha 1. The step after the
  trial is on no tick (:func:`inference_steps` keeps it). A negative beta (the original
  did not clamp) is written as 0; a belief row that is not a distribution (the original's
  0/0) carries the last good row, as does a beta row that is not finite. A session that
  logged no inference (no betas) has no belief or beta columns. alpha: CASA
  ``clip(1 / beta of the most likely goal, 0, 1)`` (a negative beta gives 0, as the
  original applied it); PBA ``clip(d / 0.55, 0, 1)``, ``d`` the distance of link 7 at the
  step's last waypoint to the most likely goal's link-7 position (the scene's goals at
  link 7, else the link 7 of the original's goal angles), the most likely goal being the
  logged belief's or, when none was logged, the one the original's beta = 1 posterior
  gives over the same waypoints (:func:`~casa_core.io.original.numerics.original_step`);
  NA 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from casa_core.defaults import DT, PBA_DISTANCE, ROT_SPEED, SPEED
from casa_core.fixed_order import matmul
from casa_core.io import JOINTS, Problem
from casa_core.io.contract import TICK
from casa_core.io.original._checker import SessionError
from casa_core.io.original.numerics import original_step
from casa_core.io.original.sessions import Session, reference_q
from casa_core.robot import kinematics as kin
from casa_core.scene import KNOWN_GOALS
from casa_core.vocabulary import KEYS

#: A command faster than this fraction of a key's speed counts as the key held.
KEY_FRACTION = 0.5


def command_keys(q: np.ndarray, command: np.ndarray, point: str = "tool") -> str:
    """The keys (space-separated, in :data:`~casa_core.vocabulary.KEYS` order) of one
    command, read from its velocity at ``point``.

    Examples
    --------
    >>> q = reference_q("start")
    >>> up = np.linalg.pinv(kin.jacobian(q)[:3]) @ np.array([0.0, 0.0, SPEED])
    >>> command_keys(q, up), command_keys(q, -up + [0, 0, 0, 0, 0, 0, 0.5])
    ('z+', 'z- rot-')
    """
    if not np.any(command):
        return ""
    velocity = matmul(kin.jacobian(q, point)[:3], command)
    held = set()
    for axis, v in zip("xyz", velocity, strict=True):
        if abs(v) > KEY_FRACTION * SPEED:
            held.add(f"{axis}{'+' if v > 0 else '-'}")
    if abs(command[6]) > KEY_FRACTION * ROT_SPEED:
        held.add("rot-" if command[6] > 0 else "rot+")
    return " ".join(key for key in KEYS if key in held)


@dataclass(frozen=True)
class Converted:
    """One converted trial: its ``frame`` (casa-trial/1 columns) and what was changed
    (counts of negative betas, belief rows and non-finite beta rows carried forward, over
    the timed steps)."""

    frame: pd.DataFrame
    negative_betas: int
    bad_beliefs: int
    bad_betas: int
    samples: int


def _carry(rows: np.ndarray, good: np.ndarray, initial: np.ndarray) -> np.ndarray:
    """Each bad row replaced by the last good row before it (``initial`` before any)."""
    out = rows.copy()
    last = initial
    for i in range(len(rows)):
        if good[i]:
            last = rows[i]
        else:
            out[i] = last
    return out


def _held(times: np.ndarray, ticks: np.ndarray) -> np.ndarray:
    """Index of the last of ``times`` at or before each tick; -1 before the first."""
    return np.searchsorted(times, ticks + 1e-9, side="right") - 1


def _resampled(session: Session, times) -> np.ndarray:
    """The joint angles at ``times``, interpolated over the unwrapped samples."""
    unwrapped = np.unwrap(session.q, axis=0)
    columns = [np.interp(times, session.time, unwrapped[:, j]) for j in range(kin.N_JOINTS)]
    return np.column_stack(columns)


def _evidence_waypoints(session: Session) -> np.ndarray:
    """The link-7 positions (w, 3) the steps ran over: the recorded waypoints, else the
    joint angles resampled every 0.5 s up to the last timed step's waypoint."""
    if session.waypoints is not None:
        q = session.waypoints
    else:
        last = int(session.step_waypoints[-1]) if len(session.step_waypoints) else 0
        q = _resampled(session, np.arange(last + 1) * DT)
    return np.array([kin.link7_position(row) for row in q])


def convert_session(
    session: Session, method: str, goal_names, link7_goals=None, *, point: str = "tool"
) -> Converted:
    """The casa-trial/1 time series of a session (module docs give the rules).

    Parameters
    ----------
    session : Session
    method : {"NA", "PBA", "CASA"}
        How alpha is recomputed from the logged inference.
    goal_names : sequence of str
        Our names of the session's goals, in its order (``belief_hist``'s columns).
    link7_goals : mapping of str to 3 floats, optional
        The link-7 positions of the known goals, from which PBA's distance is measured
        (the scene's goals at link 7); default the link 7 of the original's goal angles
        (:data:`~casa_core.io.original.sessions.REFERENCE_ANGLES`).
    point : {"tool", "link7"}
        The point whose position ``x, y, z`` is, and whose velocity gives the keys (the
        scene's ``point``).

    Raises
    ------
    SessionError
        A CASA session without betas, or a PBA session with a goal without a known
        position.

    Examples
    --------
    >>> n = 13
    >>> session = Session("task1c_data.npz", np.round(np.arange(n) * 0.05, 6),
    ...                   np.tile(reference_q("start"), (n, 1)), np.zeros((n, 7)),
    ...                   steps=np.array([0.52]), step_waypoints=np.array([1]),
    ...                   belief=np.array([[0.25, 0.75]]), beta=np.array([[0.5, 2.0]]),
    ...                   final_belief=np.array([0.1, 0.9]), final_beta=np.array([-1.0, 3.0]),
    ...                   waypoints=None, started=None)
    >>> frame = convert_session(session, "CASA", ["green", "purple"]).frame
    >>> frame[["t", "alpha", "beta:purple", "belief:purple"]].iloc[[0, 10, 11]].values.tolist()
    [[0.0, 1.0, 0.0, 0.5], [0.5, 1.0, 0.0, 0.5], [0.55, 0.5, 2.0, 0.75]]
    """
    goals = len(goal_names)
    if goals != session.goals:
        raise ValueError(f"{goals} goal names for {session.goals} goals")
    last = session.time[-1]
    ticks = np.round(np.arange(int(np.floor(last / TICK + 1e-9)) + 1) * TICK, 6)
    q = _resampled(session, ticks)
    frames = [kin.link_frames(row) for row in q]
    position = np.array([frame[kin.POINT_FRAMES[point]][:3, 3] for frame in frames])
    rot = np.unwrap([kin.rot_of(frame[-1][:3, :3]) for frame in frames])
    sample_keys = [
        command_keys(qi, ci, point) for qi, ci in zip(session.q, session.command, strict=True)
    ]
    at_sample = _held(session.time, ticks)
    keys = ["" if i < 0 else sample_keys[i] for i in at_sample]
    table: dict[str, Any] = {"t": ticks, "x": position[:, 0], "y": position[:, 1]}
    table["z"] = position[:, 2]
    table |= {"rot": rot, "keys": keys}
    table |= {name: q[:, j] for j, name in enumerate(JOINTS)}

    uniform = np.full(goals, 1.0 / goals)
    belief, bad = None, 0
    if session.logged_inference:
        total = session.belief.sum(axis=1)
        good = np.isfinite(session.belief).all(axis=1) & (session.belief >= 0).all(axis=1)
        good &= total > 0
        belief = _carry(session.belief / np.where(good, total, 1.0)[:, None], good, uniform)
        bad = int(np.sum(~good))
    beta, bad_betas = session.beta, 0
    if beta is not None:
        finite = np.isfinite(beta).all(axis=1)
        beta, bad_betas = _carry(beta, finite, np.zeros(goals)), int(np.sum(~finite))
    negative = 0 if beta is None else int(np.sum(beta < 0))
    alphas = _step_alphas(session, method, belief, beta, goal_names, link7_goals)
    at_step = _held(session.steps, ticks)
    before = at_step < 0
    index = np.maximum(at_step, 0)
    table["alpha"] = np.where(before, 1.0, alphas[index]) if len(alphas) else np.ones(len(ticks))
    for g, name in enumerate(goal_names):
        if beta is not None:
            table[f"beta:{name}"] = np.where(before, 0.0, np.maximum(beta[index, g], 0.0))
        if belief is not None:
            table[f"belief:{name}"] = np.where(before, uniform[g], belief[index, g])
    return Converted(pd.DataFrame(table), negative, bad, bad_betas, len(session.time))


def _step_alphas(session: Session, method: str, belief, beta, goal_names, link7_goals):
    """alpha after each timed step, as the original arbitrated it."""
    steps = len(session.steps)
    if method == "NA" or not steps:
        return np.ones(steps)
    if method == "CASA":
        if beta is None or belief is None:
            message = "is empty, but a CASA trial's alpha needs the confidence of every step"
            raise SessionError([Problem(session.file, "key 'beta_hist'", "shape", message)])
        likely = np.argmax(belief, axis=1)
        with np.errstate(divide="ignore"):
            inverse = 1.0 / beta[np.arange(steps), likely]
        return np.clip(inverse, 0.0, 1.0)
    goals = _pba_goals(session, goal_names, link7_goals)
    points = _evidence_waypoints(session)
    alphas = np.empty(steps)
    for k, w in enumerate(session.step_waypoints):
        if belief is not None:
            likely = int(np.argmax(belief[k]))
        else:  # the prediction of the original's posterior at beta = 1, never saved
            likely = original_step(points[: w + 1], goals, "distance").star
        distance = float(np.linalg.norm(points[w] - goals[likely]))
        alphas[k] = min(max(distance / PBA_DISTANCE, 0.0), 1.0)
    return alphas


def _pba_goals(session: Session, goal_names, link7_goals) -> np.ndarray:
    """The link-7 positions of a PBA session's goals, in its order."""
    if link7_goals is None:
        link7_goals = {
            name: kin.link7_position(reference_q(f"goal {g}")) for g, name in enumerate(KNOWN_GOALS)
        }
    missing = [name for name in goal_names if name not in link7_goals]
    if missing:
        message = (
            f"PBA's distance needs the link-7 position of every goal; {missing[0]!r} has none "
            f"(known: {', '.join(link7_goals)})"
        )
        raise SessionError([Problem(session.file, "key 'belief_hist'", "goal", message)])
    return np.array([link7_goals[name] for name in goal_names], dtype=float)


def _number(value) -> float | None:
    """A float for JSON: None where it is not finite (the original's 0/0)."""
    value = float(value)
    return value if math.isfinite(value) else None


def inference_steps(session: Session, goal_names) -> dict:
    """The metadata key ``inference_steps`` of a session (docs/data-contracts.md).

    ``started`` and ``waypoint``: each timed step's start and the last waypoint it ran
    over; ``waypoints``: the recorded waypoints' joint angles (when the file has them);
    ``after_trial``: the step run after the trial, with its logged ``beta`` and ``belief``
    per goal as the original computed them (a negative beta kept), when the session
    logged inference.

    Examples
    --------
    >>> session = Session("task1c_data.npz", np.zeros(1), np.zeros((1, 7)), np.zeros((1, 7)),
    ...                   steps=np.array([0.52]), step_waypoints=np.array([1]),
    ...                   belief=np.array([[0.25, 0.75]]), beta=np.array([[0.5, 2.0]]),
    ...                   final_belief=np.array([0.1, 0.9]), final_beta=np.array([-1.0, 3.0]),
    ...                   waypoints=None, started=None)
    >>> inference_steps(session, ["green", "purple"])  # doctest: +NORMALIZE_WHITESPACE
    {'started': [0.52], 'waypoint': [1], 'after_trial': {'beta': {'green': -1.0,
    'purple': 3.0}, 'belief': {'green': 0.1, 'purple': 0.9}}}
    """
    steps: dict[str, Any] = {
        "started": [float(t) for t in session.steps],
        "waypoint": [int(w) for w in session.step_waypoints],
    }
    if session.waypoints is not None:
        steps["waypoints"] = [[float(angle) for angle in row] for row in session.waypoints]
    if session.logged_inference:
        after: dict[str, Any] = {}
        if session.waypoints is not None:
            after["waypoint"] = len(session.waypoints) - 1
        assert session.final_beta is not None
        after["beta"] = {n: _number(v) for n, v in zip(goal_names, session.final_beta, strict=True)}
        after["belief"] = {
            n: _number(v) for n, v in zip(goal_names, session.final_belief, strict=True)
        }
        steps["after_trial"] = after
    return steps
