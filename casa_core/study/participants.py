"""Simulated participants: closed-loop keyboard operators.

A participant watches the end effector, follows the task's intended trajectory
(:func:`casa_core.assist.tasks.intended_trajectory`, the reference shown before each
task) and holds keys of the same 8-key interface a person uses. It is an
operator model, not a script: it sees the arm's state with a delay and with
noise, steers toward a point a little ahead on the path, holds a key while the
error along that axis exceeds a deadband, lapses now and then, and sometimes
presses a wrong key. When assistance pulls the arm off the path the error grows
and the participant presses against it, so assisting for the wrong intent costs
effort, as it does for a person. Once it sees itself at the path's end it is ``done``
and lets go; where the trial goes on (a scene's fixed ``trial_length``) it waits there,
watching, and steers back if the arm is seen to leave.

Population parameters (fixed before any result was looked at; distributions in
``config/config.yaml`` under ``simulation.population``): ``reaction_time`` (s),
``perception_noise`` (m), ``deadband`` (m), ``lapse_rate`` (1/s) and ``lapse_duration``
(s), ``wrong_key`` (probability), ``max_keys``; the predictive operator's intermittent
control, ``bout``, ``pause`` and ``planning`` (s), which the config may set and the
default population does not (:mod:`casa_core.study.operator_params`). The expert of the
case study has a short delay, little noise, no lapses and no wrong keys.

Two operator models share this machinery (config key ``simulation.operator``):
*lookahead* (:class:`SimulatedParticipant`) steers toward a point :data:`LOOKAHEAD` ahead
on the path; *predictive* (:class:`PredictiveParticipant`) knows its own keys, estimates
the arm from them and from what it sees (:mod:`casa_core.study.arm_estimate`) and acts on
where the arm is heading, with a lead time :data:`LEAD_TIME`, the estimate's period
:data:`ESTIMATE_PERIOD`, a refractory interval :data:`REFRACTORY` and bouts of keys at most
:data:`BOUT` long. What each model does, and the literature each parameter comes from:
docs/departures.md, "Simulated operators".
"""

from __future__ import annotations

from collections import deque

import numpy as np

from casa_core.defaults import ROT_SPEED, SPEED, TICK
from casa_core.fixed_order import dot, length
from casa_core.robot.keys import AXIS_KEYS, keys_to_action
from casa_core.study import _operator_kernels as _kernels
from casa_core.study.arm_estimate import ArmEstimate
from casa_core.study.operator_params import BOUT, ParticipantParams, draw_participants

__all__ = ["BOUT", "OPERATORS", "ParticipantParams", "PredictiveParticipant"]
__all__ += ["SimulatedParticipant", "draw_participants", "make_participant"]

# Rotation error is compared with position error at this many metres per radian.
ROT_TO_METRES = 0.1
#: Time constant of the perception noise's AR(1) variation, s.
NOISE_TIME = 0.5
#: The perception noise per axis x, y, z relative to ``perception_noise``: twice in depth (x).
DEPTH_NOISE = np.array([2.0, 1.0, 1.0])
LOOKAHEAD = 0.04  # m of path ahead that the participant steers toward
#: How many path points ahead of its progress the participant looks for the nearest.
WINDOW = 40
DONE_ROT_TOLERANCE = 0.15  # rad
#: A held key goes up at a third of the deadband (hysteresis); by the same ratio, an
#: operator waiting at the path's end steers again only when it sees the arm three times
#: as far from the end as arriving took (three deadbands, three rotation tolerances).
HYSTERESIS = 3.0
#: The predictive operator's lead time constant T_L, s (docs/departures.md).
LEAD_TIME = 0.5
#: Natural period of the predictive operator's estimate of the arm's drift, s
#: (:class:`~casa_core.study.arm_estimate.ArmEstimate`, docs/departures.md).
ESTIMATE_PERIOD = 1.0
#: Shortest interval from a change of the predictive operator's keys to its next press, s.
REFRACTORY = 0.25
_SCALE = np.array([1.0, 1.0, 1.0, ROT_TO_METRES])  # [x, y, z, rot] with rot in metres
_SCALE_FLOATS = tuple(_SCALE.tolist())


