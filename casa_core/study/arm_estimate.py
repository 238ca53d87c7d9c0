"""The simulated operator's estimate of the arm: its own keys and what it sees, combined.

A person steering an arm knows which keys they hold (an efference copy) and sees the arm
with noise and a delay; people combine the two as a Kalman filter does (Wolpert,
Ghahramani & Jordan 1995, "An internal model for sensorimotor integration", *Science*
269(5232)), and adapt the internal model when a tool's gain changes (visuomotor
adaptation). :class:`ArmEstimate` is that filter over ``[x, y, z, rot]``. Over each
interval the arm moves by the operator's own displacement times one *authority* (1 under
direct control, alpha under a blend, the same on every axis) plus a *drift* per axis (what
the arm does without the keys: the robot's share) times the interval; drift and authority
change at random. The operator sees the position plus its perception noise, which is not
white but slowly varying (AR(1), as :class:`~casa_core.study.participants.SimulatedParticipant`
draws it), so the noise is part of the state.

State, in order: position (4), drift (4), authority (1), perception noise of x, y, z (3).
The covariance is propagated and updated by compiled loops in a fixed order (no linear
algebra library, no fastmath), so the estimate is the same to the bit on every x86-64
processor.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Perception noise, m, of the operator whose estimate of a steady drift settles with the
#: natural period ``period`` of :class:`ArmEstimate`: the population's median
#: (``simulation.population.perception_noise`` in config/config.yaml).
REFERENCE_NOISE = 0.01
#: Standard deviation of the authority a key has under a blend that may give it any share
#: from 0 to 1 (a uniform share: 1 / sqrt(12)).
AUTHORITY_SPREAD = 1 / np.sqrt(12)
#: White noise left on what is seen once the slowly varying noise is in the state, m.
_RESIDUAL = 1e-5
_AXES = 4
_DRIFT = 4  # first drift entry
_AUTHORITY = 8
_NOISE = 9  # first noise entry (x, y, z)
_SIZE = 12


@njit(cache=True)
def _propagate(state, covariance, transition, change):
    """``x = F x`` and ``P = F P F^T + Q``, summed in index order."""
    n = state.shape[0]
    moved = np.zeros(n)
    for i in range(n):
        total = 0.0
        for k in range(n):
            total += transition[i, k] * state[k]
        moved[i] = total
    state[:] = moved
    left = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            total = 0.0
            for k in range(n):
                total += transition[i, k] * covariance[k, j]
            left[i, j] = total
    for i in range(n):
        for j in range(n):
            total = 0.0
            for k in range(n):
                total += left[i, k] * transition[j, k]
            covariance[i, j] = total + change[i, j]


@njit(cache=True)
def _observe(state, covariance, seen, residual):
    """One scalar update per axis, in axis order: ``seen[a] = position[a] + noise[a]``."""
    n = state.shape[0]
    gain = np.empty(n)
    row = np.empty(n)
    for axis in range(_AXES):
        noisy = axis < 3
        noise = _NOISE + axis
        predicted = state[axis] + (state[noise] if noisy else 0.0)
        total = covariance[axis, axis] + residual
        if noisy:
            total += 2 * covariance[axis, noise] + covariance[noise, noise]
        for i in range(n):
            row[i] = covariance[axis, i] + (covariance[noise, i] if noisy else 0.0)
        for i in range(n):
            gain[i] = row[i] / total
        innovation = seen[axis] - predicted
        for i in range(n):
            state[i] += gain[i] * innovation
        for i in range(n):
            for j in range(n):
                covariance[i, j] -= gain[i] * row[j]


@njit(cache=True)
def _model(moved, elapsed, drift_change, authority_change, noise_decay, noise_change):
    """The transition F and the random change Q over one interval."""
    transition = np.eye(_SIZE)
    change = np.zeros((_SIZE, _SIZE))
    for axis in range(_AXES):
        drift = _DRIFT + axis
        transition[axis, drift] = elapsed
        transition[axis, _AUTHORITY] = moved[axis]
        change[axis, axis] = drift_change * elapsed**4 / 4
        change[axis, drift] = drift_change * elapsed**3 / 2
        change[drift, axis] = drift_change * elapsed**3 / 2
        change[drift, drift] = drift_change * elapsed**2
    change[_AUTHORITY, _AUTHORITY] = authority_change * elapsed
    for axis in range(3):
        noise = _NOISE + axis
        transition[noise, noise] = noise_decay
        change[noise, noise] = noise_change[axis]
    return transition, change


@njit(cache=True)
def _step(state, covariance, seen, moved, elapsed, rates, noise_decay, noise_change):
    """Propagate over ``elapsed`` and take the percept ``seen``; ``rates`` holds the
    drift's and the authority's random change and the residual white noise's variance."""
    transition, change = _model(moved, elapsed, rates[0], rates[1], noise_decay, noise_change)
    _propagate(state, covariance, transition, change)
    _observe(state, covariance, seen, rates[2])


