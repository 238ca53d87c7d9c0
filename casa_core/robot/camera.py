"""Where the cameras look: the participant's window and the scene figure, per scene.

A :class:`Camera` is pybullet's orbit camera: a ``target`` point, a ``distance`` from it,
a ``yaw`` and ``pitch`` (degrees, z up) and a vertical field of view ``fov``. Each of the
two views has a role (:data:`ROLES`) with a fixed orientation and field of view:

- ``window`` (``casa teleop``, ``casa session``): behind the robot, looking along its +x
  axis and down, so that the arrow keys move the cup the way they point on screen and
  the simulated operators' depth axis (:mod:`casa_core.study.participants`) is the
  view's; the field of view is the pybullet window's own (90 degrees, measured);
- ``figure`` (``figures/scene.png``): from the front left, above the table.

A scene may pin either view (scene key ``view.window`` / ``view.figure``: ``target``,
``distance``, ``yaw``, ``pitch``); ``config/scene.yaml`` pins both. Otherwise
:func:`fit_camera` frames the scene's positions (start, goals, pouring pose, bowl) by a
fixed rule: the role's orientation, the target at the centre of their bounding box, and
the shortest distance (in steps of :data:`DISTANCE_STEP`) at which every position lies in
the image's central part, :data:`MARGIN` of each side left free. So any layout, the
authors' too, is seen whole.

Examples
--------
>>> from casa_core.scene import load_scene
>>> camera = scene_camera(load_scene("config/scene-original.yaml"), "window")
>>> (camera.yaw, camera.pitch, camera.fov)
(-90.0, -50.0, 90.0)
>>> bool(np.all(np.abs(camera.normalized(scene_positions(
...     load_scene("config/scene-original.yaml")), aspect=ASPECT)) <= 1 - 2 * MARGIN))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from casa_core.fixed_order import matmul
from casa_core.scene import Scene

#: Fraction of each side of the image that a fitted camera leaves free of positions.
MARGIN = 0.1
#: A fitted camera's distance is a multiple of this, m.
DISTANCE_STEP = 0.05
#: Shortest and longest distance a fitted camera may take, m.
DISTANCE_RANGE = (0.5, 5.0)


@dataclass(frozen=True)
class Camera:
    """pybullet's orbit camera: ``target`` (m), ``distance`` (m), ``yaw``, ``pitch`` and the
    vertical field of view ``fov`` (degrees), z up."""

    target: tuple[float, float, float]
    distance: float
    yaw: float
    pitch: float
    fov: float

    def view_matrix(self) -> list[float]:
        """pybullet's view matrix (column-major, 16 numbers)."""
        import pybullet as p

        return list(
            p.computeViewMatrixFromYawPitchRoll(
                cameraTargetPosition=list(self.target),
                distance=self.distance,
                yaw=self.yaw,
                pitch=self.pitch,
                roll=0.0,
                upAxisIndex=2,
            )
        )

    def projection_matrix(self, aspect: float) -> list[float]:
        """pybullet's perspective projection for an image ``aspect`` = width / height."""
        import pybullet as p

        return list(
            p.computeProjectionMatrixFOV(fov=self.fov, aspect=aspect, nearVal=0.05, farVal=5.0)
        )

    def normalized(self, points, *, aspect: float) -> np.ndarray:
        """Where ``points`` ``(n, 3)`` land in the image, ``(n, 2)`` in [-1, 1] from the
        bottom left corner to the top right; a point behind the camera is at infinity."""
        # pybullet's matrices are column-major: transpose to act on column vectors.
        to_clip = matmul(
            np.asarray(self.projection_matrix(aspect)).reshape(4, 4).T,
            np.asarray(self.view_matrix()).reshape(4, 4).T,
        )
        points = np.atleast_2d(np.asarray(points, dtype=float))
        clip = matmul(np.c_[points, np.ones(len(points))], to_clip.T)
        depth = clip[:, 3:]
        return np.where(depth > 0, clip[:, :2] / np.where(depth > 0, depth, 1.0), np.inf)

    def pixels(self, points, *, width: int, height: int) -> np.ndarray:
        """Where ``points`` ``(n, 3)`` land in a ``width`` x ``height`` image, ``(n, 2)``
        columns and rows from the top left corner."""
        xy = self.normalized(points, aspect=width / height)
        return np.c_[(xy[:, 0] + 1) / 2 * width, (1 - xy[:, 1]) / 2 * height]


#: Each view's orientation and field of view: ``(yaw, pitch, fov)`` in degrees.
ROLES: dict[str, tuple[float, float, float]] = {
    # Behind the robot along +x, pitched down enough that the arm hides no goal; pybullet's
    # window draws 90 degrees vertically (its projection matrix, read at 1024 x 768).
    "window": (-90.0, -50.0, 90.0),
    # From the front left, above the table.
    "figure": (75.0, -35.0, 40.0),
}
#: The image shape both views are fitted for, width / height: the session's window
#: (1024 x 768) and the figure's rendering (1200 x 900) are both 4:3.
ASPECT = 4 / 3


def scene_positions(scene: Scene) -> np.ndarray:
    """The positions a view must show, ``(n, 3)``: start, goals, pouring pose and bowl."""
    return np.array(
        [scene.start.position, *scene.goals.values(), scene.pouring.position, scene.pouring.bowl]
    )


def fit_camera(points, role: str) -> Camera:
    """The ``role``'s camera that frames ``points`` ``(n, 3)`` by the rule of the module.

    Raises
    ------
    ValueError
        If no distance in :data:`DISTANCE_RANGE` frames them.
    """
    yaw, pitch, fov = ROLES[role]
    points = np.atleast_2d(np.asarray(points, dtype=float))
    x, y, z = ((points.min(axis=0) + points.max(axis=0)) / 2).tolist()
    target = (x, y, z)
    low, high = DISTANCE_RANGE
    for step in range(round(low / DISTANCE_STEP), round(high / DISTANCE_STEP) + 1):
        camera = Camera(target, round(step * DISTANCE_STEP, 10), yaw, pitch, fov)
        if np.all(np.abs(camera.normalized(points, aspect=ASPECT)) <= 1 - 2 * MARGIN):
            return camera
    raise ValueError(f"no {role} camera within {low}-{high} m frames these positions: {points}")


def scene_camera(scene: Scene, role: str) -> Camera:
    """The ``role``'s camera of ``scene``: the view the scene pins, else :func:`fit_camera`
    of its :func:`scene_positions`."""
    if role not in ROLES:
        raise ValueError(f"camera role {role!r}: expected one of {', '.join(ROLES)}")
    pinned = scene.view.get(role)
    if pinned is None:
        return fit_camera(scene_positions(scene), role)
    return Camera(pinned.target, pinned.distance, pinned.yaw, pinned.pitch, ROLES[role][2])
