"""The simulated JACO arm: pybullet in the loop of a 20 Hz Cartesian velocity controller.

Every control tick (``dt`` = 0.05 s) :meth:`ArmSimulation.step` takes a Cartesian
velocity ``[vx, vy, vz, vrot]`` (the blended action), turns the Cartesian part into
joint velocities through pybullet's Jacobian by damped least squares and the rotation
into a turn of the last joint (as the original implementation does, see
docs/paper-to-code.md), lets pybullet's velocity motors
drive the joints for ``dt`` and reads the end-effector pose and the joints back from
pybullet. The tool orientation is held at :func:`~casa_core.robot.kinematics.ee_rotation`
of the current ``rot``: only the last joint's turn changes it.

To make the arm move at the commanded speed instead of drifting with integration
errors, the controller tracks a reference pose integrated from the commands
(feed-forward velocity plus a proportional correction). The reference is never allowed
to run more than ``max_lag`` ahead of the arm, so that a blocked arm (table, joint
limit) does not wind up and jump when released.

Gravity is off: the real arm's firmware compensates it, and a sagging arm is not what
a participant's keys ask for.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import numpy as np
import pybullet as p

from casa_core.defaults import TICK
from casa_core.robot import kinematics as kin
from casa_core.robot.control_kernel import joint_velocities as _joint_velocities
from casa_core.robot.control_kernel import read_pose as _read_pose
from casa_core.robot.scene import SceneBodies, build_scene
from casa_core.scene import Scene

URDF_PATH = Path(str(files("casa_core.robot").joinpath("j2s7s300.urdf")))

TOOL_LINK = 7
#: pybullet's link of each point a scene may measure the arm at (``Scene.point``): the tool
#: point, or the origin of link 7 (the last arm link, just before the tool's).
POINT_LINKS = {"tool": TOOL_LINK, "link7": TOOL_LINK - 1}
ARM_JOINTS = list(range(kin.N_JOINTS))


@dataclass(frozen=True)
class ControllerSettings:
    """Gains of the Cartesian velocity controller.

    Attributes
    ----------
    dt : float
        Control tick (s): 0.05 s (20 Hz), the original implementation's.
    substeps : int
        pybullet physics steps per tick.
    damping : float
        Damping of the least-squares Jacobian inverse (m); keeps joint speeds bounded
        near singular configurations.
    position_gain, orientation_gain : float
        Proportional gains (1/s) pulling the arm onto the reference pose.
    null_gain : float
        Gain (1/s) of the null-space motion centring joints 2, 4, 6 in their limits.
    max_lag : float
        Largest distance (m, and rad for orientation) the reference may run ahead.
    motor_force : float
        Largest torque (N m) a velocity motor may apply.
    """

    dt: float = TICK
    substeps: int = 2
    damping: float = 0.02
    position_gain: float = 5.0
    orientation_gain: float = 5.0
    null_gain: float = 0.5
    max_lag: float = 0.01
    motor_force: float = 200.0


class ArmSimulation:
    """The JACO arm and the task scene in a pybullet client.

    Parameters
    ----------
    scene : Scene
        The task scene; the arm starts at ``scene.start_state``.
    gui : bool
        Open a pybullet window (needs a display) instead of running headless.
    settings : ControllerSettings, optional
        Controller gains; default :class:`ControllerSettings` with the scene's
        ``teleop.dt`` as the tick.
    gui_options : str
        pybullet's window options (``p.connect``'s ``options``), e.g.
        ``"--width=1024 --height=768"``.
    start_q : array_like, optional
        Joint angles (rad) to start at; default the scene's ``start.joints`` where it
        gives them (the original's start angles, whose tool orientation is not the held
        one), else the inverse kinematics of the scene's start state.

    Notes
    -----
    The state the rest of the code sees is ``[x, y, z, rot]``: the position of the scene's
    point (``scene.point``: the tool point, or link 7's origin; :data:`POINT_LINKS`) in the
    robot base frame (m) and the angle of the last joint's turn (rad), unwrapped so that
    it grows past pi when a participant keeps rotating. The Cartesian controller moves that
    point. Use as a context manager or call :meth:`close`.
    """

    def __init__(
        self,
        scene: Scene,
        *,
        gui: bool = False,
        settings: ControllerSettings | None = None,
        gui_options: str = "",
        start_q=None,
    ):
        if settings is None:
            settings = ControllerSettings(dt=scene.teleop.dt)
        self.settings = settings
        self.scene = scene
        self.point_link = POINT_LINKS[scene.point]
        self.gui = gui
        if gui and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            # pybullet's window needs X11 and would end the whole process without one.
            raise RuntimeError(
                "the pybullet window needs a display, but DISPLAY is not set: run in a "
                "desktop session (or under xvfb-run for tests)"
            )
        self.client = p.connect(p.GUI, options=gui_options) if gui else p.connect(p.DIRECT)
        if self.client < 0:
            raise RuntimeError("pybullet could not connect (no display for the GUI?)")
        try:
            p.setGravity(0, 0, 0, physicsClientId=self.client)
            p.setTimeStep(self.settings.dt / self.settings.substeps, physicsClientId=self.client)
            self.robot = p.loadURDF(str(URDF_PATH), useFixedBase=True, physicsClientId=self.client)
            self.bodies: SceneBodies = build_scene(self.client, scene)
        except Exception:
            p.disconnect(self.client)
            raise
        s = self.settings
        self._gains = np.array(
            [s.dt, s.max_lag, s.position_gain, s.orientation_gain, s.damping, s.null_gain]
        )
        self._zeros = [0.0] * kin.N_JOINTS
        self._q = np.zeros(kin.N_JOINTS)
        self._state = np.zeros(4)
        self._reference = np.zeros(4)
        if start_q is None:
            self.reset_to_start()
        else:
            self.reset(scene.start_state, q=start_q)

    # -- lifecycle ---------------------------------------------------------------------
    def close(self) -> None:
        """Disconnect from pybullet (idempotent)."""
        if self.client is not None and p.isConnected(self.client):
            p.disconnect(self.client)
        self.client = None

    def __enter__(self) -> ArmSimulation:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- state -------------------------------------------------------------------------
    @property
    def state(self) -> np.ndarray:
        """``[x, y, z, rot]`` as last read from pybullet (a copy)."""
        return self._state.copy()

    @property
    def q(self) -> np.ndarray:
        """Joint angles q1..q7 (rad) as last read from pybullet (a copy)."""
        return self._q.copy()

    def ee_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Tool position ``(3,)`` and rotation matrix ``(3, 3)`` read from pybullet now."""
        link = p.getLinkState(
            self.robot, TOOL_LINK, computeForwardKinematics=True, physicsClientId=self.client
        )
        rotation = np.array(p.getMatrixFromQuaternion(link[5])).reshape(3, 3)
        return np.array(link[4]), rotation

    def link7(self) -> np.ndarray:
        """Position ``(3,)`` of the link-7 origin, the original's end effector, read now."""
        link = p.getLinkState(
            self.robot,
            POINT_LINKS["link7"],
            computeForwardKinematics=True,
            physicsClientId=self.client,
        )
        return np.array(link[4])

    def _read(self) -> None:
        joints = p.getJointStates(self.robot, ARM_JOINTS, physicsClientId=self.client)
        self._q = np.array([joint[0] for joint in joints])
        link = p.getLinkState(
            self.robot, TOOL_LINK, computeForwardKinematics=True, physicsClientId=self.client
        )
        position = link[4]
        if self.point_link != TOOL_LINK:
            position = p.getLinkState(
                self.robot,
                self.point_link,
                computeForwardKinematics=True,
                physicsClientId=self.client,
            )[4]
        # One compiled call: the rotation matrix and rot, unwrapped from the last reading.
        self._state, self._rotation = _read_pose(
            position, p.getMatrixFromQuaternion(link[5]), float(self._state[3])
        )

    def reset_to_start(self) -> np.ndarray:
        """Put the arm at the scene's start: its joint angles where the scene gives them
        (``start.joints``), else the inverse kinematics of its start state. Returns the
        state read back."""
        return self.reset(self.scene.start_state, q=self.scene.start.joints)

    def reset(self, state, q=None) -> np.ndarray:
        """Put the arm at ``state`` = ``[x, y, z, rot]`` (by inverse kinematics of the tool
        point) or at ``q``, which a scene measured at another point must give.

        Returns the state read back from pybullet.
        """
        state = np.asarray(state, dtype=float)
        if q is None:
            if self.point_link != TOOL_LINK:
                raise ValueError(
                    f"a scene measured at {self.scene.point} starts the arm at joint angles "
                    "(start.joints), not by inverse kinematics of the tool point"
                )
            q = kin.inverse_kinematics(state[:3], state[3])
        for joint, angle in zip(ARM_JOINTS, q, strict=True):
            p.resetJointState(self.robot, joint, angle, 0.0, physicsClientId=self.client)
        self._state = np.array([0.0, 0.0, 0.0, state[3]])
        self._read()
        self._reference = self._state.copy()
        return self.state

    # -- control -----------------------------------------------------------------------
    def joint_velocities(self, action) -> np.ndarray:
        """Joint velocities realising the Cartesian velocity ``action`` from the current pose.

        Returns the damped least-squares solution for the feed-forward velocity plus the
        correction toward the reference pose, with ``vrot`` added to the last joint,
        then advances the reference by ``action * dt``. A null-space term centres the
        bounded joints; the result is scaled down uniformly when a joint would exceed
        its speed limit. The formula is
        :func:`~casa_core.robot.control_kernel.joint_velocities_numpy`, computed in one
        compiled call.
        """
        action = np.asarray(action, dtype=float)
        if action.shape == (4,):
            linear, angular = p.calculateJacobian(
                self.robot,
                self.point_link,
                [0.0, 0.0, 0.0],
                self._q.tolist(),
                self._zeros,
                self._zeros,
                physicsClientId=self.client,
            )
            # One compiled call (casa_core.robot.control_kernel); advances the reference.
            qdot = _joint_velocities(
                linear,
                angular,
                self._q,
                self._state,
                self._reference,
                self._rotation,
                action,
                self._gains,
            )
            if len(qdot):
                return qdot
        raise ValueError(f"action must be 4 finite numbers [vx, vy, vz, vrot], got {action}")

    def step(self, action) -> np.ndarray:
        """Drive the arm with Cartesian velocity ``action`` for one tick; return the new state.

        Parameters
        ----------
        action : array_like, shape (4,)
            ``[vx, vy, vz, vrot]`` in m/s and rad/s, base frame.
        """
        return self.step_joints(self.joint_velocities(action))

    def step_joints(self, qdot) -> np.ndarray:
        """Drive the joints at velocities ``qdot`` (rad/s, seven) for one tick; return the
        new state. What :meth:`step` does after its controller, and what a joint velocity
        controller does with a command from outside (``casa ros2 sim``)."""
        qdot = np.asarray(qdot, dtype=float)
        p.setJointMotorControlArray(
            self.robot,
            ARM_JOINTS,
            p.VELOCITY_CONTROL,
            targetVelocities=qdot.tolist(),
            forces=[self.settings.motor_force] * kin.N_JOINTS,
            physicsClientId=self.client,
        )
        for _ in range(self.settings.substeps):
            p.stepSimulation(physicsClientId=self.client)
        self._read()
        return self.state
