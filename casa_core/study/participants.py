"""Simulated participants: closed-loop keyboard operators.

A participant watches the end effector, follows the task's intended trajectory
(:func:`casa_core.tasks.intended_trajectory`, the reference shown before each
task) and holds keys of the same 8-key interface a person uses. It is an
operator model, not a script: it sees the arm's state with a delay and with
noise, steers toward a point a little ahead on the path, holds a key while the
error along that axis exceeds a deadband, lapses now and then, and sometimes
presses a wrong key. When assistance pulls the arm off the path the error grows
and the participant presses against it, so assisting for the wrong intent costs
effort, as it does for a person.

Population parameters (fixed before any result was looked at; distributions in
``config/config.yaml`` under ``simulation.population``) and their sources:

- ``reaction_time``: delay from seeing the arm to a changed key, s. The Model
  Human Processor puts a simple perceive-decide-press cycle at about 0.24 s
  (range 0.1-0.47 s; Card, Moran & Newell 1983, *The Psychology of
  Human-Computer Interaction*, ch. 2); choosing among several keys adds to it
  (Hick 1952; Hyman 1953). Lognormal, median 0.35 s.
- ``perception_noise``: standard deviation of the perceived end-effector
  position, m, slowly varying (AR(1), 0.5 s). Judging 3-D position on a screen
  is imprecise, worst in depth (Cutting & Vishton 1995); about 1 cm, twice that
  along the viewing direction (the robot's x axis).
- ``deadband``: position error below which no key is held, m (about 1.5 cm):
  keyboard control is on/off, so operators accept small errors instead of
  tapping (bang-bang control with a dead zone, Sheridan & Ferrell 1974,
  *Man-Machine Systems*).
- ``lapse_rate`` and ``lapse_duration``: attention lapses per second and their
  length, s, during which the held keys do not change (lapses of about 0.5-1.5 s
  in sustained tasks; Dinges & Powell 1985 psychomotor vigilance data).
- ``wrong_key``: probability that a press hits a wrong key; keystroke error
  rates of typists are about 1-3% (Salthouse 1986, Psychol. Bull. 99(3)).
- ``max_keys``: most keys held at once (1-3); players combine two direction
  keys for diagonals, novices often press one at a time.

The expert of the case study has a short delay, little noise, no lapses and no
wrong keys.
"""

from __future__ import annotations

from collections import deque
from dataclasses import asdict, dataclass

import numpy as np

from casa_core.robot.keys import AXIS_KEYS

# Rotation error is compared with position error at this many metres per radian.
ROT_TO_METRES = 0.1
LOOKAHEAD = 0.04  # m of path ahead that the participant steers toward
DONE_ROT_TOLERANCE = 0.15  # rad


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
    n: int, population: dict, rng: np.random.Generator
) -> list[ParticipantParams]:
    """Draw ``n`` participants from the population distribution in the config.

    ``population`` maps each parameter to ``{"median": m, "sigma": s}`` (lognormal)
    except ``max_keys``, which maps to ``{"values": [...], "p": [...]}``.
    """
    drawn = []
    for _ in range(n):
        values = {}
        for name in (
            "reaction_time",
            "perception_noise",
            "deadband",
            "lapse_rate",
            "lapse_duration",
            "wrong_key",
        ):
            spec = population[name]
            values[name] = float(spec["median"] * np.exp(spec["sigma"] * rng.standard_normal()))
        values["wrong_key"] = min(values["wrong_key"], 0.5)
        keys = population["max_keys"]
        values["max_keys"] = int(rng.choice(keys["values"], p=keys["p"]))
        drawn.append(ParticipantParams(**values))
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
        self._seen = deque()  # (t, state) not yet perceived
        self._perceived = None
        self._noise = np.zeros(3)
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
        error = self._error(perceived)
        if error is None:
            self.done = True
            self._held = frozenset()
            return self._held
        self._held = self._choose_keys(error)
        return self._held

    def _perceive(self) -> np.ndarray:
        # AR(1) position noise with a 0.5 s time constant, doubled along x (depth).
        decay = np.exp(-self.tick / 0.5)
        scale = self.params.perception_noise * np.array([2.0, 1.0, 1.0])
        innovation = self.rng.standard_normal(3) * scale * np.sqrt(1 - decay**2)
        self._noise = decay * self._noise + innovation
        perceived = self._perceived.copy()
        perceived[:3] += self._noise
        return perceived

    def _error(self, perceived: np.ndarray) -> np.ndarray | None:
        """Error to the steering point ahead on the path; None once the task is done."""
        scaled = self.reference.copy()
        scaled[:, 3] *= ROT_TO_METRES
        here = perceived.copy()
        here[3] *= ROT_TO_METRES
        window = scaled[self._progress : self._progress + 40]
        self._progress += int(np.argmin(np.linalg.norm(window - here, axis=1)))
        path = np.linalg.norm(np.diff(scaled[self._progress :], axis=0), axis=1)
        ahead = self._progress + int(np.searchsorted(np.cumsum(path), LOOKAHEAD))
        target = self.reference[min(ahead, len(self.reference) - 1)]
        final = self.reference[-1]
        at_end = ahead >= len(self.reference) - 1
        if (
            at_end
            and np.linalg.norm(perceived[:3] - final[:3]) < self.params.deadband
            and abs(perceived[3] - final[3]) < DONE_ROT_TOLERANCE
        ):
            return None
        return target - perceived

    def _choose_keys(self, error: np.ndarray) -> frozenset[str]:
        magnitude = np.abs(error) * np.array([1.0, 1.0, 1.0, ROT_TO_METRES])
        # Hysteresis: a held key stays down until the error falls to a third of the deadband.
        held_axes = {
            axis
            for axis, (plus, minus) in enumerate(AXIS_KEYS)
            if plus in self._held or minus in self._held
        }
        thresholds = np.array(
            [
                self.params.deadband / 3 if axis in held_axes else self.params.deadband
                for axis in range(4)
            ]
        )
        wanted = [axis for axis in np.argsort(-magnitude) if magnitude[axis] > thresholds[axis]]
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
