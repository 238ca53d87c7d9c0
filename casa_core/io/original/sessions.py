"""The original implementation's session files, read and converted to casa-trial/1 trials.

The authors' original implementation (Python 2, on the real JACO) wrote one NumPy
``.npz`` per trial. :func:`read_session` loads one and checks every array it uses;
:func:`convert_session` turns it into a casa-trial/1 metadata dict and time series.
:mod:`casa_core.io.original.importer` does this for a folder of them (``casa import
original``). The format and the rules are ``docs/data-contracts.md`` ("Importing the
original implementation's sessions"); in short:

* **Ticks.** The original logged its control loop at about 18 Hz, irregularly
  (``cmdpos_time``); casa-trial/1 has one row per 0.05 s tick. Rows are written at
  ``t = 0, 0.05, ...`` up to the last sample. Joint angles (``curr_pos``, unwrapped over
  the trial: a jump of more than pi between two samples is a wrap, not motion) are
  interpolated linearly; keys, ``alpha``, betas and beliefs hold the value of the last
  sample (or inference step) at or before the tick.
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
* **Inference.** Each step (``inf_start_time``) gives the betas (``beta_hist``) and
  beliefs (``belief_hist``) of the goals, held until the next step; before the first
  step beta is 0, the belief uniform and alpha 1. A negative beta (the original did not
  clamp) is written as 0; a belief row that is not a distribution (the original's 0/0)
  carries the last good row, as does a beta row that is not finite; all are counted in
  the trial's ``notes``. alpha: CASA
  ``clip(1 / beta of the most likely goal, 0, 1)`` (a negative beta gives 0, as the
  original applied it); PBA ``clip(d / 0.55, 0, 1)`` with ``d`` the distance of link 7
  (the original's end effector) at the step to the most likely goal's link-7 position (the
  scene's goals at link 7, else the link 7 of the original's goal angles);
  NA 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from casa_core.defaults import PBA_DISTANCE, ROT_SPEED, SPEED
from casa_core.fixed_order import matmul
from casa_core.io import JOINTS, Problem
from casa_core.io.contract import TICK
from casa_core.io.original._checker import Checker, SessionError, load_arrays
from casa_core.robot import kinematics as kin
from casa_core.scene import KNOWN_GOALS
from casa_core.vocabulary import KEYS

#: The original's reference joint angles (degrees): start, its goals 0 and 1, the unknown goal.
REFERENCE_ANGLES = {
    "start": (180, 175, 180, 300, 180, 180, 190),
    "goal 0": (150, 130, 160, 240, 180, 172, 280),
    "goal 1": (210, 130, 200, 240, 180, 172, 280),
    "unknown goal": (123, 155, 131, 284, 180, 176, 189),
}
#: A command faster than this fraction of a key's speed counts as the key held.
KEY_FRACTION = 0.5
#: The arrays a session must have (the others are not read).
REQUIRED_KEYS = ("cmdpos_time", "curr_pos", "joy_cmd", "inf_start_time", "belief_hist")


@dataclass(frozen=True)
class Session:
    """The arrays of one session file that the conversion reads, checked.

    ``time`` (n,), ``q`` and ``command`` (n, 7); ``steps`` (m + 1,) the time of each
    inference row: 0 (the step at the start, not timed in the file), then
    ``inf_start_time``; ``belief`` (m + 1, g); ``beta`` (m + 1, g) or None when the
    method logged none; ``started`` the wall clock or None.
    """

    file: str
    time: np.ndarray
    q: np.ndarray
    command: np.ndarray
    steps: np.ndarray
    belief: np.ndarray
    beta: np.ndarray | None
    started: float | None


def reference_q(name: str) -> np.ndarray:
    """The original's reference joint angles ``name`` (:data:`REFERENCE_ANGLES`), radians.

    Examples
    --------
    >>> kin.link7_position(reference_q("goal 0")).round(3)
    array([-0.548, -0.444,  0.424])
    """
    return np.radians(np.asarray(REFERENCE_ANGLES[name], dtype=float))


def read_session(path: Path | str) -> Session:
    """Load and check one session file of the original implementation.

    Raises
    ------
    SessionError
        Listing every problem, each naming the file, the key and the rule: ``npz`` (not
        a readable archive), ``required-key``, ``pickle`` (an object array, never loaded),
        ``numbers``, ``shape``, ``finite-number``,
        ``rows`` (arrays of one length disagree), ``range``, ``increasing`` (times).

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "task1a_data.npz"
    >>> np.savez(path, cmdpos_time=[0.0, 0.05], curr_pos=np.zeros((2, 7)))
    >>> try:
    ...     read_session(path)
    ... except SessionError as error:
    ...     print([(p.where, p.rule) for p in error.problems])
    [("key 'joy_cmd'", 'required-key'), ("key 'inf_start_time'", 'required-key'), \
("key 'belief_hist'", 'required-key')]
    """
    path = Path(path)
    check = Checker(str(path), load_arrays(path))
    time = check.array("cmdpos_time", None)
    q = check.array("curr_pos", kin.N_JOINTS)
    command = check.array("joy_cmd", kin.N_JOINTS)
    check.increasing("cmdpos_time", time)
    if time is not None:
        if not len(time):
            check.fail("cmdpos_time", "non-empty", "no samples")
        check.rows("curr_pos", q, len(time), "cmdpos_time")
        check.rows("joy_cmd", command, len(time), "cmdpos_time")
    timed = check.array("inf_start_time", None)
    check.increasing("inf_start_time", timed)
    # Row 0 of the histories is the step at t = 0; row k the one started at timed[k - 1].
    steps = None if timed is None else np.r_[0.0, timed]
    belief, beta = _inference_arrays(check, steps)
    raw_start = check.arrays.get("start_T")
    started = None
    if raw_start is not None and np.ndim(raw_start) == 0:
        started = float(raw_start) if np.asarray(raw_start).dtype.kind in "iuf" else None
    if check.problems or steps is None:  # no steps: inf_start_time's problem is listed
        raise SessionError(check.problems)
    return Session(str(path), time, q, command, steps, belief, beta, started)


def _inference_arrays(check: Checker, steps):
    """``belief_hist`` (m + 1, g) and ``beta_hist`` (m + 1, g) or None, ``steps`` the m + 1
    times of their rows."""
    m = None if steps is None else len(steps)
    arrays: dict[str, np.ndarray | None] = {}
    for key in ("belief_hist", "beta_hist"):
        raw = check.arrays.get(key)
        if raw is None and key == "belief_hist":
            check.fail(key, "required-key", "missing")
            continue
        if raw is None or np.shape(raw) == (0,):
            # No betas: the method used none; no beliefs only without inference steps.
            if key == "belief_hist" and m:
                check.fail(key, "shape", f"is empty but the session has {m} inference steps")
            arrays[key] = None
            continue
        value = check.array(key, 0, finite=False)
        if value is not None and m is not None and len(value) != m:
            message = (
                f"has {len(value)} rows, expected {m}: one per entry of inf_start_time "
                f"({m - 1}) and row 0, the step at t = 0"
            )
            check.fail(key, "rows", message)
        arrays[key] = value
    belief, beta = arrays.get("belief_hist"), arrays.get("beta_hist")
    if belief is None:
        belief = np.zeros((0, len(KNOWN_GOALS)))
    if beta is not None and beta.shape[1] != belief.shape[1]:
        check.fail(
            "beta_hist", "shape", f"has {beta.shape[1]} goals, belief_hist {belief.shape[1]}"
        )
    return belief, beta


# --------------------------------------------------------------------------- conversion


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
    (counts of negative betas, belief rows and non-finite beta rows carried forward)."""

    frame: pd.DataFrame
    negative_betas: int
    bad_beliefs: int
    bad_betas: int
    samples: int


