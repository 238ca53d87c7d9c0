"""Simulated participants: closed-loop keyboard operators.

A participant watches the end effector, follows the task's intended trajectory
(:func:`casa_core.assist.tasks.intended_trajectory`, the reference shown before each
task) and holds keys of the same 8-key interface a person uses. It is an
operator model, not a script: it sees the arm's state with a delay and with
noise, steers toward a point a little ahead on the path, holds a key while the
error along that axis exceeds a deadband, lapses now and then, and sometimes
presses a wrong key. When assistance pulls the arm off the path the error grows
and the participant presses against it, so assisting for the wrong intent costs
effort, as it does for a person.

Population parameters (fixed before any result was looked at; distributions in
``config/config.yaml`` under ``simulation.population``): ``reaction_time`` (s),
``perception_noise`` (m), ``deadband`` (m), ``lapse_rate`` (1/s) and ``lapse_duration``
(s), ``wrong_key`` (probability), ``max_keys``. The expert of the case study has a short
delay, little noise, no lapses and no wrong keys.

Two operator models share this machinery (config key ``simulation.operator``):
*lookahead* (:class:`SimulatedParticipant`) steers toward a point :data:`LOOKAHEAD` ahead
on the path; *predictive* (:class:`PredictiveParticipant`) acts on where the arm is
heading, with a lead time :data:`LEAD_TIME`, a velocity filter :data:`VELOCITY_FILTER` and
a refractory interval :data:`REFRACTORY`. What each model does, and the literature each
parameter comes from: docs/departures.md, "Simulated operators".
"""

from __future__ import annotations

from collections import deque
from dataclasses import asdict, dataclass

import numpy as np

from casa_core.fixed_order import dot, length
from casa_core.robot.keys import AXIS_KEYS
from casa_core.study import _operator_kernels as _kernels
from casa_core.study.path_geometry import unit_tangents
from casa_core.study.settings import LOGNORMAL_PARAMETERS, Population

# Rotation error is compared with position error at this many metres per radian.
ROT_TO_METRES = 0.1
LOOKAHEAD = 0.04  # m of path ahead that the participant steers toward
DONE_ROT_TOLERANCE = 0.15  # rad
#: The predictive operator's lead time constant T_L, s (docs/departures.md).
LEAD_TIME = 0.5
#: Time constant of the predictive operator's velocity estimate, s (docs/departures.md).
VELOCITY_FILTER = 1.0
#: Shortest interval from a change of the predictive operator's keys to its next press, s.
REFRACTORY = 0.25
_SCALE = np.array([1.0, 1.0, 1.0, ROT_TO_METRES])  # [x, y, z, rot] with rot in metres
_SCALE_FLOATS = tuple(_SCALE.tolist())


@dataclass(frozen=True)
class ParticipantParams:
    """One participant's operator parameters (units in the module docstring)."""

    reaction_time: float
    perception_noise: float
    deadband: float
    lapse_rate: float
    lapse_duration: float
    wrong_key: float
    max_keys: int

    def as_dict(self) -> dict:
        return asdict(self)


def draw_participants(
    n: int, population: Population, rng: np.random.Generator
) -> list[ParticipantParams]:
    """Draw ``n`` participants from the population of the study's settings.

    Each parameter is lognormal (:class:`~casa_core.study.settings.Lognormal`) except
    ``max_keys``, one of its ``values`` drawn with the probabilities ``p``.
    """
    drawn = []
    for _ in range(n):
        values: dict[str, float] = {}
        for name in LOGNORMAL_PARAMETERS:
            spec = getattr(population, name)
            values[name] = float(spec.median * np.exp(spec.sigma * rng.standard_normal()))
        values["wrong_key"] = min(values["wrong_key"], 0.5)
        keys = population.max_keys
        max_keys = int(rng.choice(keys.values, p=keys.p))
        drawn.append(ParticipantParams(**values, max_keys=max_keys))
    return drawn


