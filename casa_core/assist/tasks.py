"""The study's tasks and the trajectory each one intends.

A task's *intended trajectory* is the exemplary reference shown to participants
before each task (paper, Sec. V-A): straight Cartesian segments driven at the
teleoperation speed, then, for pouring, the cup tilted at the rotation speed. The
segments run from the start through the positions the scene's ``via`` names for the task
(none by default) to the task's end.
It is the reference of the error metric and the path simulated participants follow.
"""

from __future__ import annotations

import numpy as np

from casa_core.fixed_order import length
from casa_core.scene import Scene
from casa_core.vocabulary import TASKS

#: The familiarization's practice target: a goal of its own, not the Known Goal's green,
#: so that practice does not rehearse the task that follows.
PRACTICE_GOAL = "purple"


def task_waypoints(task: str, scene: Scene) -> np.ndarray:
    """Waypoints ``(n, 4)`` of ``[x, y, z, rot]`` that the task's reference visits in order.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> task_waypoints("unknown_skill", load_scene())[:, 3].tolist()
    [0.0, 0.0, 1.8]
    >>> task_waypoints("familiarization", load_scene())[-1].tolist()  # the purple goal
    [0.22, -0.4, 0.18, 0.0]
    """
    if task not in TASKS:
        raise ValueError(f"unknown task {task!r}; expected one of {', '.join(TASKS)}")
    start = scene.start_state
    passing = [[*position, start[3]] for position in scene.via.get(task, ())]
    if task == "familiarization":
        ends = [[*scene.goals[PRACTICE_GOAL], 0.0]]
    elif task == "known_goal":
        ends = [[*scene.goals["green"], 0.0]]
    elif task == "unknown_goal":
        ends = [[*scene.goals["red"], 0.0]]
    else:
        pour = scene.pouring.position
        ends = [[*pour, 0.0], [*pour, scene.pouring.tilt]]
    return np.array([start, *passing, *ends])


def intended_trajectory(task: str, scene: Scene, dt: float | None = None) -> np.ndarray:
    """The task's reference as an array ``(n, 5)`` of ``[t, x, y, z, rot]``.

    Each segment between waypoints is driven at ``teleop.speed`` (m/s) for the
    position and ``teleop.rot_speed`` (rad/s) for the rotation, whichever takes
    longer, and sampled every ``dt`` seconds (default: the control tick); the
    last sample sits exactly on the last waypoint.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> reference = intended_trajectory("known_goal", load_scene())
    >>> reference[-1, 1:].tolist()  # at the green goal, cup upright
    [0.58, 0.0, 0.3, 0.0]
    """
    teleop = scene.teleop
    dt = teleop.dt if dt is None else dt
    waypoints = task_waypoints(task, scene)
    times = [0.0]
    for a, b in zip(waypoints[:-1], waypoints[1:], strict=True):
        duration = max(length(b[:3] - a[:3]) / teleop.speed, abs(b[3] - a[3]) / teleop.rot_speed)
        times.append(times[-1] + duration)
    t = np.arange(0.0, times[-1], dt)
    t = np.append(t, times[-1])
    columns = [np.interp(t, times, waypoints[:, j]) for j in range(4)]
    return np.column_stack([t, *columns])