def _held(times: np.ndarray, ticks: np.ndarray) -> np.ndarray:
    """Index of the last of ``times`` at or before each tick; -1 before the first."""
    return np.searchsorted(times, ticks + 1e-9, side="right") - 1


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
        (:data:`REFERENCE_ANGLES`).
    point : {"tool", "link7"}
        The point whose position ``x, y, z`` is, and whose velocity gives the keys (the
        scene's ``point``).

    Raises
    ------
    SessionError
        A CASA session without betas, or a PBA session predicting a goal without a
        known position.

    Examples
    --------
    >>> n = 3
    >>> session = Session("task1a_data.npz", np.array([0.0, 0.06, 0.11]),
    ...                   np.tile(reference_q("start"), (n, 1)), np.zeros((n, 7)),
    ...                   np.array([0.05]), np.array([[0.25, 0.75]]), None, None)
    >>> converted = convert_session(session, "NA", ["green", "purple"])
    >>> converted.frame[["t", "keys", "alpha", "belief:purple"]].values.tolist()
    [[0.0, '', 1.0, 0.5], [0.05, '', 1.0, 0.75], [0.1, '', 1.0, 0.75]]
    """
    goals = len(goal_names)
    if goals != session.belief.shape[1]:
        raise ValueError(f"{goals} goal names for {session.belief.shape[1]} goals")
    last = session.time[-1]
    ticks = np.round(np.arange(int(np.floor(last / TICK + 1e-9)) + 1) * TICK, 6)
    unwrapped = np.unwrap(session.q, axis=0)
    q = np.column_stack([np.interp(ticks, session.time, unwrapped[:, j]) for j in range(7)])
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

    uniform = np.full(goals, 1.0 / goals) if goals else np.zeros(0)
    belief = session.belief
    total = belief.sum(axis=1) if len(belief) else np.zeros(0)
    good = np.isfinite(belief).all(axis=1) & (belief >= 0).all(axis=1) & (total > 0)
    belief = _carry(belief / np.where(good, total, 1.0)[:, None], good, uniform)
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
    for g, name in enumerate(goal_names if len(belief) else ()):
        if beta is not None:
            table[f"beta:{name}"] = np.where(before, 0.0, np.maximum(beta[index, g], 0.0))
        table[f"belief:{name}"] = np.where(before, uniform[g], belief[index, g])
    bad = int(np.sum(~good))
    return Converted(pd.DataFrame(table), negative, bad, bad_betas, len(session.time))


def _step_alphas(session: Session, method: str, belief, beta, goal_names, link7_goals):
    """alpha after each inference step, as the original arbitrated it."""
    steps = len(session.steps)
    if method == "NA" or not steps:
        return np.ones(steps)
    likely = np.argmax(belief, axis=1)
    if method == "CASA":
        if beta is None:
            message = "is empty, but a CASA trial's alpha needs the confidence of every step"
            raise SessionError([Problem(session.file, "key 'beta_hist'", "shape", message)])
        with np.errstate(divide="ignore"):
            inverse = 1.0 / beta[np.arange(steps), likely]
        return np.clip(inverse, 0.0, 1.0)
    known = [name for name in goal_names if name in KNOWN_GOALS]
    if np.any(likely >= len(known)):
        message = f"PBA predicts a goal without a known position; known: {', '.join(known)}"
        raise SessionError([Problem(session.file, "key 'belief_hist'", "goal", message)])
    if link7_goals is None:
        link7_goals = {
            name: kin.link7_position(reference_q(f"goal {g}")) for g, name in enumerate(KNOWN_GOALS)
        }
    missing = [name for name in known if name not in link7_goals]
    if missing:
        message = f"PBA's distance needs the link-7 position of goal {missing[0]!r}"
        raise SessionError([Problem(session.file, "scene: link7", "goal", message)])
    targets = np.array([link7_goals[known[g]] for g in likely], dtype=float)
    unwrapped = np.unwrap(session.q, axis=0)
    q = np.column_stack([np.interp(session.steps, session.time, unwrapped[:, j]) for j in range(7)])
    distance = np.linalg.norm([kin.link7_position(row) for row in q] - targets, axis=1)
    return np.clip(distance / PBA_DISTANCE, 0.0, 1.0)


def started_at(session: Session) -> str | None:
    """The session's wall-clock start (``start_T``) as ISO 8601 UTC, or None.

    Examples
    --------
    >>> session = Session("f", np.zeros(1), np.zeros((1, 7)), np.zeros((1, 7)), np.zeros(0),
    ...                   np.zeros((0, 2)), None, 1.6e9)
    >>> started_at(session)
    '2020-09-13T12:26:40+00:00'
    """
    if session.started is None or not np.isfinite(session.started) or session.started <= 0:
        return None
    return datetime.fromtimestamp(session.started, UTC).isoformat()