class SimulatedParticipant:
    """A keyboard operator following a reference trajectory in closed loop.

    Parameters
    ----------
    params : ParticipantParams
    reference : ndarray, shape (n, 5)
        The intended trajectory ``[t, x, y, z, rot]``.
    rng : numpy.random.Generator
        The participant's own stream of randomness.
    tick : float
        Control period, s (0.05).
    """

    def __init__(
        self,
        params: ParticipantParams,
        reference,
        *,
        rng: np.random.Generator,
        tick: float = 0.05,
    ):
        self.params = params
        self.reference = np.asarray(reference, dtype=float)[:, 1:5]
        self.rng = rng
        self.tick = tick
        # The path with rotation in metres (ROT_TO_METRES), so that distances mix the two.
        self._scaled = self.reference * _SCALE
        # The path length of each step.
        self._steps = np.linalg.norm(np.diff(self._scaled, axis=0), axis=1)
        self._seen: deque[tuple[float, np.ndarray]] = deque()  # (t, state) not yet perceived
        self._perceived: np.ndarray | None = None
        self._noise = np.zeros(3)
        self._ar1: tuple[float, np.ndarray, float] | None = None
        self._progress = 0
        self._held: frozenset[str] = frozenset()
        self._lapse_until = -1.0
        self.done = False

    def keys(self, t: float, state) -> frozenset[str]:
        """The keys held during the tick starting at ``t``, given the arm's ``state``."""
        self._seen.append((t, np.asarray(state, dtype=float).copy()))
        while self._seen and self._seen[0][0] <= t - self.params.reaction_time + 1e-9:
            self._perceived = self._seen.popleft()[1]
        if self._perceived is None or self.done:
            return frozenset()
        if t < self._lapse_until:
            return self._held
        if self.rng.random() < self.params.lapse_rate * self.tick:
            self._lapse_until = t + self.params.lapse_duration * self.rng.uniform(0.5, 1.5)
            return self._held
        perceived = self._perceive()
        error = self._error(perceived, t)
        if error is None:
            self.done = True
            self._held = frozenset()
            return self._held
        self._held = self._choose_keys(error)
        return self._held

    def _perceive(self) -> np.ndarray:
        # AR(1) position noise with a 0.5 s time constant, doubled along x (depth).
        if self._ar1 is None:  # (decay, scale, innovation scale), once per participant
            decay = np.exp(-self.tick / 0.5)
            scale = self.params.perception_noise * np.array([2.0, 1.0, 1.0])
            self._ar1 = (decay, scale, np.sqrt(1 - decay**2))
        decay, scale, root = self._ar1
        innovation = self.rng.standard_normal(3) * scale * root
        self._noise = decay * self._noise + innovation
        assert self._perceived is not None  # keys() returns before perceiving anything
        perceived = self._perceived.copy()
        perceived[:3] += self._noise
        return perceived

    def _error(self, perceived: np.ndarray, t: float) -> np.ndarray | None:
        """Error to the steering point ahead on the path; None once the task is done."""
        ahead = self._track(perceived)
        if self._arrived(perceived, ahead):
            return None
        return self.reference[min(ahead, len(self.reference) - 1)] - perceived

    def _track(self, perceived: np.ndarray) -> int:
        """Advance the progress along the path to ``perceived``; the steering point's index."""
        # The nearest of the next 40 path points, then LOOKAHEAD of path further on.
        progress, ahead = _kernels.track(
            self._scaled, self._steps, self._progress, perceived, 40, LOOKAHEAD, ROT_TO_METRES
        )
        self._progress = int(progress)
        return int(ahead)

    def _arrived(self, perceived: np.ndarray, ahead: int) -> bool:
        """Whether the steering point is the path's end and the arm is seen there."""
        final = self.reference[-1]
        return bool(
            ahead >= len(self.reference) - 1
            and length(perceived[:3] - final[:3]) < self.params.deadband
            and abs(perceived[3] - final[3]) < DONE_ROT_TOLERANCE
        )

    def _choose_keys(self, error: np.ndarray) -> frozenset[str]:
        # Python floats: the same products as numpy's on 4 numbers, without its overhead.
        error = error.tolist()
        magnitude = [abs(e) * s for e, s in zip(error, _SCALE_FLOATS, strict=True)]
        # Hysteresis: a held key stays down until the error falls to a third of the deadband.
        deadband, held = self.params.deadband, self._held
        thresholds = [deadband / 3 if held.intersection(pair) else deadband for pair in AXIS_KEYS]
        # Largest first, ties in axis order (as np.argsort sorts 4 numbers).
        order = sorted(range(4), key=lambda axis: -magnitude[axis])
        wanted = [axis for axis in order if magnitude[axis] > thresholds[axis]]
        chosen = set()
        for axis in wanted[: self.params.max_keys]:
            plus, minus = AXIS_KEYS[axis]
            key = plus if error[axis] > 0 else minus
            if key not in self._held and self.rng.random() < self.params.wrong_key:
                key = self._wrong_key(key)
            chosen.add(key)
        return frozenset(chosen)

    def _wrong_key(self, key: str) -> str:
        others = [k for pair in AXIS_KEYS for k in pair if k != key]
        return others[self.rng.integers(len(others))]


