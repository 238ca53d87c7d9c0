"""The study's scene rendered by pybullet's software renderer, for ``figures/scene.png``.

The JACO arm at the start pose, the table, the goals in their colours, the pouring
target and bowl come from :class:`~casa_core.robot.sim.ArmSimulation` (which loads the
arm's URDF and builds the scene); this module adds the tasks' intended trajectories
(:func:`casa_core.tasks.intended_trajectory`) as thin tubes and renders the view with
``ER_TINY_RENDERER``, which needs no display or GPU. The figure around the image is
:func:`casa_core.figures.scene.scene_figure`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from casa_core.scene import Scene
from casa_core.tasks import intended_trajectory

TUBE_RADIUS = 0.005  # m

#: The camera: looking at the workspace from the front left, above the table.
CAMERA = {
    "target": (0.32, -0.02, 0.18),
    "distance": 1.05,
    "yaw": 75.0,
    "pitch": -35.0,
    "fov": 40.0,
}


def _segment(client: int, a: np.ndarray, b: np.ndarray, rgba) -> None:
    """A visual-only cylinder from ``a`` to ``b`` (pybullet cylinders lie along local z)."""
    import pybullet as p

    axis = b - a
    length = float(np.linalg.norm(axis))
    if length < 1e-6:
        return
    z = axis / length
    # Rotation taking local z to the segment's direction: about z x axis by the angle.
    cross = np.cross([0.0, 0.0, 1.0], z)
    sin, cos = float(np.linalg.norm(cross)), float(z[2])
    if sin < 1e-9:
        quaternion = (0.0, 0.0, 0.0, 1.0) if cos > 0 else (1.0, 0.0, 0.0, 0.0)
    else:
        half = np.arctan2(sin, cos) / 2
        quaternion = (*(np.sin(half) * cross / sin), np.cos(half))
    shape = p.createVisualShape(
        p.GEOM_CYLINDER, radius=TUBE_RADIUS, length=length, rgbaColor=rgba, physicsClientId=client
    )
    p.createMultiBody(
        baseMass=0,
        baseVisualShapeIndex=shape,
        basePosition=list((a + b) / 2),
        baseOrientation=quaternion,
        physicsClientId=client,
    )


def _path(client: int, positions: np.ndarray, rgba) -> None:
    """Tubes through the distinct consecutive ``positions`` ``(n, 3)``."""
    import pybullet as p

    keep = np.r_[True, np.linalg.norm(np.diff(positions, axis=0), axis=1) > 1e-6]
    points = positions[keep]
    for a, b in zip(points[:-1], points[1:], strict=True):
        _segment(client, a, b, rgba)
    # A ball at each bend so the tube has no gaps where segments meet.
    joint = p.createVisualShape(
        p.GEOM_SPHERE, radius=TUBE_RADIUS, rgbaColor=rgba, physicsClientId=client
    )
    for point in points[1:-1]:
        p.createMultiBody(
            baseMass=0, baseVisualShapeIndex=joint, basePosition=list(point), physicsClientId=client
        )


def render_scene(
    scene: Scene,
    paths: Mapping[str, str] | None = None,
    *,
    width: int = 1200,
    height: int = 900,
) -> np.ndarray:
    """Render the arm, the scene and the tasks' intended trajectories headless.

    Parameters
    ----------
    scene : Scene
        The study's scene (:func:`casa_core.scene.load_scene`).
    paths : mapping of str to colour, optional
        The tasks whose intended trajectories are drawn, each with its colour (any
        matplotlib colour, e.g. :data:`casa_core.figures.scene.TASK_PATHS`); none by
        default.
    width, height : int
        Image size in pixels.

    Returns
    -------
    ndarray
        ``(height, width, 3)`` RGB image, ``uint8``.
    """
    import pybullet as p
    from matplotlib.colors import to_rgba

    from casa_core.robot.sim import ArmSimulation

    with ArmSimulation(scene, gui=False) as sim:
        client = sim.client
        # The tiny renderer draws no transparency: the translucent pouring marker would
        # be an opaque ball hiding the goals. The pouring spot is where the Unknown
        # Skill path ends, above the bowl.
        p.removeBody(sim.bodies.pouring, physicsClientId=client)
        for task, colour in (paths or {}).items():
            # One sample a second is plenty: the references are straight segments.
            positions = intended_trajectory(task, scene, dt=1.0)[:, 1:4]
            _path(client, positions, to_rgba(colour))
        view = p.computeViewMatrixFromYawPitchRoll(
            cameraTargetPosition=CAMERA["target"],
            distance=CAMERA["distance"],
            yaw=CAMERA["yaw"],
            pitch=CAMERA["pitch"],
            roll=0.0,
            upAxisIndex=2,
        )
        projection = p.computeProjectionMatrixFOV(
            fov=CAMERA["fov"], aspect=width / height, nearVal=0.05, farVal=5.0
        )
        _, _, rgba, _, _ = p.getCameraImage(
            width,
            height,
            viewMatrix=view,
            projectionMatrix=projection,
            renderer=p.ER_TINY_RENDERER,
            shadow=1,
            lightDirection=[0.6, -0.4, 1.0],
            physicsClientId=client,
        )
    return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]