class ArmEstimate:
    """A Kalman filter of the arm's position, its drift and the keys' authority.

    Parameters
    ----------
    noise : array_like, shape (3,)
        Standard deviation of the operator's perception noise along x, y, z, m; rotation
        is seen without noise.
    noise_decay : float
        The noise's AR(1) factor from one percept to the next.
    period : float
        The natural period, s, with which the estimate of an operator seeing with
        :data:`REFERENCE_NOISE` settles on a steady drift: the drift changes at random by
        ``REFERENCE_NOISE / period**2`` per second per sqrt(s) (the alpha-beta filter's
        white change of velocity), the authority by ``AUTHORITY_SPREAD / sqrt(period)``.
    key_speed : array_like, shape (4,)
        What one key moves per second along its axis; the drift's prior spread is
        ``AUTHORITY_SPREAD`` times it (the robot's share of a blend).
    authority_spread : float, default AUTHORITY_SPREAD
        The prior spread of the authority around 1 (direct control); 0, with
        ``authority_change=0``, is a filter that knows the keys act in full.
    authority_change : float, optional
        The authority's random change per sqrt(s); default ``AUTHORITY_SPREAD / sqrt(period)``.

    Attributes
    ----------
    position : ndarray, shape (4,) or None
        The arm when the last percept was made; None before the first.
    drift : ndarray, shape (4,)
        What the arm does per second without the operator's keys.
    authority : float
        The share of its own keys' displacement that the arm makes.

    Examples
    --------
    Direct control, seen without noise: the estimate follows the arm, the authority stays 1.

    >>> estimate = ArmEstimate(
    ...     np.full(3, 1e-6), noise_decay=0.9, period=1.0, key_speed=np.full(4, 0.05)
    ... )
    >>> estimate.update(np.zeros(4), np.zeros(4), 0.05)
    >>> estimate.update(np.full(4, 0.0025), np.full(4, 0.0025), 0.05)
    >>> estimate.position.round(6).tolist(), round(estimate.authority, 3)
    ([0.0025, 0.0025, 0.0025, 0.0025], 1.0)
    """

    def __init__(
        self,
        noise,
        *,
        noise_decay: float,
        period: float,
        key_speed,
        authority_spread: float = AUTHORITY_SPREAD,
        authority_change: float | None = None,
    ):
        self.noise = np.asarray(noise, dtype=float)
        self.noise_decay = float(noise_decay)
        self.period = float(period)
        self.key_speed = np.asarray(key_speed, dtype=float)
        if authority_change is None:
            authority_change = AUTHORITY_SPREAD / np.sqrt(period)
        self._drift_change = (REFERENCE_NOISE / period**2) ** 2
        self._authority_change = float(authority_change) ** 2
        self._noise_change = self.noise**2 * (1 - self.noise_decay**2)
        self._rates = np.array([self._drift_change, self._authority_change, _RESIDUAL**2])
        self._state = np.zeros(_SIZE)
        self._state[_AUTHORITY] = 1.0
        covariance = np.zeros((_SIZE, _SIZE))
        # The first percept is taken for the position: its error is that percept's noise.
        for axis in range(3):
            variance = self.noise[axis] ** 2
            covariance[axis, axis] = covariance[_NOISE + axis, _NOISE + axis] = variance
            covariance[axis, _NOISE + axis] = covariance[_NOISE + axis, axis] = -variance
        covariance[3, 3] = _RESIDUAL**2
        for axis in range(_AXES):
            spread = AUTHORITY_SPREAD * self.key_speed[axis]
            covariance[_DRIFT + axis, _DRIFT + axis] = spread**2
        covariance[_AUTHORITY, _AUTHORITY] = authority_spread**2
        self._covariance = covariance
        self._started = False

    @property
    def position(self) -> np.ndarray | None:
        return self._state[:_AXES].copy() if self._started else None

    @property
    def drift(self) -> np.ndarray:
        return self._state[_DRIFT:_AUTHORITY].copy()

    @property
    def authority(self) -> float:
        return float(self._state[_AUTHORITY])

    def update(self, seen, moved, elapsed: float) -> None:
        """Take a percept ``seen`` made ``elapsed`` s after the last one, over which the
        operator's own keys commanded the displacement ``moved``; the noise has taken one
        AR(1) step since."""
        seen = np.asarray(seen, dtype=float)
        if not self._started:
            self._state[:_AXES] = seen
            self._started = True
            return
        _step(
            self._state,
            self._covariance,
            seen,
            np.asarray(moved, dtype=float),
            float(elapsed),
            self._rates,
            self.noise_decay,
            self._noise_change,
        )
