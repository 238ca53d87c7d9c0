"""The original implementation's session files, read and checked.

The authors' original implementation (Python 2, on the real JACO) wrote one NumPy
``.npz`` per trial. :func:`read_session` loads one and checks every array it uses;
:mod:`casa_core.io.original.conversion` turns it into a casa-trial/1 trial and
:mod:`casa_core.io.original.importer` does this for a folder of them (``casa import
original``). The format is ``docs/data-contracts.md`` ("Importing the original
implementation's sessions"). How the original logged its inference, which decides how the
rows are read:

* **Waypoints.** The original records the joint angles ``traj_hist[j]`` at the first
  control-loop iteration at or after ``j * 0.5`` s (``j = 0`` is the start), 31 in a 15 s
  trial: the path its inference ran along.
* **Timed steps.** When it records a waypoint and no inference step is running, it starts
  one over the waypoints recorded so far; ``inf_start_time[k]`` is when step ``k`` started
  and row ``k`` of ``belief_hist``, ``beta_hist`` and ``sub_hist`` its result (its result
  arrived later, at a time the file does not keep). The first step starts at about 0.5 s,
  over waypoints 0 and 1. A step still running when a waypoint is recorded (after
  learning one can take 2 s) makes that waypoint start no step, so step ``k`` ran over the
  waypoints up to ``floor(inf_start_time[k] / 0.5)``: :func:`step_waypoints`.
* **The final step.** The histories have one row more than ``inf_start_time``: the last
  row is a step run after the 15 s trial had ended, over every waypoint and with the goal's
  pose penalty. It never changed alpha or the arm, and its beta can be negative.
* **No logged inference.** A session without betas (``beta_hist`` empty: NA and PBA, whose
  posterior lived in a joint table over goals and beta that was never saved) holds the
  uniform prior on every row of ``belief_hist``: those rows are not inference results.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from casa_core.defaults import DT
from casa_core.io.original._checker import Checker, SessionError, load_arrays
from casa_core.robot import kinematics as kin
from casa_core.scene import KNOWN_GOALS

#: The original's reference joint angles (degrees): start, its goals 0 and 1, the unknown goal.
REFERENCE_ANGLES = {
    "start": (180, 175, 180, 300, 180, 180, 190),
    "goal 0": (150, 130, 160, 240, 180, 172, 280),
    "goal 1": (210, 130, 200, 240, 180, 172, 280),
    "unknown goal": (123, 155, 131, 284, 180, 176, 189),
}
#: The arrays a session must have (``traj_hist`` and ``beta_hist`` are read when there).
REQUIRED_KEYS = ("cmdpos_time", "curr_pos", "joy_cmd", "inf_start_time", "belief_hist")
#: A step may be timed up to this share of a waypoint interval (0.5 s) before the waypoint
#: that started it: the loop's clock and the step's are read at different moments.
WAYPOINT_SLACK = 0.1


@dataclass(frozen=True)
class Session:
    """The arrays of one session file that the conversion reads, checked.

    Attributes
    ----------
    file : str
    time : numpy.ndarray
        (n,) seconds since the start, per control-loop sample (``cmdpos_time``).
    q, command : numpy.ndarray
        (n, 7) joint angles (``curr_pos``) and the user's command (``joy_cmd``).
    steps : numpy.ndarray
        (m,) when each timed inference step started (``inf_start_time``).
    step_waypoints : numpy.ndarray
        (m,) the last waypoint each timed step ran over (:func:`step_waypoints`).
    belief : numpy.ndarray
        (m, g) the timed steps' rows of ``belief_hist``.
    beta : numpy.ndarray or None
        (m, g) the timed steps' rows of ``beta_hist``; None when the session logged none.
    final_belief, final_beta : numpy.ndarray or None
        (g,) the last row, the step after the trial (``final_beta`` None without betas).
    waypoints : numpy.ndarray or None
        (w, 7) the recorded waypoints (``traj_hist``), None when the file has none.
    started : float or None
        The wall clock of the start (``start_T``).
    """

    file: str
    time: np.ndarray
    q: np.ndarray
    command: np.ndarray
    steps: np.ndarray
    step_waypoints: np.ndarray
    belief: np.ndarray
    beta: np.ndarray | None
    final_belief: np.ndarray
    final_beta: np.ndarray | None
    waypoints: np.ndarray | None
    started: float | None

    @property
    def logged_inference(self) -> bool:
        """Whether the rows hold inference results: False for a session without betas,
        whose ``belief_hist`` is the prior on every row."""
        return self.beta is not None

    @property
    def goals(self) -> int:
        return self.belief.shape[1]


def reference_q(name: str) -> np.ndarray:
    """The original's reference joint angles ``name`` (:data:`REFERENCE_ANGLES`), radians.

    Examples
    --------
    >>> kin.link7_position(reference_q("goal 0")).round(3)
    array([-0.548, -0.444,  0.424])
    """
    return np.radians(np.asarray(REFERENCE_ANGLES[name], dtype=float))


def step_waypoints(steps: np.ndarray) -> np.ndarray:
    """The last waypoint each step ran over: the one recorded when the step started.

    Waypoint ``j`` is recorded at ``j * 0.5`` s, so a step started at ``t`` ran over
    waypoints ``0 .. floor(t / 0.5)`` (timed up to :data:`WAYPOINT_SLACK` of an interval
    early).

    Examples
    --------
    >>> step_waypoints(np.array([0.503, 1.02, 3.01, 3.49]))  # a late step from 1.02 s
    array([1, 2, 6, 7])
    """
    return np.floor(np.asarray(steps, dtype=float) / DT + WAYPOINT_SLACK).astype(int)


def read_session(path: Path | str) -> Session:
    """Load and check one session file of the original implementation.

    Raises
    ------
    SessionError
        Listing every problem, each naming the file, the key and the rule: ``npz`` (not
        a readable archive), ``required-key``, ``pickle`` (an object array, never loaded),
        ``numbers``, ``shape``, ``finite-number``, ``rows`` (arrays of one length
        disagree), ``range``, ``increasing`` (times), ``waypoints`` (two steps started
        at one waypoint, or a step after the last recorded one).

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
    steps = check.array("inf_start_time", None)
    check.increasing("inf_start_time", steps)
    waypoints = None
    if "traj_hist" in check.arrays:
        waypoints = check.array("traj_hist", kin.N_JOINTS)
        if waypoints is not None and len(waypoints) < 2:
            check.fail("traj_hist", "shape", f"has {len(waypoints)} waypoint(s), needs 2 or more")
    at = None if steps is None else _waypoints_of_steps(check, steps, waypoints)
    histories = _inference_arrays(check, steps)
    raw_start = check.arrays.get("start_T")
    started = None
    if raw_start is not None and np.ndim(raw_start) == 0:
        started = float(raw_start) if np.asarray(raw_start).dtype.kind in "iuf" else None
    if check.problems or steps is None or at is None:  # their problems are listed
        raise SessionError(check.problems)
    belief, beta = histories
    return Session(
        file=str(path),
        time=time,
        q=q,
        command=command,
        steps=steps,
        step_waypoints=at,
        belief=belief[:-1],
        beta=None if beta is None else beta[:-1],
        final_belief=belief[-1],
        final_beta=None if beta is None else beta[-1],
        waypoints=waypoints,
        started=started,
    )


