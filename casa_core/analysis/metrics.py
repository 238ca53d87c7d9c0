"""The user study's objective metrics (paper, Sec. V-B), per trial.

For a trial logged at ticks ``t_0 < ... < t_{n-1}`` with end-effector positions
``p_i = (x_i, y_i, z_i)``, rotation ``r_i`` and held keys ``K_i``:

- **error** (m^2): the sum of squared differences between the executed and the
  intended trajectory, ``sum_j ||p(s_j) - p*(s_j)||^2``, and beside it
  **error_rot** (rad^2) ``sum_j (r(s_j) - r*(s_j))^2``. *Alignment in time*:
  both are compared at the same seconds since the start,
  ``s_j = j * dt`` for ``j = 0 .. ceil(max(T, T*) / dt)``, with ``dt`` the
  control tick, ``T`` the trial's last tick and ``T*`` the end of the intended
  trajectory (:func:`casa_core.assist.tasks.intended_trajectory`). Each trajectory is
  linearly interpolated between its samples and holds its first / last pose
  outside them: the reference waits at its goal while a slow participant
  finishes, and an executed trajectory that stops early is compared, standing
  still, with the rest of the reference. Lagging behind the reference therefore
  counts as error, as it does for a person told to follow the shown trajectory.
- **efficiency** (m^2/s^2): the efficiency cost, the sum of squared end-effector
  velocities ``sum_{i=1}^{n-1} ||(p_i - p_{i-1}) / (t_i - t_{i-1})||^2``, and
  **efficiency_rot** (rad^2/s^2) the same for ``r``.
- **effort**: the number of key presses, i.e. press events: key ``k`` is pressed
  at tick ``i`` when ``k in K_i`` and ``k not in K_{i-1}`` (every key held at
  the first tick counts once). Holding a key is one press. For a continuous device
  (gamepad, SpaceMouse) ``K_i`` are the directions its command holds
  (:mod:`casa_core.analysis.effort`).
- **effort_ticks**: the original implementation's counter, ``sum_i |K_i|``
  (a held key counts once per tick).
- **command_time** (s) and **command_integral** (full-speed seconds): how long a command
  was given and how large it was, for keys and devices alike
  (:mod:`casa_core.analysis.effort`).
- **input**: the device, the metadata's ``input`` (``keyboard`` when it has none).
- **relative_effort**: ``effort`` divided by the same participant's ``effort`` in
  the NA condition of the same task (:func:`relative_effort`).
- **duration** (s): ``t_{n-1}``, the seconds from the trial's start to its last tick.
- **timed_out**: the trial ran until its time limit ``max_duration`` (the metadata
  key of that name) instead of ending when the operator was done: true when
  ``max_duration - t_{n-1} < dt``, i.e. its last tick is within one control tick of
  the limit (:func:`timed_out`). Unknown (None) when the log does not say its limit.
- **success**: the trial ends where the task intends: the last position ``p_{n-1}``
  is within :data:`SUCCESS_RADIUS` (0.05 m) of the end of the intended trajectory
  and, for a task whose intended trajectory ends with the cup tilted (the pour,
  Unknown Skill), the last rotation ``r_{n-1}`` is within
  :data:`POUR_TILT_TOLERANCE` (0.2 rad) of the intended final tilt
  (:func:`task_success`). Only the end counts, not how or how fast it was
  reached: a trial that ran out of time succeeds when its pose at the limit meets
  these bounds (an operator still fine-tuning the tilt), and fails otherwise (an
  arm held at another goal).
- **arrival** (s): the time of the first tick from which the pose stays within the
  bounds of success to the trial's end (:func:`arrival_time`); None when the trial
  does not succeed.

*Under a fixed trial length* (a scene's ``trial_length``, the original's 15 s protocol)
every trial runs to its limit: ``duration`` is that length and ``timed_out`` is true for
every trial, so neither says how fast the task was done; ``arrival`` does. ``success`` is
the pose at the limit, so an arm that arrived and was then pulled away fails. ``error``
sums over the whole length: waiting at the task's end adds nothing (the reference waits
there too), an arm short of it adds its distance every tick until the end. The
efficiency cost gains nothing from standing still, and ``effort`` counts every press,
those made while waiting included.

Both error sums and the efficiency cost grow with the number of ticks, as the
paper's sums do; compare them only across trials logged at the same tick rate.

Examples
--------
>>> executed = np.array([[0.0, 0, 0, 0, 0], [1.0, 0.1, 0, 0, 0]])
>>> efficiency_cost(executed[:, 0], executed[:, 1:4])
0.010000000000000002
>>> from casa_core.analysis.effort import key_presses, key_ticks
>>> key_presses(["x+", "x+", "", "x+ y+"]), key_ticks(["x+", "x+", "", "x+ y+"])
(3, 4)
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.analysis.effort import (
    command_integral,
    command_time,
    commanded,
    held_directions,
    held_ticks,
    presses,
)
from casa_core.defaults import POUR_TILT_TOLERANCE, ROT_SPEED, SPEED, SUCCESS_RADIUS
from casa_core.fixed_order import length
from casa_core.vocabulary import PHASES, condition_of

#: The condition whose effort is the reference of relative effort, and its method.
REFERENCE_CONDITION = REFERENCE_METHOD = "NA"
#: The phases whose NA trials are the NA *condition* (:func:`casa_core.vocabulary.condition_of`):
#: not the demonstrations (also driven with NA), nor the familiarization, nor after learning.
REFERENCE_PHASES = tuple(
    phase for phase in PHASES if condition_of(REFERENCE_METHOD, phase) == REFERENCE_CONDITION
)


def trajectory_error(
    executed: np.ndarray, intended: np.ndarray, *, dt: float
) -> tuple[float, float]:
    """Position and rotation error between two trajectories aligned in time.

    Parameters
    ----------
    executed, intended : ndarray, shape (n, 5) and (m, 5)
        Rows ``[t, x, y, z, rot]`` with strictly increasing ``t`` (s).
    dt : float
        The comparison step (s), the control tick.

    Returns
    -------
    error : float
        ``sum_j ||p(s_j) - p*(s_j)||^2`` in m^2 over ``s_j = j dt`` (module docstring).
    error_rot : float
        ``sum_j (r(s_j) - r*(s_j))^2`` in rad^2.

    Raises
    ------
    ValueError
        If ``dt`` is not positive.

    Examples
    --------
    Standing still at the start for 1 s while the reference moves 0.05 m along x:

    >>> intended = np.array([[0.0, 0, 0, 0, 0], [1.0, 0.05, 0, 0, 0.1]])
    >>> executed = np.array([[0.0, 0, 0, 0, 0], [1.0, 0, 0, 0, 0]])
    >>> error, error_rot = trajectory_error(executed, intended, dt=0.5)
    >>> round(error, 8), round(error_rot, 8)
    (0.003125, 0.0125)
    """
    executed = np.asarray(executed, dtype=float)
    intended = np.asarray(intended, dtype=float)
    if dt <= 0:
        raise ValueError(f"dt must be > 0, got {dt!r}")
    end = max(executed[-1, 0], intended[-1, 0])
    # The small tolerance keeps an end that is a whole number of ticks from gaining one.
    grid = np.arange(int(np.ceil(end / dt - 1e-9)) + 1) * dt

    def at(trajectory: np.ndarray) -> np.ndarray:
        return np.column_stack(
            [np.interp(grid, trajectory[:, 0], trajectory[:, j]) for j in range(1, 5)]
        )

    difference = at(executed) - at(intended)
    return float(np.sum(difference[:, :3] ** 2)), float(np.sum(difference[:, 3] ** 2))


def efficiency_cost(t: np.ndarray, values: np.ndarray) -> float:
    """Sum of squared finite-difference velocities, ``sum_i ||(v_i - v_{i-1})/(t_i - t_{i-1})||^2``.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Strictly increasing times (s).
    values : ndarray, shape (n,) or (n, d)
        Positions (m) or angles (rad) at those times.

    Returns
    -------
    float
        0 for fewer than two samples.

    Examples
    --------
    0.1 m in 0.5 s (0.2 m/s), then 0.3 m in 1 s (0.3 m/s):

    >>> t = np.array([0.0, 0.5, 1.5])
    >>> round(efficiency_cost(t, [[0, 0, 0], [0.1, 0, 0], [0.1, 0.3, 0]]), 12)
    0.13
    """
    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float).reshape(len(t), -1)
    if len(t) < 2:
        return 0.0
    velocities = np.diff(values, axis=0) / np.diff(t)[:, None]
    return float(np.sum(velocities**2))


def timed_out(duration: float, max_duration: float | None, *, dt: float) -> bool | None:
    """Whether a trial ran to its time limit: its last tick within one tick ``dt`` of it.

    Parameters
    ----------
    duration : float
        The trial's last tick ``t_{n-1}`` (s).
    max_duration : float or None
        The time limit the trial ran under (s), the metadata's ``max_duration``.
    dt : float
        The control tick (s).

    Returns
    -------
    bool or None
        None when ``max_duration`` is None (the log does not say its limit).

    Examples
    --------
    A 40 s limit at 20 Hz: the last tick at 40 s ran out; one tick earlier, the
    operator was done first.

    >>> timed_out(40.0, 40.0, dt=0.05), timed_out(39.95, 40.0, dt=0.05)
    (True, False)
    >>> timed_out(12.0, None, dt=0.05) is None
    True
    """
    if max_duration is None:
        return None
    # The small tolerance keeps a last tick exactly one tick before the limit out.
    return bool(max_duration - duration < dt - 1e-9)


def task_success(executed: np.ndarray, intended: np.ndarray) -> bool:
    """Whether a trial ends where its task intends (module docstring, **success**).

    Parameters
    ----------
    executed, intended : ndarray, shape (n, 5) and (m, 5)
        Rows ``[t, x, y, z, rot]``; only the last row of each counts.

    Returns
    -------
    bool
        The last position within :data:`SUCCESS_RADIUS` of the intended end and, when
        the intended trajectory ends with a rotation other than its first (the pour),
        the last rotation within :data:`POUR_TILT_TOLERANCE` of the intended one.

    Examples
    --------
    A reference that ends at x = 0.3 m with the cup tilted to 1.8 rad:

    >>> intended = np.array([[0.0, 0, 0, 0, 0], [6.0, 0.3, 0, 0, 1.8]])
    >>> task_success(np.array([[9.0, 0.26, 0, 0, 1.65]]), intended)  # 4 cm, 0.15 rad off
    True
    >>> task_success(np.array([[9.0, 0.3, 0, 0, 1.5]]), intended)  # tilt 0.3 rad short
    False
    >>> task_success(np.array([[9.0, 0.24, 0, 0, 1.8]]), intended)  # 6 cm away
    False
    """
    end = np.asarray(executed, dtype=float)[-1, 1:]
    reference = np.asarray(intended, dtype=float)
    target = reference[-1, 1:]
    # Tiny tolerances: a trial ending on the boundary counts, despite rounding.
    close = bool(length(end[:3] - target[:3]) <= SUCCESS_RADIUS + 1e-12)
    if reference[-1, 4] == reference[0, 4]:
        return close
    return close and bool(abs(end[3] - target[3]) <= POUR_TILT_TOLERANCE + 1e-12)


def arrival_time(executed: np.ndarray, intended: np.ndarray) -> float | None:
    """When a trial arrived for good: the first tick from which every pose to the last
    meets the bounds of :func:`task_success`; None when the last one does not.

    Parameters
    ----------
    executed, intended : ndarray, shape (n, 5) and (m, 5)
        Rows ``[t, x, y, z, rot]``.

    Examples
    --------
    In at 2 s, out at 3 s, in again from 4 s:

    >>> intended = np.array([[0.0, 0, 0, 0, 0], [6.0, 0.3, 0, 0, 0]])
    >>> x = [0.0, 0.1, 0.28, 0.2, 0.29, 0.3]
    >>> executed = np.column_stack([np.arange(6.0), x, np.zeros((6, 3))])
    >>> arrival_time(executed, intended)
    4.0
    >>> arrival_time(executed[:4], intended) is None
    True
    """
    executed = np.asarray(executed, dtype=float)
    first = None
    for k in range(len(executed) - 1, -1, -1):
        if not task_success(executed[k : k + 1], intended):
            break
        first = k
    return None if first is None else float(executed[first, 0])


def trial_metrics(
    frame: pd.DataFrame,
    intended: np.ndarray,
    *,
    dt: float,
    max_duration: float | None = None,
    input: str = "keyboard",
    speed: float = SPEED,
    rot_speed: float = ROT_SPEED,
) -> dict[str, float | int | bool | str | None]:
    """Every per-trial metric of one trial log (module docstring for the formulas).

    Parameters
    ----------
    frame : pandas.DataFrame
        A trial as returned by :func:`casa_core.io.read_trial`.
    intended : ndarray, shape (m, 5)
        The task's intended trajectory ``[t, x, y, z, rot]``.
    dt : float
        The control tick (s), the step at which error is summed.
    max_duration : float, optional
        The trial's time limit (s), the metadata's ``max_duration``; without it
        ``timed_out`` is None.
    input : str, default "keyboard"
        The device, the metadata's ``input``.
    speed, rot_speed : float
        The scene's key speeds (m/s, rad/s): the full speed of ``command_integral``.

    Returns
    -------
    dict
        ``error, error_rot, efficiency, efficiency_rot, effort, effort_ticks,
        duration, ticks, timed_out, success, arrival, input, command_time,
        command_integral``.

    Examples
    --------
    >>> frame = pd.DataFrame({"t": [0.0, 0.5, 1.0], "x": [0.0, 0.05, 0.1], "y": 0.0,
    ...                       "z": 0.0, "rot": 0.0, "keys": ["x+", "x+", ""]})
    >>> result = trial_metrics(frame, frame[["t", "x", "y", "z", "rot"]].to_numpy(), dt=0.5)
    >>> result["error"], result["effort"], result["effort_ticks"], result["duration"]
    (0.0, 1, 2, 1.0)
    >>> result["success"], result["timed_out"], result["arrival"]  # within 5 cm from 0.5 s
    (True, None, 0.5)
    """
    executed = frame[["t", "x", "y", "z", "rot"]].to_numpy(dtype=float)
    error, error_rot = trajectory_error(executed, intended, dt=dt)
    t = executed[:, 0]
    held = held_directions(frame)
    commands = commanded(frame, speed=speed, rot_speed=rot_speed)
    return {
        "error": error,
        "error_rot": error_rot,
        "efficiency": efficiency_cost(t, executed[:, 1:4]),
        "efficiency_rot": efficiency_cost(t, executed[:, 4]),
        "effort": presses(held),
        "effort_ticks": held_ticks(held),
        "duration": float(t[-1]),
        "ticks": len(t),
        "timed_out": timed_out(float(t[-1]), max_duration, dt=dt),
        "success": task_success(executed, intended),
        "arrival": arrival_time(executed, intended),
        "input": input,
        "command_time": command_time(t, commands),
        "command_integral": command_integral(t, commands, speed=speed, rot_speed=rot_speed),
    }


def relative_effort(trials: pd.DataFrame, column: str = "effort") -> pd.Series:
    """Each trial's ``column`` divided by its participant's NA value on the same task.

    Parameters
    ----------
    trials : pandas.DataFrame
        One row per trial with ``participant, task, method, phase`` and ``column``.
    column : str
        The effort count to relate (``"effort"`` or ``"effort_ticks"``).

    Returns
    -------
    pandas.Series
        Aligned with ``trials``; NaN where the participant has no NA trial of
        that task (in a phase of :data:`REFERENCE_PHASES`) or its effort is 0.

    Raises
    ------
    ValueError
        If a participant has more than one NA reference trial for a task.

    Examples
    --------
    >>> trials = pd.DataFrame({"participant": ["p1", "p1", "p1"],
    ...                        "task": ["unknown_goal"] * 3,
    ...                        "method": ["NA", "CASA", "NA"],
    ...                        "phase": ["before_learning", "after_learning", "demonstration"],
    ...                        "effort": [40, 10, 99]})
    >>> relative_effort(trials).tolist()
    [1.0, 0.25, 2.475]
    """
    is_reference = trials["method"].eq(REFERENCE_METHOD) & trials["phase"].isin(REFERENCE_PHASES)
    reference = trials.loc[is_reference, ["participant", "task", column]]
    repeated = reference.duplicated(subset=["participant", "task"], keep=False)
    if repeated.any():
        first = reference[repeated].iloc[0]
        raise ValueError(
            f"participant {first['participant']!r} has several NA trials of task "
            f"{first['task']!r}; relative effort needs exactly one"
        )
    denominator = reference.set_index(["participant", "task"])[column].astype(float)
    denominator = denominator.where(denominator > 0)
    keys = pd.MultiIndex.from_frame(trials[["participant", "task"]])
    values = denominator.reindex(keys).to_numpy()
    return pd.Series(trials[column].to_numpy(dtype=float) / values, index=trials.index)
