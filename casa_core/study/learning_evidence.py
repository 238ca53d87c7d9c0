"""What the study gives the learner, and how it judges what was learned.

The study's learned intents see five objects of the scene (:func:`scene_objects`); a
learned intent is judged by where its own optimum ends, against the demonstrations,
and by the cup's tilt there (:func:`learning_evidence`, the columns of ``learning.csv``).
"""

from __future__ import annotations

import numpy as np

from casa_core.fixed_order import length
from casa_core.planning import PlannedIntent
from casa_core.planning.pouring import cup_tilt_deg
from casa_core.scene import Scene

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


def learning_evidence(intent: PlannedIntent, demos) -> dict:
    """How well a learned intent reproduces its demonstrations.

    The intent's optimal trajectory is planned from the mean start of the
    demonstrations over the full horizon.

    Returns
    -------
    dict
        ``endpoint_error_m``: distance (m) from the end of that trajectory to the
        mean end of the demonstrations; ``final_tilt_deg``: the cup's tilt from
        upright (degrees) at that end.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> from casa_core.planning.pouring import PouringIntent
    >>> scene = load_scene()
    >>> demo = np.array([[0.0, *scene.start_state], [20.0, *scene.pouring.position, 1.8]])
    >>> evidence = learning_evidence(PouringIntent.from_scene(scene), [demo])
    >>> evidence["endpoint_error_m"] < 0.01, round(evidence["final_tilt_deg"] / 10)
    (True, 10)
    """
    demos = [np.asarray(d, dtype=float) for d in demos]
    start = np.mean([d[0, 1:5] for d in demos], axis=0)
    end = np.mean([d[-1, 1:4] for d in demos], axis=0)
    trajectory = intent.optimal_trajectory(start, intent.planner.horizon)
    return {
        "endpoint_error_m": length(trajectory[-1, :3] - end),
        "final_tilt_deg": float(cup_tilt_deg(trajectory[-1, 3])),
    }
