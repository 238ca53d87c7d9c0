"""The user study's objective metrics (paper, Sec. V-B), per trial.

For a trial logged at ticks ``t_0 < ... < t_{n-1}`` with end-effector positions
``p_i = (x_i, y_i, z_i)``, rotation ``r_i`` and held keys ``K_i``:

- **error** (m^2): the sum of squared differences between the executed and the
  intended trajectory, ``sum_j ||p(s_j) - p*(s_j)||^2``, and beside it
  **error_rot** (rad^2) ``sum_j (r(s_j) - r*(s_j))^2``. *Alignment in time*:
  both are compared at the same seconds since the start,
  ``s_j = j * dt`` for ``j = 0 .. ceil(max(T, T*) / dt)``, with ``dt`` the
  control tick, ``T`` the trial's last tick and ``T*`` the end of the intended
  trajectory (:func:`casa_core.tasks.intended_trajectory`). Each trajectory is
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
  the first tick counts once). Holding a key is one press.
- **effort_ticks**: the original implementation's counter, ``sum_i |K_i|``
  (a held key counts once per tick).
- **relative_effort**: ``effort`` divided by the same participant's ``effort`` in
  the NA condition of the same task (:func:`relative_effort`).
- **duration** (s): ``t_{n-1}``, the seconds from the trial's start to its last tick.

Both error sums and the efficiency cost grow with the number of ticks, as the
paper's sums do; compare them only across trials logged at the same tick rate.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

REFERENCE_METHOD = "NA"
# Phases whose NA trial is the reference of relative effort: the NA *condition*,
# not the demonstrations (also driven with NA) nor the familiarization.
REFERENCE_PHASES = ("no_misspecification", "before_learning")


def trajectory_error(executed: np.ndarray, intended: np.ndarray, dt: float) -> tuple[float, float]:
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
    """
    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float).reshape(len(t), -1)
    if len(t) < 2:
        return 0.0
    velocities = np.diff(values, axis=0) / np.diff(t)[:, None]
    return float(np.sum(velocities**2))


def held_keys(keys: Sequence[str]) -> list[frozenset[str]]:
    """The set of keys held at each tick, from the log's space-separated ``keys`` cells."""
    return [frozenset(cell.split()) for cell in keys]


def key_presses(keys: Sequence[str]) -> int:
    """Number of press events: a key not held at the previous tick and held at this one."""
    previous: frozenset[str] = frozenset()
    presses = 0
    for held in held_keys(keys):
        presses += len(held - previous)
        previous = held
    return presses


def key_ticks(keys: Sequence[str]) -> int:
    """The original's effort counter: keys held summed over ticks."""
    return sum(len(held) for held in held_keys(keys))


def trial_metrics(frame: pd.DataFrame, intended: np.ndarray, dt: float) -> dict[str, float]:
    """Every per-trial metric of one trial log (module docstring for the formulas).

    Parameters
    ----------
    frame : pandas.DataFrame
        A trial as returned by :func:`casa_core.logs.read_trial`.
    intended : ndarray, shape (m, 5)
        The task's intended trajectory ``[t, x, y, z, rot]``.
    dt : float
        The control tick (s), the step at which error is summed.

    Returns
    -------
    dict
        ``error, error_rot, efficiency, efficiency_rot, effort, effort_ticks,
        duration, ticks``.
    """
    executed = frame[["t", "x", "y", "z", "rot"]].to_numpy(dtype=float)
    error, error_rot = trajectory_error(executed, intended, dt)
    t = executed[:, 0]
    return {
        "error": error,
        "error_rot": error_rot,
        "efficiency": efficiency_cost(t, executed[:, 1:4]),
        "efficiency_rot": efficiency_cost(t, executed[:, 4]),
        "effort": key_presses(frame["keys"]),
        "effort_ticks": key_ticks(frame["keys"]),
        "duration": float(t[-1]),
        "ticks": len(t),
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
