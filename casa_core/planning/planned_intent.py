"""Intents whose cost is a differentiable per-state cost, planned by the optimizer.

A :class:`PlannedIntent` answers the assistant's questions (cost-to-go, optimal
trajectory, distance) by planning with :func:`~casa_core.planning.optimizer.optimize`,
caching its plans and warm starting each from the latest, so that along a trial one
inference step costs a short warm-started optimization.
"""

from __future__ import annotations

from abc import abstractmethod
from collections import OrderedDict

import numpy as np
import torch

from casa_core.assist.intents import Intent
from casa_core.fixed_order import length
from casa_core.planning.optimizer import Plan, PlannerConfig, optimize, steps_left, warm_start_from


class PlannedIntent(Intent):
    """An intent whose cost is a differentiable per-state cost, planned by :func:`optimize`.

    Subclasses implement :meth:`state_cost`. The cost of a trajectory is the sum
    of the per-state cost over its states after the first, so one step from
    ``a`` to ``b`` costs ``state_cost(b)``. Plans are cached per (state, steps
    left) and each new plan is warm started from the latest one, advanced by the
    steps taken since: along a trial, one inference step costs a short warm
    started optimization instead of a cold one.

    Parameters
    ----------
    name : str
        Intent name.
    planner : PlannerConfig, optional
        Horizon, ``dt``, speed limits and optimizer settings (defaults if None).
    cache_size : int
        Plans kept (the assistant asks for the cost-to-go, the trajectory and the
        distance at the same state; a trial has 31 inference states and the next
        trial restarts from the same start, whose cold plan is the expensive one).
    guides : sequence of array_like, optional
        Trajectories ``(m + 1, 4)`` every ``dt`` (e.g. the mean demonstration of
        a learned intent). A plan that cannot be warm started is optimized, in
        one batch, from staying at the start and from each guide (its states
        after the first, cut or padded to the steps left), and the cheapest
        result is kept: a learned cost is not convex and a single start can
        stall in a local minimum. The guides only seed the optimizer; the cost
        alone decides.
    """

    def __init__(
        self,
        name: str,
        planner: PlannerConfig | None = None,
        *,
        cache_size: int = 64,
        guides=(),
    ):
        if not isinstance(name, str) or not name:
            raise ValueError(f"intent name must be a non-empty string, got {name!r}")
        self.name = name
        self.planner = PlannerConfig() if planner is None else planner
        self.dt = self.planner.dt
        self._cache: OrderedDict[tuple, Plan] = OrderedDict()
        self._cache_size = cache_size
        self._latest: tuple[int, np.ndarray] | None = None  # (steps left, states) of last plan
        self._seeded: dict[tuple, Plan] = {}  # plans given at construction: kept across trials
        self.guides = [np.asarray(g, dtype=float).reshape(-1, 4) for g in guides]

    @abstractmethod
    def state_cost(self, states: torch.Tensor) -> torch.Tensor:
        """Per-state cost ``(B, n)`` of states ``(B, n, 4)`` (float64), differentiable."""

    @property
    def planning_cost(self):
        """The per-state cost the planner optimizes: :meth:`state_cost` by default.

        A subclass may return an equal cost that :func:`optimize` evaluates faster (one
        with ``value_and_grad``, on numpy arrays).
        """
        return self.state_cost

    def costs_of(self, states) -> np.ndarray:
        """Per-state costs of states ``(n, 4)`` as a numpy array ``(n,)``."""
        states = np.asarray(states, dtype=float).reshape(-1, 4)
        cost = self.planning_cost
        if hasattr(cost, "value_and_grad"):
            return np.asarray(cost(states[None]), dtype=float)[0]
        with torch.no_grad():
            return self.state_cost(torch.from_numpy(states)[None]).numpy()[0].copy()

    def step_cost(self, state_from, state_to) -> float:
        return float(self.costs_of(state_to)[0])

    def prefix_cost(self, states) -> float:
        states = np.asarray(states, dtype=float)
        return float(self.costs_of(states[1:]).sum()) if len(states) > 1 else 0.0

    def plan(self, state, time_left: float) -> Plan:
        """The optimal trajectory from ``state`` with ``time_left`` seconds left (cached)."""
        state = np.asarray(state, dtype=float).reshape(4)
        n = steps_left(time_left, self.dt)
        key = (state.tobytes(), n)
        if key in self._cache:
            self._cache.move_to_end(key)
            cached = self._cache[key]
            if n > 0:  # later plans of this trial warm start from here
                self._latest = (n, cached.states[0])
            return cached
        if self._latest is not None and 0 < n <= self._latest[0]:
            previous_n, previous_states = self._latest
            warm = warm_start_from(previous_states[None], previous_n - n, n)
            result = optimize(
                self.planning_cost, state[None], n, config=self.planner, warm_start=warm
            )
        elif self.guides and n > 0:
            stay = np.repeat(state[None, None, :], n, axis=1)
            guesses = [warm_start_from(g[None], 0, n) for g in self.guides]
            batch = optimize(
                self.planning_cost,
                np.repeat(state[None], 1 + len(guesses), axis=0),
                n,
                config=self.planner,
                initial_guess=np.concatenate([stay, *guesses]),
            )
            best = int(np.argmin(batch.costs))
            result = Plan(
                batch.states[best : best + 1], batch.costs[best : best + 1], batch.iterations
            )
        else:
            result = optimize(self.planning_cost, state[None], n, config=self.planner)
        self._remember(key, result)
        if n > 0:
            self._latest = (n, result.states[0])
        return result

    def seed_plan(self, state, time_left: float, plan: Plan) -> None:
        """Take ``plan`` as the optimal trajectory from ``state`` (as if :meth:`plan` had).

        For a cost known to be a positive multiple of one already planned (a calibrated
        learned cost): its optimum is the same trajectory, its cost the multiple.
        """
        state = np.asarray(state, dtype=float).reshape(4)
        n = steps_left(time_left, self.dt)
        self._seeded[(state.tobytes(), n)] = plan
        self._remember((state.tobytes(), n), plan)
        if n > 0:
            self._latest = (n, plan.states[0])

    def start_trial(self) -> None:
        """Drop the plans and the warm start of earlier trials (a seeded plan stays): each
        trial's plans then depend on that trial alone, whatever ran before it."""
        self._cache = OrderedDict(self._seeded)
        self._latest = None

    def _remember(self, key: tuple, plan: Plan) -> None:
        self._cache[key] = plan
        if len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)

    def cost_to_go(self, state, time_left: float) -> float:
        return float(self.plan(state, time_left).costs[0])

    def costs_to_go(self, states, time_left: float) -> np.ndarray:
        """Costs-to-go of several states, the plans not yet cached optimized in one batch.

        Each is warm started from the latest plan (one network evaluation per
        iteration serves them all); the last state's plan is the one later plans
        warm start from.
        """
        states = [np.asarray(state, dtype=float).reshape(4) for state in states]
        n = steps_left(time_left, self.dt)
        keys = [(state.tobytes(), n) for state in states]
        missing = [i for i, key in enumerate(keys) if key not in self._cache]
        if len(missing) > 1 and self._latest is not None and 0 < n <= self._latest[0]:
            previous_n, previous_states = self._latest
            warm = warm_start_from(previous_states[None], previous_n - n, n)
            batch = optimize(
                self.planning_cost,
                np.stack([states[i] for i in missing]),
                n,
                config=self.planner,
                warm_start=np.repeat(warm, len(missing), axis=0),
            )
            for row, i in enumerate(missing):
                one = slice(row, row + 1)
                self._remember(keys[i], Plan(batch.states[one], batch.costs[one], batch.iterations))
        return np.array([self.plan(state, time_left).costs[0] for state in states])

    def optimal_trajectory(self, state, time_left: float) -> np.ndarray:
        return self.plan(state, time_left).states[0].copy()

    def distance(self, state) -> float:
        """Distance (m) to the end of the longest cached plan from ``state`` (or a new one)."""
        state = np.asarray(state, dtype=float).reshape(4)
        plans = [p for (s, _), p in self._cache.items() if s == state.tobytes()]
        plan = max(plans, key=lambda p: p.states.shape[1]) if plans else None
        if plan is None:
            plan = self.plan(state, self.planner.horizon)
        return length(plan.states[0, -1, :3] - state[:3])