class SimulatedParticipant:
    """A keyboard operator following a reference trajectory in closed loop.

    Parameters
    ----------
    params : ParticipantParams
    reference : ndarray, shape (n, 5)
        The intended trajectory ``[t, x, y, z, rot]``.
    rng : numpy.random.Generator
        The participant's own stream of randomness.
    tick : float, default TICK
        Control period, s (:data:`casa_core.defaults.TICK`).
    """

    def __init__(
        self,
        params: ParticipantParams,
        reference,
        *,
        rng: np.random.Generator,
        tick: float = TICK,
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
        self._perceived_at = 0.0  # when the perceived state was the arm's
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
            self._perceived_at, self._perceived = self._seen.popleft()
        if self._perceived is None:
            return frozenset()
        if t < self._lapse_until:
            return self._held
        if self.rng.random() < self.params.lapse_rate * self.tick:
            self._lapse_until = t + self.params.lapse_duration * self.rng.uniform(0.5, 1.5)
            return self._held
        perceived = self._perceive()
        error = self._error(perceived, t)
        # Done while it judges itself arrived: it lets go and watches, and steers again
        # if the arm is seen to leave (a trial of fixed length goes on after arrival).
        self.done = error is None
        self._held = frozenset() if error is None else self._choose_keys(error, t)
        return self._held

    def _perceive(self) -> np.ndarray:
        # AR(1) position noise with time constant NOISE_TIME, doubled along x (depth).
        if self._ar1 is None:  # (decay, scale, innovation scale), once per participant
            decay = np.exp(-self.tick / NOISE_TIME)
            scale = self.params.perception_noise * DEPTH_NOISE
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
        # The nearest of the next WINDOW path points, then LOOKAHEAD of path further on.
        progress, ahead = _kernels.track(
            self._scaled, self._steps, self._progress, perceived, WINDOW, LOOKAHEAD, ROT_TO_METRES
        )
        self._progress = int(progress)
        return int(ahead)

    def _arrived(self, perceived: np.ndarray, ahead: int) -> bool:
        """Whether the steering point is the path's end and the arm is seen there (within
        the deadband; once arrived, within :data:`HYSTERESIS` deadbands)."""
        final = self.reference[-1]
        scale = HYSTERESIS if self.done else 1.0
        return bool(
            ahead >= len(self.reference) - 1
            and length(perceived[:3] - final[:3]) < self.params.deadband * scale
            and abs(perceived[3] - final[3]) < DONE_ROT_TOLERANCE * scale
        )

    def _choose_keys(self, error: np.ndarray, t: float) -> frozenset[str]:
        """The keys that answer ``error`` during the tick starting at ``t``."""
        # Python floats: the same products as numpy's on 4 numbers, without its overhead.
        error = error.tolist()
        magnitude = [abs(e) * s for e, s in zip(error, _SCALE_FLOATS, strict=True)]
        # Hysteresis: a held key stays down until the error falls to a third of the deadband.
        deadband, held = self.params.deadband, self._held
        released = deadband / HYSTERESIS
        thresholds = [released if held.intersection(pair) else deadband for pair in AXIS_KEYS]
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

    Perception, lapses, wrong keys and the deadband's rule for choosing keys are those of
    :class:`SimulatedParticipant`; the error the keys answer and the judgement that the task
    is done differ. The operator knows the keys it holds (an efference copy) and estimates
    the arm from them and from what it sees (:class:`~casa_core.study.arm_estimate.ArmEstimate`:
    position, the drift the keys do not explain, the share of its keys' motion the arm
    makes). From the estimate it bridges its own delay to *now*, and asks what displacement
    its keys must still add, beyond the drift, to reach within :data:`LEAD_TIME` the point
    of the reference that far ahead of the arm; it holds a key on an axis while that exceeds
    the deadband, and presses no sooner than :data:`REFRACTORY` after its last change of
    keys. It steers in bouts (intermittent control, move and wait): after holding keys
    for ``bout`` seconds it lets go and watches for its reaction time, the soonest it can
    see what the arm does without its keys, and ``pause`` seconds more; whenever it lets
    go of all its keys it presses again no sooner than ``pause`` later. Its first press
    comes ``planning`` seconds after its first sight of the arm at the soonest. A robot
    that carries the arm along then shows as drift and saves it keys; one that pulls it
    away costs it keys. With ``pause`` and ``planning`` 0 it watches only at a bout's end.

    Parameters
    ----------
    speed, rot_speed : float
        What the operator's keys command, m/s and rad/s (the scene's ``teleop``).
    bout : float, optional
        The longest it holds keys before watching, s; ``math.inf``: continuous control.
        Default ``params.bout``.
    pause : float, optional
        Seconds it watches after letting go, beyond the reaction time; default
        ``params.pause``.
    planning : float, optional
        Seconds from its first sight of the arm to its first press at the soonest (the
        time to plan the first move); default ``params.planning``.
    """

    def __init__(
        self,
        params: ParticipantParams,
        reference,
        *,
        rng,
        tick: float = TICK,
        speed: float = SPEED,
        rot_speed: float = ROT_SPEED,
        bout: float | None = None,
        pause: float | None = None,
        planning: float | None = None,
    ):
        super().__init__(params, reference, rng=rng, tick=tick)
        self.bout, self.pause, self.planning = intermittency(
            params.bout if bout is None else bout,
            params.pause if pause is None else pause,
            params.planning if planning is None else planning,
        )
        self._times = np.asarray(reference, dtype=float)[:, 0]
        self._speeds = (float(speed), float(rot_speed))
        self._estimate = ArmEstimate(
            params.perception_noise * DEPTH_NOISE,  # as _perceive adds it
            noise_decay=np.exp(-tick / NOISE_TIME),
            period=ESTIMATE_PERIOD,
            key_speed=[speed, speed, speed, rot_speed],
        )
        # The displacement the own keys commanded so far, and before each tick from the
        # percept in hand on (t, displacement before t); the last percept taken.
        self._commanded = np.zeros(4)
        self._history: deque[tuple[float, np.ndarray]] = deque()
        self._taken: tuple[float, np.ndarray] | None = None
        self._changed_at = -np.inf
        self._bout_from = 0.0  # when the keys went down after none were held
        self._watch_until = -np.inf
        self._pulled_back = 0.0  # m the drift takes the arm back within LEAD_TIME

    def keys(self, t: float, state) -> frozenset[str]:
        if self.planning and not self._history:
            # The first tick: no press before the first sight and the planning after it.
            self._watch_until = t + self.params.reaction_time + self.planning
        self._history.append((t, self._commanded))
        held = super().keys(t, state)
        self._commanded = self._commanded + keys_to_action(held, *self._speeds) * self.tick
        return held

    def _choose_keys(self, error: np.ndarray, t: float) -> frozenset[str]:
        if t < self._watch_until - 1e-9:
            return frozenset()
        if self._held and t - self._bout_from >= self.bout - 1e-9:
            if self._pulled_back > self.params.deadband:
                # Seen pulled off without its keys: no look needed, the bout goes on.
                self._bout_from = t
            else:
                # The bout is over: let go, and watch until the arm without keys is seen.
                self._watch_until = t + self.params.reaction_time + self.pause
                self._changed_at = t
                return frozenset()
        chosen = super()._choose_keys(error, t)
        if chosen == self._held:
            return chosen
        # A press waits out the refractory interval of the last change; a release
        # never waits, and starts the interval like any other response.
        if not chosen < self._held and t - self._changed_at < REFRACTORY - 1e-9:
            return self._held
        self._changed_at = t
        if chosen and not self._held:
            self._bout_from = t
        elif not chosen and self.pause:
            self._watch_until = t + self.pause  # let go: move and wait
        return chosen

    def _error(self, perceived: np.ndarray, t: float) -> np.ndarray | None:
        """The displacement the operator's keys must add within :data:`LEAD_TIME`."""
        now, drift = self._estimate_now(perceived, t)
        ahead = self._track(now)
        if self._arrived(now, ahead):
            return None
        last = len(self._times) - 1
        wanted = self._times.searchsorted(self._times[self._progress] + LEAD_TIME)
        toward = self.reference[min(int(wanted), last)] - now
        drifted = drift * LEAD_TIME
        # How far the drift alone takes the arm back from where it wants to go.
        distance = length(toward[:3] * _SCALE[:3])
        self._pulled_back = -dot(drifted[:3], toward[:3]) / distance if distance > 0 else 0.0
        return toward - drifted

    def _estimate_now(self, perceived: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The arm now, from the estimate at the percept and the own keys since; the drift."""
        seen_at = self._perceived_at
        while len(self._history) > 1 and self._history[1][0] <= seen_at + 1e-9:
            self._history.popleft()
        commanded_then = self._history[0][1]
        estimate = self._estimate
        if self._taken is None or seen_at > self._taken[0]:
            before = commanded_then if self._taken is None else self._taken[1]
            elapsed = seen_at - (seen_at if self._taken is None else self._taken[0])
            estimate.update(perceived, commanded_then - before, elapsed)
            self._taken = (seen_at, commanded_then)
        assert estimate.position is not None  # updated above
        since = self._commanded - commanded_then
        drift = estimate.drift
        return estimate.position + estimate.authority * since + drift * (t - seen_at), drift


def intermittency(bout: float, pause: float, planning: float) -> tuple[float, float, float]:
    """``bout``, ``pause`` and ``planning`` as floats, if valid; else a ValueError naming one.

    Examples
    --------
    >>> intermittency(1, 0, 0.5)
    (1.0, 0.0, 0.5)
    >>> intermittency(1, -0.1, 0)
    Traceback (most recent call last):
    ...
    ValueError: pause = -0.1 s: the watch after letting go must be finite and >= 0
    """
    if not bout > 0:
        raise ValueError(f"bout = {bout} s: the longest bout of keys must be positive")
    if not 0 <= pause < np.inf:
        raise ValueError(f"pause = {pause} s: the watch after letting go must be finite and >= 0")
    if not 0 <= planning < np.inf:
        raise ValueError(f"planning = {planning} s: the time to plan must be finite and >= 0")
    return float(bout), float(pause), float(planning)


#: The operator models, by the name of config key ``simulation.operator``.
OPERATORS = {"lookahead": SimulatedParticipant, "predictive": PredictiveParticipant}


def make_participant(
    params: ParticipantParams,
    reference,
    *,
    rng: np.random.Generator,
    tick: float = TICK,
    operator: str,
    speed: float = SPEED,
    rot_speed: float = ROT_SPEED,
) -> SimulatedParticipant:
    """The participant of operator model ``operator`` (a key of :data:`OPERATORS`).

    ``speed`` and ``rot_speed`` are what its keys command (the scene's ``teleop``), which
    the predictive operator knows; it steers with the intermittent control of ``params``
    (``bout``, ``pause``, ``planning``; :class:`PredictiveParticipant`), which the
    lookahead operator does not have.

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
    if operator == "predictive":
        return PredictiveParticipant(
            params, reference, rng=rng, tick=tick, speed=speed, rot_speed=rot_speed
        )
    return OPERATORS[operator](params, reference, rng=rng, tick=tick)