class PredictiveParticipant(SimulatedParticipant):
    """An operator who acts on where the arm is heading (module docstring, *predictive*).

    Perception, lapses, wrong keys and the end of the task are those of
    :class:`SimulatedParticipant`; only the error the keys answer differs. The
    operator filters the perceived positions into a velocity, predicts the arm
    :data:`LEAD_TIME` plus its own reaction time ahead and presses only when that
    prediction leaves the path, or falls behind the point of the reference that far
    ahead, by more than the deadband, and presses no sooner than :data:`REFRACTORY` after its
    last change of keys.
    """

    def __init__(self, params: ParticipantParams, reference, *, rng, tick: float = 0.05):
        super().__init__(params, reference, rng=rng, tick=tick)
        self._times = np.asarray(reference, dtype=float)[:, 0]
        self._arc = np.concatenate([[0.0], np.cumsum(self._steps)])
        self._tangents = unit_tangents(self._scaled)
        self._velocity = np.zeros(4)
        self._last: tuple[float, np.ndarray] | None = None
        self._pushing = False
        self._now = 0.0
        self._changed_at = -np.inf

    def _choose_keys(self, error: np.ndarray) -> frozenset[str]:
        chosen = super()._choose_keys(error)
        if chosen == self._held:
            return chosen
        # A press waits out the refractory interval of the last change; a release
        # never waits, and starts the interval like any other response.
        if not chosen < self._held and self._now - self._changed_at < REFRACTORY - 1e-9:
            return self._held
        self._changed_at = self._now
        return chosen

    @property
    def horizon(self) -> float:
        """How far ahead of its (delayed) perception the operator predicts, s."""
        return self.params.reaction_time + LEAD_TIME

    def _error(self, perceived: np.ndarray, t: float) -> np.ndarray | None:
        self._now = t
        ahead = self._track(perceived)
        self._estimate_velocity(perceived, t)
        if self._arrived(perceived, ahead):
            return None
        horizon = self.horizon
        start = self._progress
        last = len(self._scaled) - 1
        # The predicted position's nearest path point, searched ahead of the progress.
        stop = start + int(horizon / self.tick) + 40
        here, nearest, offset = _kernels.predicted_offset(
            self._scaled, _SCALE, perceived, self._velocity, horizon, start, stop
        )
        tangent = self._tangents[nearest]
        along = dot(offset, tangent)
        wanted = min(int(self._times.searchsorted(self._times[start] + horizon)), last)
        behind = self._arc[wanted] - (self._arc[nearest] + along)
        threshold = self.params.deadband
        if wanted == last and abs(tangent[3]) > 0.5:
            # Ending on a turn: done only within DONE_ROT_TOLERANCE of the end's angle.
            threshold = min(threshold, DONE_ROT_TOLERANCE * ROT_TO_METRES)
        threshold = threshold / 3 if self._pushing else threshold
        self._pushing = bool(behind > threshold)
        # Back to the path across it; when pushing, along it too.
        correction = _kernels.correction(offset, tangent, along, behind, self._pushing)
        if not self._pushing and wanted == last:
            # Past the end now (not just predicted to arrive): back to the end.
            beyond = dot(here - self._scaled[last], self._tangents[last])
            if beyond > self.params.deadband:
                correction -= beyond * self._tangents[last]
        return correction / _SCALE

    def _estimate_velocity(self, perceived: np.ndarray, t: float) -> None:
        # First-order low-pass of the perceived displacement per second (VELOCITY_FILTER).
        if self._last is not None and t > self._last[0]:
            elapsed = t - self._last[0]
            raw = (perceived - self._last[1]) / elapsed
            self._velocity += (1 - np.exp(-elapsed / VELOCITY_FILTER)) * (raw - self._velocity)
        self._last = (t, perceived.copy())


#: The operator models, by the name of config key ``simulation.operator``.
OPERATORS = {"lookahead": SimulatedParticipant, "predictive": PredictiveParticipant}


def make_participant(
    params: ParticipantParams,
    reference,
    *,
    rng: np.random.Generator,
    tick: float = 0.05,
    operator: str,
) -> SimulatedParticipant:
    """The participant of operator model ``operator`` (a key of :data:`OPERATORS`).

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> from casa_core.assist.tasks import intended_trajectory
    >>> params = ParticipantParams(0.35, 0.01, 0.015, 0.03, 0.8, 0.02, 2)
    >>> reference = intended_trajectory("known_goal", load_scene())
    >>> rng = np.random.default_rng(0)
    >>> type(make_participant(params, reference, rng=rng, operator="predictive")).__name__
    'PredictiveParticipant'
    >>> make_participant(params, reference, rng=rng, operator="lead")
    Traceback (most recent call last):
    ...
    ValueError: unknown operator model 'lead'; expected one of lookahead, predictive
    """
    if operator not in OPERATORS:
        raise ValueError(
            f"unknown operator model {operator!r}; expected one of {', '.join(OPERATORS)}"
        )
    return OPERATORS[operator](params, reference, rng=rng, tick=tick)
