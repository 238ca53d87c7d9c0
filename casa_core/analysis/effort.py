"""The user's effort, per trial, for keys and for a continuous device alike.

A keyboard trial holds keys ``K_i`` at tick ``i``; a gamepad or SpaceMouse trial commands
a velocity ``u_i = [vx, vy, vz, vrot]`` (the log's command columns, zero inside the
device's deadzone). Both are read as *held directions*: the keys themselves, or for a
device the key that moves each axis the way its command does (``x+`` while ``vx > 0``).
A direction is a press where it starts, so the paper's effort is defined for both:

- **effort**: press events, a direction held at tick ``i`` and not at ``i - 1`` (every
  direction held at the first tick counts once; :func:`presses`). For keys these are key
  presses; for a device, the times an axis leaves its deadzone (or reverses).
- **effort_ticks**: the original's counter, ``sum_i |K_i|``, held directions summed over
  ticks (:func:`held_ticks`).

Two measures of the command itself, the same for both kinds of input
(``dt_i = t_{i+1} - t_i``, the tick during which ``u_i`` drove; the last row drives
nothing):

- **command_time** (s): ``sum_{i<n-1} dt_i [u_i != 0]``, the time with a command above
  the deadzone (for keys: with a key held; :func:`command_time`);
- **command_integral** (s): ``sum_{i<n-1} dt_i sum_a |u_{i,a}| / s_a``, the command's
  magnitude in full-speed seconds, ``s_a`` each axis's key speed (0.05 m/s, 0.5 rad/s;
  :func:`command_integral`). A held key adds 1 per second, so for keys without opposite
  pairs held it is ``dt * effort_ticks`` less the last row's keys; a stick half deflected
  adds 0.5 per second where it counts as held all the same.

Examples
--------
>>> frame = pd.DataFrame({"t": [0.0, 0.05, 0.1], "keys": ["", "", ""],
...                       "command_x": [0.025, 0.05, 0.0], "command_y": 0.0,
...                       "command_z": 0.0, "command_rot": 0.0})
>>> [sorted(held) for held in held_directions(frame)]
[['x+'], ['x+'], []]
>>> round(command_integral(frame["t"], commanded(frame), speed=0.05, rot_speed=0.5), 12)
0.075
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from casa_core.defaults import ROT_SPEED, SPEED
from casa_core.io.contract import COMMAND_COLUMNS
from casa_core.robot.keys import AXIS_KEYS, keys_to_action, parse_keys


def has_command(frame: pd.DataFrame) -> bool:
    """Whether the log is a continuous device's: it has the command columns."""
    return all(column in frame.columns for column in COMMAND_COLUMNS)


def held_keys(keys: Sequence[str]) -> list[frozenset[str]]:
    """The set of keys held at each tick, from the log's space-separated ``keys`` cells.

    Examples
    --------
    >>> [sorted(held) for held in held_keys(["x+ rot-", ""])]
    [['rot-', 'x+'], []]
    """
    return [frozenset(cell.split()) for cell in keys]


def held_directions(frame: pd.DataFrame) -> list[frozenset[str]]:
    """The directions held at each tick: the keys, or the signs of a device's command."""
    if not has_command(frame):
        return held_keys(frame["keys"])
    signs = np.sign(frame[list(COMMAND_COLUMNS)].to_numpy(dtype=float)).tolist()
    return [
        frozenset(_direction(s, keys) for s, keys in zip(row, AXIS_KEYS, strict=True) if s)
        for row in signs
    ]


def _direction(sign: float, keys: tuple[str, str]) -> str:
    """The key of an axis whose command has ``sign`` (non-zero)."""
    return keys[0] if sign > 0 else keys[1]


def presses(held: Sequence[frozenset[str]]) -> int:
    """Press events: a direction not held at the previous tick and held at this one.

    Examples
    --------
    >>> presses(held_keys(["", "x+", "x+", "", "x+ y+", "y+"]))
    3
    """
    previous: frozenset[str] = frozenset()
    count = 0
    for now in held:
        count += len(now - previous)
        previous = now
    return count


def held_ticks(held: Sequence[frozenset[str]]) -> int:
    """The original implementation's effort counter: directions held, summed over ticks.

    Examples
    --------
    >>> held_ticks(held_keys(["", "x+", "x+", "", "x+ y+", "y+"]))
    5
    """
    return sum(len(now) for now in held)


def key_presses(keys: Sequence[str]) -> int:
    """:func:`presses` of the log's ``keys`` cells (the paper's effort)."""
    return presses(held_keys(keys))


def key_ticks(keys: Sequence[str]) -> int:
    """:func:`held_ticks` of the log's ``keys`` cells."""
    return held_ticks(held_keys(keys))


def commanded(frame: pd.DataFrame, *, speed: float = SPEED, rot_speed: float = ROT_SPEED):
    """The user's command ``u_i`` per row, shape (n, 4): the device's, or the keys' velocity
    (:func:`casa_core.robot.keys.keys_to_action` at ``speed`` and ``rot_speed``)."""
    if has_command(frame):
        return frame[list(COMMAND_COLUMNS)].to_numpy(dtype=float)
    cells = frame["keys"].fillna("").astype(str)
    by_cell = {cell: keys_to_action(parse_keys(cell), speed, rot_speed) for cell in set(cells)}
    return np.array([by_cell[cell] for cell in cells]).reshape(len(cells), 4)


def command_time(t, commands: np.ndarray) -> float:
    """Seconds with a command above the deadzone (module docstring).

    Examples
    --------
    >>> command_time([0.0, 0.05, 0.1], np.array([[0.05, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0]]))
    0.05
    """
    steps = np.diff(np.asarray(t, dtype=float))
    active = np.asarray(commands)[:-1].any(axis=1)
    return float(np.sum(steps[active]))


def command_integral(t, commands: np.ndarray, *, speed: float, rot_speed: float) -> float:
    """The command's magnitude over the trial in full-speed seconds (module docstring)."""
    steps = np.diff(np.asarray(t, dtype=float))
    scale = np.array([speed, speed, speed, rot_speed], dtype=float)
    per_tick = (np.abs(np.asarray(commands, dtype=float)[:-1]) / scale).sum(axis=1)
    return float(np.sum(steps * per_tick))
