"""Intents as cost functions (paper, Sec. II-A).

An intent is what the user may want the robot to do, represented by a cost over
trajectories of the arm's state ``[x, y, z, rot]`` (end-effector position in the
robot base frame, metres, and the angle driven by the rotate keys, radians),
sampled every ``dt`` seconds. Inference needs three things of an intent: the
cost of the observed prefix (additive, so it can be kept incrementally), the
optimal cost-to-go from a state with the time left, and the optimal trajectory
that the robot assists along.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from casa_core.defaults import COST_PER_METRE, DT, SPEED
from casa_core.fixed_order import length
from casa_core.model._checks import require_positive

COST_FORMS = ("path_length", "distance_sum")


class Intent(ABC):
    """A cost function over trajectories of states ``[x, y, z, rot]`` sampled every ``dt``.

    Subclasses implement :meth:`step_cost`, :meth:`cost_to_go`,
    :meth:`optimal_trajectory` and :meth:`distance`.
    """

    name: str
    dt: float

    @abstractmethod
    def step_cost(self, state_from: np.ndarray, state_to: np.ndarray) -> float:
        """Cost of one step; the cost of a prefix is the sum of its steps."""

    def prefix_cost(self, states: np.ndarray) -> float:
        """C(xi_{0->t}) of the observed states ``(n, 4)``, the first being the start.

        Examples
        --------
        >>> green = GoalIntent("green", [0.3, 0.4, 0.0], scale=1.0)
        >>> green.prefix_cost([[0, 0, 0, 0], [0.3, 0, 0, 0], [0.3, 0.4, 0, 0]])  # 0.3 + 0.4
        0.7
        """
        states = np.asarray(states, dtype=float)
        pairs = zip(states[:-1], states[1:], strict=True)
        return float(sum(self.step_cost(a, b) for a, b in pairs))

    @abstractmethod
    def cost_to_go(self, state: np.ndarray, time_left: float) -> float:
        """C(xi*_{t->T}): the optimal cost from ``state`` with ``time_left`` seconds left."""

    def costs_to_go(self, states, time_left: float) -> np.ndarray:
        """:meth:`cost_to_go` of several states with the same time left (planners batch them).

        Examples
        --------
        >>> green = GoalIntent("green", [0.3, 0.4, 0.0], scale=1.0)
        >>> green.costs_to_go([[0, 0, 0, 0], [0.3, 0.4, 0, 0]], 15.0)
        array([0.5, 0. ])
        """
        return np.array([self.cost_to_go(state, time_left) for state in states])

    @abstractmethod
    def optimal_trajectory(self, state: np.ndarray, time_left: float) -> np.ndarray:
        """xi*_{t->T}: states ``(n, 4)`` every ``dt`` from ``state`` (included) to the horizon."""

    @abstractmethod
    def distance(self, state: np.ndarray) -> float:
        """Distance (m) from the end effector to where the intent ends; PBA arbitrates with it."""

    def start_trial(self) -> None:  # noqa: B027 (a hook: a closed form has nothing to drop)
        """Forget what earlier trials left behind, so that a trial's numbers do not depend
        on the trials before it. A closed-form intent keeps nothing; a planned one
        (:class:`casa_core.planning.PlannedIntent`) drops its cached plans and warm start."""


class GoalIntent(Intent):
    """Reaching a goal position with the end effector, at most ``speed`` m/s.

    Two cost forms, chosen with ``cost``:

    ``"path_length"`` (the original implementation's; see docs/departures.md)
        C(xi) = scale * (sum of ||x_{i+1} - x_i||): the end-effector path length.
        Its cost-to-go is the straight line to the goal, ``scale * d`` from distance
        d, whatever the time left: the time left sets how many states the optimal
        trajectory has, not its cost.
    ``"distance_sum"`` (the paper's, Sec. II-A)
        C(xi) = scale * dt * sum_i ||x_i - g|| over the states after the start,
        i.e. the time integral of the distance to the goal. The optimum drives
        straight at ``speed`` (step s = v dt) and waits at the goal; with n steps
        left and m = min(n, floor(d / s)) its cost-to-go is
        ``scale * dt * (m d - s m (m + 1) / 2)``.

    Only the position counts; the rotation is held. Under both, the robot's optimal
    trajectory (:meth:`optimal_trajectory`) drives straight to the goal at ``speed``.

    Parameters
    ----------
    name : str
        Intent name (e.g. ``"green"``).
    goal : array_like, shape (3,)
        Goal position in the robot base frame, metres.
    cost : {"path_length", "distance_sum"}, default "path_length"
    speed : float, default SPEED
        Fastest end-effector speed of the optimal trajectory, m/s (the keyboard's 0.05).
    dt : float, default DT
        Seconds between trajectory states (0.5 in the original).
    scale : float, default COST_PER_METRE
        Cost per metre (path_length; the original's 50 / 0.22) or per metre-second
        (distance_sum).

    Examples
    --------
    >>> green = GoalIntent("green", [0.3, 0.4, 0.0])  # 0.5 m from the origin
    >>> green
    GoalIntent('green', goal=[0.3, 0.4, 0.0], cost='path_length')
    >>> start = np.zeros(4)
    >>> green.distance(start)
    0.5
    >>> green.optimal_trajectory(start, 1.0)[:, :2]  # 0.025 m per 0.5 s step toward the goal
    array([[0.   , 0.   ],
           [0.015, 0.02 ],
           [0.03 , 0.04 ]])
    """

    def __init__(
        self,
        name: str,
        goal,
        *,
        cost: str = "path_length",
        speed: float = SPEED,
        dt: float = DT,
        scale: float = COST_PER_METRE,
    ):
        if cost not in COST_FORMS:
            raise ValueError(f"cost must be one of {COST_FORMS}, got {cost!r}")
        goal = np.asarray(goal, dtype=float)
        if goal.shape != (3,) or not np.isfinite(goal).all():
            raise ValueError(f"goal of intent {name!r} must be 3 finite numbers, got {goal!r}")
        require_positive(f"intent {name!r}", speed=speed, dt=dt, scale=scale)
        self.name = name
        self.goal = goal
        self.cost = cost
        self.speed = float(speed)
        self.dt = float(dt)
        self.scale = float(scale)

    def __repr__(self) -> str:
        return f"GoalIntent({self.name!r}, goal={self.goal.tolist()}, cost={self.cost!r})"

    def step_cost(self, state_from, state_to) -> float:
        """Cost of the step ``state_from -> state_to`` (path length, or distance left x dt).

        Examples
        --------
        >>> GoalIntent("green", [0.3, 0.4, 0.0], scale=1.0).step_cost(np.zeros(4), np.ones(4))
        1.7320508075688772
        """
        if self.cost == "path_length":
            return self.scale * length(state_to[:3] - state_from[:3])
        return self.scale * self.dt * length(state_to[:3] - self.goal)

    def cost_to_go(self, state, time_left: float) -> float:
        """C(xi*_{t->T}) in closed form (see the class docstring for both cost forms).

        Examples
        --------
        >>> green = GoalIntent("green", [0.3, 0.4, 0.0], scale=1.0)
        >>> green.cost_to_go(np.zeros(4), 15.0)  # the straight 0.5 m to the goal
        0.5
        >>> green.cost_to_go(np.zeros(4), 0.0)  # whatever the time left
        0.5
        """
        d = length(np.asarray(state[:3], dtype=float) - self.goal)
        if self.cost == "path_length":
            return self.scale * d
        n = int(np.floor(max(float(time_left), 0.0) / self.dt + 1e-9))
        step = self.speed * self.dt
        m = min(n, int(np.floor(d / step + 1e-12)))
        return self.scale * self.dt * (m * d - step * m * (m + 1) / 2.0)

    def optimal_trajectory(self, state, time_left: float) -> np.ndarray:
        """The straight line to the goal at ``speed``, then waiting there; rotation held."""
        state = np.asarray(state, dtype=float)
        n = int(np.floor(max(float(time_left), 0.0) / self.dt + 1e-9))
        offset = self.goal - state[:3]
        d = length(offset)
        travelled = np.minimum(self.speed * self.dt * np.arange(n + 1), d)
        direction = offset / d if d > 0 else np.zeros(3)
        positions = state[:3] + travelled[:, None] * direction
        return np.column_stack([positions, np.full(n + 1, state[3])])

    def distance(self, state) -> float:
        """Euclidean distance (m) from the end effector to the goal."""
        return length(np.asarray(state[:3], dtype=float) - self.goal)
