"""The original implementation's teleoperation: the keys move a target for link 7, and
inverse kinematics of its position alone gives the joint velocities.

Each tick of ``dt`` (0.05 s):

- each held translation key moves the target of link 7 (the original's end effector, the
  origin of the last link, 0.16 m before the tool point) by ``speed * dt`` (2.5 mm) along
  its axis of the robot base frame; opposite keys cancel;
- if the target moved, pybullet's ``calculateInverseKinematics`` for link 7 with the
  target's position only (no orientation, no null space: pybullet's damped least squares
  from the current joint angles) gives joint angles ``q_ik``, and the command is
  ``(q_ik - q) / dt``; if it did not move, the arm's joints are commanded to rest;
- each rotate key adds ``rot_speed`` (0.5 rad/s, 0.025 rad per tick) to joint 7's velocity:
  the wrist turns, not a Cartesian rotation. ``rot+`` turns joint 7 backwards, as the rotate
  keys of the held teleoperation do (:mod:`casa_core.robot.sim`) and as ``casa import
  original`` names the original's wrist commands, so that ``rot+`` pours in both.

Nothing holds the tool's orientation: it follows the reach. The target is kept from tick to
tick (a key moves the target, not the arm), and :meth:`OriginalTeleoperation.reset` puts it
on link 7 where the arm is.

Shared autonomy blends in joint space, as the original does: :meth:`~OriginalTeleoperation.follow`
turns the robot's Cartesian action u* into joint velocities the same way (position-only
inverse kinematics of the scene's point, whose velocity u* is), and
:meth:`~OriginalTeleoperation.state_velocity` says what a joint command does to the state
``[x, y, z, rot]``, the user's action T(a) that inference observes. On the authors' layout
the scene's point is link 7 (``point: link7``), so keys, u* and the state all move the
original's end effector. The speeds are the
scene's ``teleop`` ones (the original's). The other teleoperation, which holds the orientation, is
:meth:`casa_core.robot.sim.ArmSimulation.step` with :func:`casa_core.robot.keys.keys_to_action`.

Examples
--------
>>> import numpy as np
>>> from casa_core.robot.sim import ArmSimulation
>>> from casa_core.scene import load_scene
>>> with ArmSimulation(load_scene()) as sim:
...     teleop = OriginalTeleoperation(sim)
...     command = teleop.joint_command({"x+"})
...     sim.step_joints(command).shape, bool(np.allclose(teleop.target - sim.link7(), 0, atol=2e-3))
((4,), True)
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pybullet as p

from casa_core.fixed_order import matmul
from casa_core.robot.keys import KEY_DIRECTIONS, check_keys
from casa_core.robot.sim import POINT_LINKS

#: pybullet's index of link 7 (the last arm link) in casa's URDF, just before the tool's.
LINK7 = POINT_LINKS["link7"]


class OriginalTeleoperation:
    """Held keys to joint velocities, as the original implementation turns them.

    Parameters
    ----------
    sim : ArmSimulation
        The arm whose joints are read and whose pybullet client solves the kinematics.
    speed, rot_speed : float, optional
        Speed of a translation key (m/s) and of a rotate key (rad/s); default the scene's.
    dt : float, optional
        Tick (s); default the simulation's.
    """

    def __init__(self, sim, *, speed=None, rot_speed=None, dt=None):
        self.sim = sim
        self.speed = sim.scene.teleop.speed if speed is None else float(speed)
        self.rot_speed = sim.scene.teleop.rot_speed if rot_speed is None else float(rot_speed)
        self.dt = sim.settings.dt if dt is None else float(dt)
        self.reset()

    def reset(self) -> None:
        """Put the target on link 7 where the arm is now."""
        self.target = self.sim.link7()

    def joint_command(self, keys: Iterable[str]) -> np.ndarray:
        """Joint velocities ``(7,)`` (rad/s) for the keys held this tick; moves the target."""
        held = check_keys(keys)
        direction = np.zeros(4)
        for key in held:
            direction += KEY_DIRECTIONS[key]
        return self._joint_command(
            self.speed * self.dt * direction[:3], self.rot_speed * direction[3]
        )

    def velocity_command(self, velocity) -> np.ndarray:
        """Joint velocities ``(7,)`` for a continuous device's commanded ``[vx, vy, vz, vrot]``
        this tick, as keys are turned: the target moves by ``v * dt``; moves the target."""
        velocity = np.asarray(velocity, dtype=float)
        return self._joint_command(self.dt * velocity[:3], float(velocity[3]))

    def _joint_command(self, step: np.ndarray, turn: float) -> np.ndarray:
        """The target moved by ``step`` (m), position-only IK to it, and joint 7 turned
        backwards at ``turn`` (rad/s, as ``rot+``)."""
        command = np.zeros(len(self.sim.q))
        if np.any(step):
            self.target = self.target + step
            solution = p.calculateInverseKinematics(
                self.sim.robot,
                LINK7,
                self.target.tolist(),
                physicsClientId=self.sim.client,
            )
            command = (np.asarray(solution[: len(command)]) - self.sim.q) / self.dt
        command[-1] -= turn  # rot+ turns joint 7 backwards
        return command

    def follow(self, velocity) -> np.ndarray:
        """Joint velocities ``(7,)`` that move the scene's point (the state's position) at
        ``velocity`` = ``[vx, vy, vz, vrot]`` for one tick: position-only inverse kinematics
        of the point moved by ``v * dt``, and ``vrot`` on joint 7 (backwards, as ``rot+``).
        The target is not touched."""
        velocity = np.asarray(velocity, dtype=float)
        command = np.zeros(len(self.sim.q))
        if np.any(velocity[:3]):
            solution = p.calculateInverseKinematics(
                self.sim.robot,
                self.sim.point_link,
                (self.sim.state[:3] + velocity[:3] * self.dt).tolist(),
                physicsClientId=self.sim.client,
            )
            command = (np.asarray(solution[: len(command)]) - self.sim.q) / self.dt
        command[-1] -= velocity[3]
        return command

    def state_velocity(self, command) -> np.ndarray:
        """``[vx, vy, vz, vrot]`` of joint velocities ``command``: the velocity of the
        scene's point through pybullet's Jacobian at the current joints, and joint 7's turn
        (backwards positive, as ``rot+``)."""
        command = np.asarray(command, dtype=float)
        zeros = [0.0] * len(command)
        linear, _ = p.calculateJacobian(
            self.sim.robot,
            self.sim.point_link,
            [0.0, 0.0, 0.0],
            self.sim.q.tolist(),
            zeros,
            zeros,
            physicsClientId=self.sim.client,
        )
        return np.array([*matmul(np.asarray(linear), command), -command[-1]])


__all__ = ["LINK7", "OriginalTeleoperation"]
