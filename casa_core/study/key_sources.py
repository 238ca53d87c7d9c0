"""Key sources: whatever holds the keys of a trial, tick by tick.

The closed loop (:func:`casa_core.study.closed_loop.run_trial`) asks a key source
each tick which keys are held. Anything with ``keys(t, state) -> iterable of key
names`` and a ``done`` attribute is one: :class:`ScriptedKeys` and
:class:`WaypointKeys` here (tests and benchmarks), the simulated participants of
:class:`casa_core.study.participants.SimulatedParticipant` and the window's keyboard
(:class:`casa_core.robot.teleop.KeyboardKeys`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import KW_ONLY, dataclass, field
from typing import Protocol

import numpy as np

from casa_core.robot.keys import AXIS_KEYS, check_keys


class KeySource(Protocol):
    """Anything that yields the held keys each tick given the observed state."""

    done: bool

    def keys(self, t: float, state: np.ndarray) -> Iterable[str]:
        """Keys held during the tick starting at ``t`` seconds, given ``[x, y, z, rot]``."""
        ...


@dataclass
class ScriptedKeys:
    """A fixed sequence of held keys: ``[(seconds, keys), ...]``, then done.

    Parameters
    ----------
    script : sequence of (float, iterable of str)
        Each entry holds ``keys`` for ``seconds`` (rounded to whole ticks).
    dt : float
        Control tick, s.

    Examples
    --------
    >>> source = ScriptedKeys([(0.1, ["x+"])])
    >>> [sorted(source.keys(t, None)) for t in (0.0, 0.05, 0.1)], source.done
    ([['x+'], ['x+'], []], True)
    """

    script: Sequence[tuple[float, Iterable[str]]]
    dt: float = 0.05
    done: bool = field(default=False, init=False)

    def __post_init__(self):
        self._ticks: list[frozenset[str]] = []
        for index, (seconds, keys) in enumerate(self.script):
            if not seconds >= 0:
                raise ValueError(f"script entry {index}: seconds must be >= 0, got {seconds!r}")
            held = check_keys(keys)
            self._ticks += [held] * int(round(seconds / self.dt))
        self._next = 0

    def keys(self, t: float, state) -> frozenset[str]:
        if self._next >= len(self._ticks):
            self.done = True
            return frozenset()
        held = self._ticks[self._next]
        self._next += 1
        return held


@dataclass
class WaypointKeys:
    """A scripted expert: holds the keys toward each waypoint in turn, then is done.

    Holds the key of every axis of ``[x, y, z, rot]`` whose error exceeds the
    tolerance; moves to the next waypoint when all are within it. Deterministic,
    for tests and benchmarks; the study's participants are in
    :mod:`casa_core.study.participants`.

    Parameters
    ----------
    waypoints : array_like, shape (n, 4)
        The ``[x, y, z, rot]`` to reach, in order.
    tolerance, rot_tolerance : float
        Position (m) and rotation (rad) error within which a waypoint counts as reached.

    Examples
    --------
    >>> expert = WaypointKeys([[0.1, 0.0, 0.0, 0.0]])
    >>> sorted(expert.keys(0.0, [0.0, 0.0, 0.0, 0.0]))
    ['x+']
    >>> sorted(expert.keys(0.05, [0.1, 0.0, 0.0, 0.0])), expert.done
    ([], True)
    """

    waypoints: np.ndarray
    _: KW_ONLY
    tolerance: float = 0.005
    rot_tolerance: float = 0.05
    done: bool = field(default=False, init=False)

    def __post_init__(self):
        self.waypoints = np.asarray(self.waypoints, dtype=float)
        if self.waypoints.ndim != 2 or self.waypoints.shape[1] != 4:
            raise ValueError(f"waypoints must have shape (n, 4), got {self.waypoints.shape}")
        self._index = 0

    def keys(self, t: float, state) -> frozenset[str]:
        tolerance = [self.tolerance] * 3 + [self.rot_tolerance]
        while self._index < len(self.waypoints):
            # On Python floats: the same differences and comparisons, without numpy scalars.
            error = (self.waypoints[self._index] - np.asarray(state, dtype=float)).tolist()
            held = frozenset(
                plus if e > 0 else minus
                for e, tol, (plus, minus) in zip(error, tolerance, AXIS_KEYS, strict=True)
                if abs(e) > tol
            )
            if held:
                return held
            self._index += 1
        self.done = True
        return frozenset()
