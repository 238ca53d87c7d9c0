"""The assistant's control loop on live inputs, without ROS: one call per control tick.

:class:`AssistLoop` is what ``casa ros2 assist`` runs at 20 Hz. It takes the newest
joint state and user command with the times they arrived, and returns the joint
velocities to send, the ``casa/state`` text and the tick's log row. It is built as the
in-process closed loop (:mod:`casa_core.study.closed_loop`) builds one trial: the same
:class:`~casa_core.assist.assistant.Assistant`, inference every 0.5 s on the state
reached, the same blend and the same casa-trial/1 metadata; only the arm is outside.

The arm's state ``[x, y, z, rot]`` and the joint velocities realising the blended
Cartesian action come from a headless :class:`~casa_core.robot.sim.ArmSimulation` put
at the measured joint angles every tick: the simulated arm's own controller, without
its reference pose (the real arm's position is measured, not integrated).

Between two ticks, :meth:`AssistLoop.respond` answers a user command the moment it
arrives, with the same blend from the newest joint state and the last inference, so that
a command acts within the compute time and not a tick later; only the tick records,
counts evidence and infers.

Faults (:data:`~casa_core.ros2.messages.FAULTS`): with no fresh valid joint state the
command is zero; with no fresh valid user command the user's action is zero and the
robot's share is stopped (alpha 1), so the arm holds still. Either is logged once when
it starts and once when it ends.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from casa_core.assist.presets import Preset
from casa_core.assist.trial import inference_ticks
from casa_core.robot.sim import ArmSimulation
from casa_core.ros2.messages import (
    FAULTS,
    MAX_COMMAND_AGE,
    MAX_JOINT_STATE_AGE,
    action_keys,
    state_json,
)
from casa_core.scene import Scene
from casa_core.study.closed_loop import (
    TrialResult,
    trial_assistant,
    trial_intents,
    trial_meta,
)


@dataclass(frozen=True)
class Command:
    """What the arm is sent: joint velocities (rad/s) and the blended action they realise."""

    qdot: np.ndarray
    blended: np.ndarray


@dataclass(frozen=True)
class Tick:
    """What one control tick sends: the command, the ``casa/state`` text, the row."""

    command: Command
    state_text: str
    row: dict
    fault: str | None

    @property
    def qdot(self) -> np.ndarray:
        """The command's joint velocities."""
        return self.command.qdot