def _waypoints_of_steps(check: Checker, steps: np.ndarray, waypoints) -> np.ndarray | None:
    """:func:`step_waypoints` of the timed steps, checked against each other and traj_hist."""
    at = step_waypoints(steps)
    repeated = np.flatnonzero(np.diff(at) <= 0)
    if len(at) and at[0] < 1:
        message = f"step 0 started at {steps[0]:g} s, before waypoint 1 (0.5 s) was recorded"
        check.fail("inf_start_time", "waypoints", message)
        return None
    if len(repeated):
        k = int(repeated[0]) + 1
        message = (
            f"steps {k - 1} and {k} started at {steps[k - 1]:g} and {steps[k]:g} s, both "
            f"after waypoint {at[k]}: each step starts at a waypoint of its own (every 0.5 s)"
        )
        check.fail("inf_start_time", "waypoints", message)
        return None
    if waypoints is not None and len(at) and at[-1] >= len(waypoints):
        message = (
            f"step {len(at) - 1} started at {steps[-1]:g} s, after waypoint {at[-1]}, but "
            f"traj_hist has {len(waypoints)} waypoints (0 to {len(waypoints) - 1})"
        )
        check.fail("inf_start_time", "waypoints", message)
        return None
    return at


def _inference_arrays(check: Checker, steps):
    """``belief_hist`` (m + 1, g) and ``beta_hist`` (m + 1, g) or None, ``steps`` the m
    timed steps (the last row is the step after the trial)."""
    m = None if steps is None else len(steps)
    arrays: dict[str, np.ndarray | None] = {}
    for key in ("belief_hist", "beta_hist"):
        raw = check.arrays.get(key)
        if raw is None and key == "belief_hist":
            check.fail(key, "required-key", "missing")
            continue
        if raw is None or np.shape(raw) == (0,):
            if key == "belief_hist":
                check.fail(key, "shape", "is empty: every session has the step after the trial")
            arrays[key] = None
            continue
        value = check.array(key, 0, finite=False)
        if value is not None and m is not None and len(value) != m + 1:
            message = (
                f"has {len(value)} rows, expected {m + 1}: one per entry of inf_start_time "
                f"({m}) and the final step, run after the trial"
            )
            check.fail(key, "rows", message)
        arrays[key] = value
    belief, beta = arrays.get("belief_hist"), arrays.get("beta_hist")
    if belief is None:
        belief = np.zeros((1, len(KNOWN_GOALS)))
    if beta is not None and beta.shape[1] != belief.shape[1]:
        check.fail(
            "beta_hist", "shape", f"has {beta.shape[1]} goals, belief_hist {belief.shape[1]}"
        )
    return belief, beta


def started_at(session: Session) -> str | None:
    """The session's wall-clock start (``start_T``) as ISO 8601 UTC, or None.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> started_at(SimpleNamespace(started=1.6e9))
    '2020-09-13T12:26:40+00:00'
    """
    if session.started is None or not np.isfinite(session.started) or session.started <= 0:
        return None
    return datetime.fromtimestamp(session.started, UTC).isoformat()
