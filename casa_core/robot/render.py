"""The study's scene rendered by pybullet's software renderer, for ``figures/scene.png``.

The JACO arm at the start pose, the table, the goals in their colours, the pouring
target and bowl come from :class:`~casa_core.robot.sim.ArmSimulation` (which loads the
arm's URDF and builds the scene); this module adds the tasks' intended trajectories
(:func:`casa_core.assist.tasks.intended_trajectory`) as thin tubes, the cup in the hand at the
start, the cup tilted at the pouring pose and a dashed plumb line from there down to
the bowl, and renders the view with ``ER_TINY_RENDERER``, which needs no display or
GPU. :func:`scene_landmarks` gives where the cup, the pouring pose and the bowl land in
the image, for the figure's labels (:func:`casa_core.figures.scene.scene_figure`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from casa_core.assist.tasks import intended_trajectory
from casa_core.fixed_order import length
from casa_core.robot.camera import scene_camera
from casa_core.robot.kinematics import ee_rotation, forward_kinematics
from casa_core.robot.scene import BOWL_RADIUS, COLORS, bowl_height
from casa_core.scene import Scene

TUBE_RADIUS = 0.005  # m
#: The cup as drawn: a cylinder along the tool's x axis (its mouth), centred where the
#: tool holds it; larger than the hand's fingers so that it shows around them.
CUP_RADIUS, CUP_LENGTH = 0.042, 0.12  # m
#: The plumb line from the pouring pose to the bowl: dashes and gaps (m), and colour.
DASH, GAP = 0.018, 0.012
PLUMB_RGBA = (0.15, 0.15, 0.15, 1.0)


def _segment(client: int, a: np.ndarray, b: np.ndarray, rgba, radius: float = TUBE_RADIUS) -> None:
    """A visual-only cylinder from ``a`` to ``b`` (pybullet cylinders lie along local z)."""
    import pybullet as p

    axis = b - a
    size = length(axis)
    if size < 1e-6:
        return
    z = axis / size
    # Rotation taking local z to the segment's direction: about z x axis by the angle.
    cross = np.cross([0.0, 0.0, 1.0], z)
    sin, cos = length(cross), float(z[2])
    if sin < 1e-9:
        quaternion = (0.0, 0.0, 0.0, 1.0) if cos > 0 else (1.0, 0.0, 0.0, 0.0)
    else:
        half = np.arctan2(sin, cos) / 2
        quaternion = (*(np.sin(half) * cross / sin), np.cos(half))
    shape = p.createVisualShape(
        p.GEOM_CYLINDER, radius=radius, length=size, rgbaColor=rgba, physicsClientId=client
    )
    p.createMultiBody(
        baseMass=0,
        baseVisualShapeIndex=shape,
        basePosition=list((a + b) / 2),
        baseOrientation=quaternion,
        physicsClientId=client,
    )


def _cup(client: int, position, rotation: np.ndarray, rgba) -> None:
    """The cup held at ``position`` by a tool of orientation ``rotation`` (mouth along x)."""
    axis = rotation[:, 0]
    centre = np.asarray(position, dtype=float)
    half = 0.5 * CUP_LENGTH * axis
    _segment(client, centre - half, centre + half, rgba, radius=CUP_RADIUS)


def _plumb_line(client: int, top, bottom) -> None:
    """A dashed vertical line from ``top`` down to ``bottom``."""
    top, bottom = np.asarray(top, dtype=float), np.asarray(bottom, dtype=float)
    size = length(top - bottom)
    direction = (bottom - top) / size if size > 0 else np.zeros(3)
    start = 0.0
    while start < size:
        end = min(start + DASH, size)
        _segment(client, top + start * direction, top + end * direction, PLUMB_RGBA, radius=0.003)
        start = end + GAP


def start_tool_pose(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """The tool's position ``(3,)`` and orientation ``(3, 3)`` at the scene's start: of its
    start joint angles where it gives them, else the held orientation at its start."""
    if scene.start.joints is not None:
        pose = forward_kinematics(scene.start.joints)
        return pose[:3, 3], pose[:3, :3]
    return np.asarray(scene.start.position, dtype=float), ee_rotation(scene.start.rot)


def landmark_positions(scene: Scene) -> dict[str, np.ndarray]:
    """The scene's points the figure labels, in the robot base frame (m).

    ``"cup"``: the top of the cup in the hand at the start; ``"pouring pose"``: where
    the cup is held to pour; ``"bowl"``: the near rim of the bowl's top, under it.
    """
    tool, rotation = start_tool_pose(scene)
    pour = np.asarray(scene.pouring.position, dtype=float)
    bowl = np.asarray(scene.pouring.bowl, dtype=float)
    return {
        "cup": tool + 0.5 * CUP_LENGTH * rotation[:, 0],
        "pouring pose": pour,
        "bowl": np.array([bowl[0] - BOWL_RADIUS, bowl[1], bowl_height(scene)]),
    }


def _camera(scene: Scene, width: int, height: int) -> tuple[list[float], list[float]]:
    """pybullet's view and projection matrices of the scene's figure camera."""
    camera = scene_camera(scene, "figure")
    return camera.view_matrix(), camera.projection_matrix(width / height)


def scene_landmarks(
    scene: Scene, *, width: int = 1200, height: int = 900
) -> dict[str, tuple[float, float]]:
    """Where :func:`landmark_positions` land in :func:`render_scene`'s image, in pixels.

    Returns
    -------
    dict
        Name -> ``(column, row)`` from the image's top-left corner, for an image of
        ``width`` x ``height`` pixels rendered with the same camera.
    """
    camera = scene_camera(scene, "figure")
    landmarks = landmark_positions(scene)
    pixels = camera.pixels(np.array(list(landmarks.values())), width=width, height=height)
    return {name: (float(u), float(v)) for name, (u, v) in zip(landmarks, pixels, strict=True)}


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
    """Render the arm, the scene, the cup and the tasks' intended trajectories headless.

    The cup is drawn twice, in :data:`casa_core.robot.scene.COLORS` ``"cup"``: in the hand
    at the start, and tilted to ``scene.pouring.tilt`` at the pouring pose (``"cup
    poured"``), with a dashed plumb line from there to the bowl.

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
        # be an opaque ball hiding the goals. The cup tilted there marks the spot.
        p.removeBody(sim.bodies.pouring, physicsClientId=client)
        for task, colour in (paths or {}).items():
            # One sample a second is plenty: the references are straight segments.
            positions = intended_trajectory(task, scene, dt=1.0)[:, 1:4]
            _path(client, positions, to_rgba(colour))
        _cup(client, *start_tool_pose(scene), COLORS["cup"])
        _cup(client, scene.pouring.position, ee_rotation(scene.pouring.tilt), COLORS["cup poured"])
        bowl = scene.pouring.bowl
        _plumb_line(client, scene.pouring.position, (bowl[0], bowl[1], bowl_height(scene)))
        view, projection = _camera(scene, width, height)
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