class AssistLoop:
    """One assisted trial fed by live inputs, tick by tick.

    Parameters
    ----------
    scene : Scene
        The task scene: goals (the known intents), speeds, the tick.
    task, method, participant, phase : str
        The trial's conditions, as casa-trial/1 writes them.
    inference : Preset
        The inference preset.
    learned : sequence of path, optional
        Learned intent files (casa-intent) the robot knows besides the known goals (after
        learning), as ``casa teleop --intent``.
    log : callable, optional
        ``log(text)`` for fault changes (the node's logger); default: nothing.
    max_duration : float
        Written to the metadata: the trial's time limit.
    max_command_age, max_joint_state_age : float
        The stated ages (s) beyond which a user command or a joint state is not used.
    """

    def __init__(
        self,
        scene: Scene,
        *,
        task: str,
        method: str,
        participant: str,
        phase: str,
        inference: Preset,
        learned: Sequence[Path | str] = (),
        log: Callable[[str], None] | None = None,
        max_duration: float = 60.0,
        max_command_age: float = MAX_COMMAND_AGE,
        max_joint_state_age: float = MAX_JOINT_STATE_AGE,
    ):
        self.scene = scene
        self.speed, self.rot_speed = scene.teleop.speed, scene.teleop.rot_speed
        self.max_command_age, self.max_joint_state_age = max_command_age, max_joint_state_age
        intents = trial_intents(scene, learned, inference=inference)
        self.assistant = trial_assistant(scene, method, intents, inference)
        self.ticks_per_inference = inference_ticks(scene)
        self.meta = trial_meta(
            participant,
            task,
            method,
            phase,
            "human",
            self.assistant,
            inference,
            max_duration,
            point=scene.point,
        )
        self.model = ArmSimulation(scene)
        self.log = log or (lambda text: None)
        self.rows: list[dict] = []
        self.tick_index = 0
        self.fault: str | None = None
        self._state: np.ndarray | None = None
        self._last_tick: tuple[float, float] | None = None  # (now, elapsed in the step)

    def close(self) -> None:
        """Free the kinematic model (pybullet)."""
        self.model.close()

    def _measure(self, q: np.ndarray) -> np.ndarray:
        previous = self.scene.start_state if self._state is None else self._state
        return self.model.reset(previous, q=q)

    def step(
        self,
        now: float,
        q: np.ndarray | None,
        q_time: float | None,
        action: np.ndarray | None,
        action_time: float | None,
        *,
        joint_fault: str | None = None,
        user_fault: str | None = None,
    ) -> Tick:
        """One control tick at monotonic time ``now`` (s).

        ``q`` and ``action`` are the newest valid joint angles and user action and
        ``q_time``, ``action_time`` when they arrived (None: never); ``joint_fault`` and
        ``user_fault`` name a newer message that was refused (``joint-state-invalid``,
        ``user-invalid``).
        """
        fault = joint_fault
        if q is None or q_time is None or now - q_time > self.max_joint_state_age:
            fault = fault or "joint-state-stale"
        if fault is None and (
            user_fault
            or action is None
            or action_time is None
            or now - action_time > self.max_command_age
        ):
            fault = user_fault or "user-silent"
        self._report(fault)
        t = self.tick_index * self.scene.teleop.dt
        if q is None:  # no arm yet: nothing to assist, nothing logged
            text = state_json(t, 1.0, None, [], fault)
            return Tick(self._still(), text, {}, fault)
        state = self._measure(q)
        if self._state is None:
            self.assistant.reset(state)
        self._state = state
        if self.tick_index > 0 and self.tick_index % self.ticks_per_inference == 0:
            self.assistant.update(state)
        user = np.zeros(4) if fault or action is None else action
        elapsed = (self.tick_index % self.ticks_per_inference) * self.scene.teleop.dt
        self._last_tick = (now, elapsed)
        # Under a fault the robot's share stops: alpha 1 applied, so the evidence sees none.
        alpha = 1.0 if fault else self.assistant.alpha
        if fault is not None and fault.startswith("joint-state"):
            command = self._still()  # where the arm is, is unknown: no motion at all
        else:
            command = self._command(state, user, elapsed, alpha, record=True)
        row = self._row(t, state, q, user, alpha)
        self.rows.append(row)
        self.tick_index += 1
        text = state_json(t, alpha, self.assistant.latest, state, fault, user)
        return Tick(command, text, row, fault)

    def respond(
        self, now: float, q: np.ndarray | None, q_time: float | None, action: np.ndarray
    ) -> Command | None:
        """The command for a user ``action`` arriving at ``now`` between two ticks.

        The same blend as the next tick's, from the newest joint state ``q`` (arrived at
        ``q_time``) and the last inference, so that a command acts at once; nothing is
        recorded or counted as evidence (the next tick does that). None while the last
        tick had a fault, before the first tick, or with no fresh joint state: then the
        next tick decides.
        """
        if self._last_tick is None or self.fault is not None:
            return None
        if q is None or q_time is None or now - q_time > self.max_joint_state_age:
            return None
        tick_time, elapsed = self._last_tick
        state = self._measure(q)
        elapsed += min(max(now - tick_time, 0.0), self.scene.teleop.dt)
        return self._command(state, action, elapsed, self.assistant.alpha, record=False)

    def _command(self, state, user, elapsed, alpha, *, record: bool) -> Command:
        blended = self.assistant.act(state, user, elapsed, alpha=alpha, record=record)
        if not np.any(blended):
            return self._still()
        return Command(self.model.joint_velocities(blended), blended)

    def _still(self) -> Command:
        return Command(np.zeros(len(self.model.q)), np.zeros(4))

    def _row(self, t, state, q, user, alpha) -> dict:
        x, y, z, rot = state.tolist()
        row = {"t": round(t, 6), "x": x, "y": y, "z": z, "rot": rot}
        row["keys"] = action_keys(user, self.speed, self.rot_speed)
        row["alpha"] = alpha
        row.update({f"q{i + 1}": float(v) for i, v in enumerate(q)})
        row.update({f"beta:{name}": v for name, v in self.assistant.beta.items()})
        row.update({f"belief:{name}": v for name, v in self.assistant.belief.items()})
        return row

    def _report(self, fault: str | None) -> None:
        if fault != self.fault:
            if fault is None:
                self.log(f"{self.fault} over: assisting again")
            else:
                self.log(f"{fault}: {FAULTS[fault]}")
            self.fault = fault

    def result(self) -> TrialResult:
        """The trial so far as casa-trial/1 metadata and rows."""
        return TrialResult(meta=dict(self.meta), frame=pd.DataFrame(self.rows))
