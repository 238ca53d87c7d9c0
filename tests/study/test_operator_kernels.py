"""The simulated operator's compiled geometry computes what its numpy formulas compute.

``casa_core.study._operator_kernels`` replaces, in the operator's tick, a window's
``np.linalg.norm(..., axis=1).argmin()`` and ``np.cumsum(...).searchsorted(...)``. Each
kernel is held to the numpy expression it replaces, bit for bit, on random inputs with
ties and with distances equal to a partial sum (where ``<`` and ``<=`` part). The
operators are then held, tick by tick, to a copy written with the numpy formulas (the
expressions the kernels replace): both see the same states (the reference path, off it,
stopped, past its end), draw from equally seeded streams and must hold the same keys on
every tick.
"""

from __future__ import annotations

import numpy as np
import pytest

from casa_core.assist.tasks import intended_trajectory
from casa_core.robot.keys import AXIS_KEYS
from casa_core.scene import load_scene
from casa_core.study import _operator_kernels as kernels
from casa_core.study import participants as part
from casa_core.vocabulary import TASKS

PARAMS = part.ParticipantParams(0.35, 0.01, 0.015, 0.3, 0.8, 0.2, 2)


def test_nearest_row_is_the_argmin_of_the_row_norms():
    rng = np.random.default_rng(0)
    for _ in range(500):
        path = rng.normal(0.0, 0.05, size=(int(rng.integers(1, 60)), 4))
        path[rng.integers(len(path), size=len(path) // 3)] = path[0]  # equal rows: ties
        point = path[0] + rng.normal(0.0, 0.01, size=4) * rng.integers(2)
        start = int(rng.integers(len(path)))
        stop = start + int(rng.integers(1, 50))
        expected = int(np.linalg.norm(path[start:stop] - point, axis=1).argmin())
        assert kernels.nearest_row(path, start, stop, point) == expected


def test_first_reaching_is_the_cumulative_sums_searchsorted():
    rng = np.random.default_rng(1)
    for _ in range(500):
        steps = rng.uniform(0.0, 0.01, size=int(rng.integers(1, 80)))
        steps[rng.integers(len(steps), size=len(steps) // 4)] = 0.0
        start = int(rng.integers(len(steps)))
        sums = np.cumsum(steps[start:])
        # A distance between sums, equal to one, and beyond the last.
        for distance in (rng.uniform(0, 0.3), sums[rng.integers(len(sums))], sums[-1] + 1):
            expected = int(sums.searchsorted(distance))
            assert kernels.first_reaching(steps, start, distance) == expected


class NumpyLookahead(part.SimulatedParticipant):
    """The lookahead operator with its tick written in the numpy formulas."""

    def _track(self, perceived):
        here = perceived.copy()
        here[3] *= part.ROT_TO_METRES
        window = self._scaled[self._progress : self._progress + part.WINDOW]
        self._progress += int(np.linalg.norm(window - here, axis=1).argmin())
        path = np.cumsum(self._steps[self._progress :])
        return self._progress + int(path.searchsorted(part.LOOKAHEAD))

    def _choose_keys(self, error, t):
        magnitude = np.abs(error) * part._SCALE
        held_axes = {
            axis
            for axis, (plus, minus) in enumerate(AXIS_KEYS)
            if plus in self._held or minus in self._held
        }
        thresholds = np.array(
            [self.params.deadband / 3 if a in held_axes else self.params.deadband for a in range(4)]
        )
        wanted = [a for a in np.argsort(-magnitude) if magnitude[a] > thresholds[a]]
        # The presses (unchanged by the fast path): a draw for each new key, then its miss.
        pressed = []
        for axis in wanted[: self.params.max_keys]:
            key = AXIS_KEYS[axis][0 if error[axis] > 0 else 1]
            missed = key not in self._held and self.rng.random() < self.params.wrong_key
            pressed.append(self._wrong_key(key) if missed else key)
        return frozenset(pressed)


class NumpyPredictive(part.PredictiveParticipant):
    """The predictive operator with its path geometry written in the numpy formulas."""

    _track = NumpyLookahead._track


def _states(reference, rng):
    """Arm states along the path with drift, a stop, a detour and a run past the end."""
    path = reference[:, 1:5]
    ticks = np.linspace(0, len(path) - 1, 400).astype(int)
    states = path[ticks] + np.cumsum(rng.normal(0.0, 0.002, size=(400, 4)), axis=0)
    states[150:200] = states[150]  # stopped
    states[220:260, :3] += 0.05  # pulled off the path
    beyond = path[-1] + np.outer(np.linspace(0, 0.1, 60), [1.0, -0.5, 0.2, 0.3])
    return np.concatenate([states, beyond])


@pytest.mark.parametrize(
    ("fast", "plain"),
    [(part.PredictiveParticipant, NumpyPredictive), (part.SimulatedParticipant, NumpyLookahead)],
)
@pytest.mark.parametrize("task", TASKS)
def test_the_operator_holds_the_keys_of_its_numpy_formulas_on_every_tick(task, fast, plain):
    reference = intended_trajectory(task, load_scene())
    states = _states(reference, np.random.default_rng(3))
    operators = [cls(PARAMS, reference, rng=np.random.default_rng(4)) for cls in (fast, plain)]
    pressed = 0
    for tick, state in enumerate(states):
        fast, plain = (operator.keys(tick * 0.05, state) for operator in operators)
        assert fast == plain, tick
        pressed += bool(fast)
    assert pressed > 50  # the comparison covers ticks with keys held
    assert operators[0].rng.random() == operators[1].rng.random()  # the same draws
