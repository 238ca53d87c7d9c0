"""Command sources: a continuous device's commanded velocity, tick by tick.

A gamepad or a SpaceMouse does not hold keys: it commands a velocity
``[vx, vy, vz, vrot]`` (m/s, rad/s). Anything with ``command(t, state) -> array (4,)``,
a ``done`` attribute and an ``input`` (the device's name in
:data:`casa_core.vocabulary.CONTINUOUS_INPUTS`) is a command source; the closed loop
(:func:`casa_core.study.closed_loop.run_trial`) then logs the command in the
casa-trial/1 command columns and gives it to inference as the user's action, where a
key source's keys give :func:`casa_core.robot.keys.keys_to_action`.
:class:`DeviceCommands` reads a device of :mod:`casa_core.robot.devices`;
:class:`ScriptedCommands` plays a fixed script (tests).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import KW_ONLY, dataclass, field
from typing import Protocol, TypeGuard

import numpy as np

from casa_core.io.contract import COMMAND_BOUND
from casa_core.vocabulary import CONTINUOUS_INPUTS


class CommandSource(Protocol):
    """Anything that commands a velocity each tick given the observed state."""

    input: str
    done: bool

    def command(self, t: float, state: np.ndarray) -> np.ndarray:
        """``[vx, vy, vz, vrot]`` during the tick starting at ``t`` s, given the state."""
        ...


def is_continuous(source) -> TypeGuard[CommandSource]:
    """Whether ``source`` commands a velocity (a command source) rather than keys.

    Examples
    --------
    >>> is_continuous(ScriptedCommands([])), is_continuous(object())
    (True, False)
    """
    return callable(getattr(source, "command", None))


def checked_command(command) -> np.ndarray:
    """``command`` as a float array of 4 finite values within the log's bound.

    Examples
    --------
    >>> checked_command([0.05, 0, 0, 0]).tolist()
    [0.05, 0.0, 0.0, 0.0]
    >>> checked_command([0.05, 0, 0])
    Traceback (most recent call last):
    ...
    ValueError: a command is [vx, vy, vz, vrot]: 4 finite numbers within +-10.0, got [0.05, 0, 0]
    """
    values = np.asarray(command, dtype=float)
    if (
        values.shape != (4,)
        or not np.isfinite(values).all()
        or np.abs(values).max() > COMMAND_BOUND
    ):
        raise ValueError(
            f"a command is [vx, vy, vz, vrot]: 4 finite numbers within +-{COMMAND_BOUND}, "
            f"got {command!r}"
        )
    return values


@dataclass
class ScriptedCommands:
    """A fixed sequence of commands: ``[(seconds, [vx, vy, vz, vrot]), ...]``, then done.

    Parameters
    ----------
    script : sequence of (float, sequence of 4 floats)
        Each entry commands its velocity for ``seconds`` (rounded to whole ticks).
    dt : float
        Control tick, s.
    input : str
        The device it stands for, one of :data:`~casa_core.vocabulary.CONTINUOUS_INPUTS`.

    Examples
    --------
    >>> source = ScriptedCommands([(0.1, [0.05, 0, 0, 0])])
    >>> [float(source.command(t, None)[0]) for t in (0.0, 0.05, 0.1)], source.done
    ([0.05, 0.05, 0.0], True)
    """

    script: Sequence[tuple[float, Sequence[float]]]
    dt: float = 0.05
    _: KW_ONLY
    input: str = "gamepad"
    done: bool = field(default=False, init=False)

    def __post_init__(self):
        if self.input not in CONTINUOUS_INPUTS:
            raise ValueError(f"input must be one of {', '.join(CONTINUOUS_INPUTS)}")
        self._ticks: list[np.ndarray] = []
        for index, (seconds, command) in enumerate(self.script):
            if not seconds >= 0:
                raise ValueError(f"script entry {index}: seconds must be >= 0, got {seconds!r}")
            self._ticks += [checked_command(command)] * int(round(seconds / self.dt))
        self._next = 0

    def command(self, t: float, state) -> np.ndarray:
        if self._next >= len(self._ticks):
            self.done = True
            return np.zeros(4)
        value = self._ticks[self._next]
        self._next += 1
        return value.copy()


class DeviceCommands:
    """The command of a device (:mod:`casa_core.robot.devices`) at the keys' speeds.

    Each tick reads the device once: its axes ``[x, y, z, rot]`` in [-1, 1] times
    ``[speed, speed, speed, rot_speed]``, so full deflection commands what a held key
    does. Its finish button ends the trial (``done``), its pause button pauses it
    (``done`` and ``paused``); a press made before the source was made (between trials)
    is read and dropped when it is made. A window's keyboard, when given, is read too for Enter
    and the pause key, so a session's keys work beside the device. A device lost
    (:class:`~casa_core.robot.devices.DeviceLost`: unplugged, or its trace ended) stops
    the arm: the command is zero from then on, ``lost`` says what happened, and the trial
    ends.

    Parameters
    ----------
    device : Device
        An open device (:func:`casa_core.robot.devices.open_device`).
    input : str
        Its kind, one of :data:`~casa_core.vocabulary.CONTINUOUS_INPUTS`.
    speed, rot_speed : float
        The scene's key speeds (m/s, rad/s).
    keyboard : KeyboardKeys, optional
        The window's keyboard, read for Enter and the pause key only.
    """

    def __init__(self, device, *, input: str, speed: float, rot_speed: float, keyboard=None):
        if input not in CONTINUOUS_INPUTS:
            raise ValueError(f"input must be one of {', '.join(CONTINUOUS_INPUTS)}")
        self.device, self.input, self.keyboard = device, input, keyboard
        self._scale = np.array([speed, speed, speed, rot_speed], dtype=float)
        self.done = self.paused = False
        self.lost: str | None = None
        self._read()  # buttons pressed before the trial started do not count

    @classmethod
    def in_scene(cls, device, scene, *, input: str, keyboard=None) -> DeviceCommands:
        """The device's commands at the key speeds of ``scene`` (its ``teleop``)."""
        teleop = scene.teleop
        return cls(
            device, input=input, speed=teleop.speed, rot_speed=teleop.rot_speed, keyboard=keyboard
        )

    def _read(self):
        """The device's reading, or None once it is lost (``lost`` says how)."""
        from casa_core.robot.devices import DeviceLost

        try:
            return self.device.read()
        except DeviceLost as error:
            self.lost, self.done = str(error), True
            return None

    def command(self, t: float, state) -> np.ndarray:
        if self.keyboard is not None:
            self.keyboard.keys(t, state)  # its arm keys are ignored: the device drives
            self.done |= self.keyboard.done
            self.paused |= self.keyboard.paused
        reading = None if self.done or self.lost else self._read()
        if reading is None:
            return np.zeros(4)
        if reading.pause or reading.finish:
            self.done, self.paused = True, bool(reading.pause)
        return np.asarray(reading.axes, dtype=float) * self._scale
