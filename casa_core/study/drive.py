"""How a control tick's keys and the robot's action move the arm, per teleoperation mode.

The scene's ``teleop.mode`` (:data:`casa_core.vocabulary.TELEOP_MODES`) chooses:

- ``held`` (:class:`HeldDrive`): the keys are a Cartesian velocity of the tool point, T(a);
  the assistant blends it with the robot's u* and the simulation's Cartesian controller
  drives the blend, holding the tool orientation.
- ``original`` (:class:`OriginalDrive`): the keys move a target for link 7 and
  position-only inverse kinematics gives the user's joint velocities, as in the authors'
  implementation (:class:`casa_core.robot.original_teleop.OriginalTeleoperation`). The
  robot's u* becomes joint velocities the same way, and the two are blended in joint
  space, ``alpha q_user + (1 - alpha) q_robot``, as the original blends. Inference observes
  the velocity of the user's joint command at the scene's point (the state's position:
  link 7 on the authors' layout, ``point: link7``) as T(a). The state's ``rot`` is the
  wrist turn: the scene's start ``rot`` plus joint 7's turn (backwards positive, as
  ``rot+``) since the start, since the tool's orientation no longer tells it.

Each also drives the arm by the robot's command alone (``follow``), as the learned pour's
tilt is measured (:func:`casa_core.study.learning_evidence.tool_tilt_deg`). Both start the
arm at the scene's start (:meth:`ArmSimulation.reset_to_start`): at its
joint angles where the scene gives them (``start.joints``), else at the inverse kinematics
of its position with the held orientation.
"""

from __future__ import annotations

import numpy as np

from casa_core.assist.assistant import Assistant
from casa_core.model.arbitration import blend
from casa_core.robot.keys import keys_to_action
from casa_core.robot.original_teleop import OriginalTeleoperation
from casa_core.robot.sim import ArmSimulation
from casa_core.scene import Scene


class HeldDrive:
    """Cartesian keys, blended in Cartesian space, the tool orientation held."""

    def __init__(self, sim: ArmSimulation, scene: Scene):
        self.sim = sim
        self.scene = scene

    def start(self) -> np.ndarray:
        """Put the arm at the scene's start; return the state read back."""
        return self.sim.reset_to_start()

    def tick(
        self, assistant: Assistant, state, held, elapsed_in_step: float, *, command=None
    ) -> np.ndarray:
        """Drive one tick with the held keys (or a device's ``command``, the user's action
        itself) and the assistant's blend; return the new state."""
        teleop = self.scene.teleop
        if command is None:
            user_action = keys_to_action(held, teleop.speed, teleop.rot_speed)
        else:
            user_action = np.asarray(command, dtype=float)
        action = assistant.act(state, user_action, elapsed_in_step=elapsed_in_step)
        return self.sim.step(action)

    def follow(self, velocity) -> np.ndarray:
        """Drive one tick by the robot's own command, the state velocity ``velocity``
        ``[vx, vy, vz, vrot]`` (as u* alone); return the new state."""
        return self.sim.step(velocity)


class OriginalDrive:
    """The original's keys (link 7's target, position-only IK), blended in joint space."""

    def __init__(self, sim: ArmSimulation, scene: Scene):
        self.sim = sim
        self.scene = scene
        self.teleop = OriginalTeleoperation(sim)

    def start(self) -> np.ndarray:
        """Put the arm at the scene's start joints (or its start state); return the state."""
        state = self.sim.reset_to_start()
        self.teleop.reset()
        self._wrist_start = float(self.sim.q[-1])
        return self._with_wrist_turn(state)

    def _with_wrist_turn(self, state: np.ndarray) -> np.ndarray:
        """``state`` with ``rot`` the wrist turn since the start (module docstring)."""
        state = state.copy()
        state[3] = self.scene.start.rot - (float(self.sim.q[-1]) - self._wrist_start)
        return state

    def tick(
        self, assistant: Assistant, state, held, elapsed_in_step: float, *, command=None
    ) -> np.ndarray:
        """Drive one tick with the held keys or a device's ``command``; return the new state.

        The user's joint command is recorded by the assistant as its velocity at the
        scene's point (the evidence of inference). While the user has full authority the
        arm gets that command alone, exactly the original's; otherwise the blend with the
        robot's u* in joint space, whose share the assistant records as the velocity of
        the robot's joint command at the point, after which the keys' target is put back
        on link 7, so that the next key moves on from where the assisted arm is instead of
        pulling it back.
        """
        if command is None:
            user_joints = self.teleop.joint_command(held)
        else:
            user_joints = self.teleop.velocity_command(command)
        user_action = self.teleop.state_velocity(user_joints)
        alpha = assistant.alpha
        if alpha >= 1.0:
            assistant.record(user_action)
            return self._with_wrist_turn(self.sim.step_joints(user_joints))
        robot_joints = self.teleop.follow(assistant.robot_action(state, elapsed_in_step))
        # The robot's share as the arm gets it: its joint command's velocity at the point.
        robot_action = self.teleop.state_velocity(robot_joints)
        assistant.record(user_action, robot_action, alpha=alpha)
        state = self.sim.step_joints(blend(alpha, user_joints, robot_joints))
        self.teleop.reset()
        return self._with_wrist_turn(state)

    def follow(self, velocity) -> np.ndarray:
        """Drive one tick by the robot's own command, the state velocity ``velocity``
        ``[vx, vy, vz, vrot]`` turned into joint velocities as u* is; return the new state."""
        return self._with_wrist_turn(self.sim.step_joints(self.teleop.follow(velocity)))


DRIVES: dict[str, type[HeldDrive] | type[OriginalDrive]] = {
    "held": HeldDrive,
    "original": OriginalDrive,
}


def scene_drive(sim: ArmSimulation, scene: Scene) -> HeldDrive | OriginalDrive:
    """The drive of the scene's teleoperation mode.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> with ArmSimulation(load_scene()) as sim:
    ...     type(scene_drive(sim, load_scene().with_teleop_mode("original"))).__name__
    'OriginalDrive'
    """
    return DRIVES[scene.teleop.mode](sim, scene)


__all__ = ["DRIVES", "HeldDrive", "OriginalDrive", "scene_drive"]
