"""The task scene in pybullet: table, goals and pouring target, from a :class:`Scene`.

The scene (:class:`casa_core.scene.Scene`) is loaded and validated once, at the edge,
and passed down. Goals and the pouring marker are visual only: nothing collides with
them, they show the participant where to go. The table top is the plane z = 0 of the
robot base.
"""

from __future__ import annotations

from dataclasses import dataclass

import pybullet as p

from casa_core.scene import REQUIRED_GOALS, Scene

#: Colours (RGBA) of the scene objects; goals are named after theirs.
COLORS = {
    "green": (0.1, 0.75, 0.2, 0.9),
    "purple": (0.55, 0.2, 0.8, 0.9),
    "red": (0.9, 0.1, 0.1, 0.9),
    "pouring": (0.2, 0.5, 0.95, 0.35),
    "bowl": (0.95, 0.8, 0.3, 1.0),
    # The cup: a saturated blue no goal, path or the arm has, so it stands out.
    "cup": (0.0, 0.35, 0.95, 1.0),
    "cup poured": (0.35, 0.6, 1.0, 1.0),
    "table": (0.72, 0.6, 0.45, 1.0),
}

GOAL_RADIUS = 0.03
BOWL_RADIUS = 0.07  # m


def bowl_height(scene: Scene) -> float:
    """Height (m) of the bowl: it stands on the table, centred at ``pouring.bowl``."""
    z = scene.pouring.bowl[2]
    return 2 * z if z > 0 else 0.04


@dataclass(frozen=True)
class SceneBodies:
    """pybullet body ids of the scene objects."""

    table: int
    goals: dict[str, int]
    pouring: int
    bowl: int


def _marker(client: int, position, radius: float, rgba) -> int:
    shape = p.createVisualShape(
        p.GEOM_SPHERE, radius=radius, rgbaColor=rgba, physicsClientId=client
    )
    return p.createMultiBody(
        baseMass=0, baseVisualShapeIndex=shape, basePosition=list(position), physicsClientId=client
    )


def build_scene(client: int, scene: Scene) -> SceneBodies:
    """Add the table, goals, pouring marker and bowl to a pybullet client.

    Parameters
    ----------
    client : int
        pybullet physics client id.
    scene : Scene
        Goals ``green``, ``purple`` and ``red``, ``pouring.position`` and
        ``pouring.bowl`` in the robot base frame (m).
    """
    half = [0.6, 0.75, 0.02]
    table_col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client)
    table_vis = p.createVisualShape(
        p.GEOM_BOX, halfExtents=half, rgbaColor=COLORS["table"], physicsClientId=client
    )
    # The top face lies at z = 0, the plane the robot base stands on.
    table = p.createMultiBody(
        baseMass=0,
        baseCollisionShapeIndex=table_col,
        baseVisualShapeIndex=table_vis,
        basePosition=[0.3, 0.0, -half[2]],
        physicsClientId=client,
    )
    goals = {
        name: _marker(client, scene.goal(name), GOAL_RADIUS, COLORS[name])
        for name in REQUIRED_GOALS
    }
    pouring = _marker(client, scene.pouring.position, 0.05, COLORS["pouring"])
    # The bowl is a cylinder standing on the table with its centre at ``pouring.bowl``.
    bowl_position = scene.pouring.bowl
    height = bowl_height(scene)
    bowl_vis = p.createVisualShape(
        p.GEOM_CYLINDER,
        radius=BOWL_RADIUS,
        length=height,
        rgbaColor=COLORS["bowl"],
        physicsClientId=client,
    )
    bowl = p.createMultiBody(
        baseMass=0,
        baseVisualShapeIndex=bowl_vis,
        basePosition=[bowl_position[0], bowl_position[1], height / 2],
        physicsClientId=client,
    )
    return SceneBodies(table=table, goals=goals, pouring=pouring, bowl=bowl)
