"""The study's scene rendered by pybullet's software renderer (``figures/scene.png``).

The JACO arm at the start pose, the table, the goals in their colours, the pouring
target and bowl come from the robot package's simulation (:class:`ArmSimulation`,
which loads the arm's URDF and calls the scene builder); this module adds the tasks'
intended trajectories (:func:`casa_core.tasks.intended_trajectory`) as thin tubes and
renders the view with ``ER_TINY_RENDERER``, which needs no display or GPU.
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from casa_core.figures import style
from casa_core.tasks import intended_trajectory

#: Tasks whose intended trajectories are drawn, with their colours: the colour of the
#: goal each one ends at (the pouring skill takes the first non-goal intent colour).
TASK_PATHS: dict[str, str] = {
    "known_goal": style.GOAL_COLOURS["green"],
    "unknown_goal": style.GOAL_COLOURS["red"],
    "unknown_skill": style.OTHER_INTENT_COLOURS[0],
}

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


def render_scene(scene: dict, width: int = 1200, height: int = 900) -> np.ndarray:
    """Render the arm, the scene and the intended trajectories headless.

    Parameters
    ----------
    scene : dict
        The layout of ``config/scene.yaml``.
    width, height : int
        Image size in pixels.

    Returns
    -------
    ndarray
        ``(height, width, 3)`` RGB image, ``uint8``.
    """
    import pybullet as p

    from casa_core.robot.sim import ArmSimulation

    with ArmSimulation(scene, gui=False) as sim:
        client = sim.client
        # The tiny renderer draws no transparency: the translucent pouring marker would
        # be an opaque ball hiding the goals. The pouring spot is where the Unknown
        # Skill path ends, above the bowl.
        p.removeBody(sim.bodies.pouring, physicsClientId=client)
        for task, colour in TASK_PATHS.items():
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


def crop_background(image: np.ndarray, margin: int = 8) -> np.ndarray:
    """Cut off the rows and columns that show only the background (the top-left colour)."""
    background = image[0, 0].astype(int)
    content = np.any(np.abs(image.astype(int) - background) > 8, axis=2)
    rows, cols = np.flatnonzero(content.any(axis=1)), np.flatnonzero(content.any(axis=0))
    if rows.size == 0:
        return image
    top, bottom = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, image.shape[0])
    left, right = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, image.shape[1])
    return image[top:bottom, left:right]


def scene_figure(scene: dict, image: np.ndarray | None = None) -> Figure:
    """The rendered scene with a legend of goals and intended trajectories.

    Parameters
    ----------
    scene : dict
        The layout of ``config/scene.yaml``.
    image : ndarray, optional
        A rendering from :func:`render_scene`; rendered here when not given.

    Returns
    -------
    Figure
        One axes showing the image, with a legend naming the goals and the tasks' paths.
    """
    if image is None:
        image = render_scene(scene)
    image = crop_background(image)
    height, width = image.shape[:2]
    with style.context():
        fig = style.new_figure(4.5, 4.5 * height / width + 0.6)
        ax = fig.subplots()
        ax.imshow(image, interpolation="lanczos")
        ax.set_axis_off()
        goal_words = {"green": "known", "purple": "known", "red": "unknown"}
        handles = [
            Line2D([], [], ls="", marker="o", ms=6, color=style.GOAL_COLOURS[name])
            for name in goal_words
        ]
        labels = [f"{name} goal ({word})" for name, word in goal_words.items()]
        handles += [Line2D([], [], color=colour, lw=2) for colour in TASK_PATHS.values()]
        labels += [f"{style.TASK_LABELS[task]} path" for task in TASK_PATHS]
        fig.legend(handles, labels, loc="outside upper center", ncols=3, handlelength=1.5)
        style.add_caption(
            fig,
            "The simulated JACO arm at the start pose, the goals, the bowl of the pouring"
            " task and the tasks' intended trajectories; the cup is poured where the Unknown"
            " Skill path ends (pybullet software renderer).",
        )
    return fig
