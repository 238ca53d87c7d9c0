"""What the study gives the learner, and how it judges what was learned.

The study's learned intents see five objects of the scene (:func:`scene_objects`); a
learned intent is judged by where its own optimum ends, against the demonstrations,
and by the cup's tilt there, measured on the tool of the arm driven along that optimum
(:func:`learning_evidence`, the columns of ``learning.csv``; :func:`tool_tilt_deg`).
"""

from __future__ import annotations

import numpy as np

from casa_core.fixed_order import length
from casa_core.planning import PlannedIntent
from casa_core.robot.sim import ArmSimulation
from casa_core.scene import Scene
from casa_core.study.drive import scene_drive

#: The scene objects whose positions are the learned cost's features, in feature order.
STUDY_OBJECTS = ("green", "purple", "red", "pouring", "bowl")


def scene_objects(scene: Scene) -> dict[str, np.ndarray]:
    """The study's objects of ``scene``: the three goals, the pouring target and the bowl.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> objects = scene_objects(load_scene())
    >>> list(objects) == list(STUDY_OBJECTS), objects["red"].tolist()
    (True, [0.4, 0.22, 0.12])
    """
    objects = {name: scene.goal(name) for name in STUDY_OBJECTS[:3]}
    objects["pouring"] = np.array(scene.pouring.position, dtype=float)
    objects["bowl"] = np.array(scene.pouring.bowl, dtype=float)
    return objects


def tool_tilt_deg(scene: Scene, trajectory) -> float:
    """The cup's tilt from upright (degrees), measured on the tool, once the arm has been
    driven along ``trajectory`` (rows ``[t, x, y, z, rot]``, ``t`` from 0) in pybullet.

    The arm starts at the scene's start and each control tick the robot's own command
    (the drive of the scene's teleoperation mode, :func:`casa_core.study.drive.scene_drive`)
    moves it toward the trajectory's state one tick later. The tilt is the angle between
    the tool's x axis (the cup's axis) and world up, read from pybullet: with the
    orientation held it is the turn of ``rot``; in the original teleoperation, where the
    orientation follows the reach, it is what the wrist turn does to a cup at that reach.

    Examples
    --------
    >>> from casa_core.assist.tasks import intended_trajectory
    >>> from casa_core.scene import load_scene
    >>> scene = load_scene()
    >>> round(tool_tilt_deg(scene, intended_trajectory("unknown_skill", scene)))
    103
    """
    trajectory = np.asarray(trajectory, dtype=float)
    with ArmSimulation(scene) as sim:
        drive = scene_drive(sim, scene)
        state = drive.start()
        dt = sim.settings.dt
        times = np.arange(dt, trajectory[-1, 0] + dt / 2, dt)
        targets = np.column_stack([np.interp(times, trajectory[:, 0], c) for c in trajectory.T[1:]])
        for target in targets:
            state = drive.follow((target - state) / dt)
        _, rotation = sim.ee_pose()
    return float(np.degrees(np.arccos(np.clip(rotation[2, 0], -1.0, 1.0))))


def learning_evidence(intent: PlannedIntent, demos, *, scene: Scene) -> dict:
    """How well a learned intent reproduces its demonstrations on ``scene``.

    The intent's optimal trajectory is planned from the mean start of the
    demonstrations over the full horizon.

    Returns
    -------
    dict
        ``endpoint_error_m``: distance (m) from the end of that trajectory to the
        mean end of the demonstrations; ``final_tilt_deg``: the cup's tilt from
        upright (degrees) at that end, measured on the tool (:func:`tool_tilt_deg`).

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> from casa_core.planning.pouring import PouringIntent
    >>> scene = load_scene()
    >>> demo = np.array([[0.0, *scene.start_state], [20.0, *scene.pouring.position, 1.8]])
    >>> evidence = learning_evidence(PouringIntent.from_scene(scene), [demo], scene=scene)
    >>> evidence["endpoint_error_m"] < 0.01, round(evidence["final_tilt_deg"] / 10)
    (True, 10)
    """
    demos = [np.asarray(d, dtype=float) for d in demos]
    start = np.mean([d[0, 1:5] for d in demos], axis=0)
    end = np.mean([d[-1, 1:4] for d in demos], axis=0)
    states = intent.optimal_trajectory(start, intent.planner.horizon)
    times = intent.planner.dt * np.arange(len(states))
    return {
        "endpoint_error_m": length(states[-1, :3] - end),
        "final_tilt_deg": tool_tilt_deg(scene, np.c_[times, states]),
    }
