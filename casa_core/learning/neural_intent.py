"""A learned intent: a planned intent whose per-state cost is the learned network."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import torch

from casa_core.assist.intents import COST_FORMS, GoalIntent
from casa_core.learning.features import bounded_cost, cost_logits, feature_names, object_positions
from casa_core.learning.numpy_cost import NumpyStateCost
from casa_core.model._checks import require_positive
from casa_core.planning import Plan, PlannedIntent, PlannerConfig


class NeuralIntent(PlannedIntent):
    """An intent whose per-state cost is a learned network (deep MaxEnt IRL).

    ``state_cost(s) = cost_scale * sigmoid(network(state_features(s))) - cost_offset``,
    defined by :func:`casa_core.learning.features.bounded_cost`; the planner runs its
    compiled copy, :attr:`planning_cost` (checked equal in
    ``tests/learning/test_speed_equivalence.py``). The prefix cost, optimal
    cost-to-go, optimal trajectory and distance come from it and the planner
    (:class:`casa_core.planning.PlannedIntent`).

    ``cost_offset`` is the learned cost where the demonstrations come to rest,
    so that, as for a goal intent at its goal, resting where the task is done
    costs nothing. Learning cannot see a constant per-state offset (every
    trajectory of IRL has the same number of states), but inference can: a
    trial goes on past the horizon, and a cost that is not zero at rest would
    make a person who has finished look ever more suboptimal.

    Parameters
    ----------
    name : str
        Intent name.
    network : torch.nn.Module
        Maps features ``(..., F)`` to ``(..., 1)``.
    objects : mapping of str to array_like (3,)
        The scene objects whose positions are features, in feature order (kept
        with the intent: the cost is the one learned in that scene).
    cost_scale, length_scale : float
        See :class:`casa_core.learning.IRLConfig`.
    planner : PlannerConfig, optional
        Horizon, dt, speed limits and optimizer settings.
    guides : sequence of array_like, optional
        Extra starting guesses of the planner (the mean demonstration), see
        :class:`casa_core.planning.PlannedIntent`.
    cost_offset : float, optional
        Subtracted from every per-state cost (set by :class:`casa_core.learning.MaxEntIRL`).

    Attributes
    ----------
    object_names : list of str
        The objects' names, in feature order.
    objects : numpy.ndarray, shape (K, 3)
        Their positions.
    """

    def __init__(
        self,
        name: str,
        network: torch.nn.Module,
        *,
        objects: Mapping,
        cost_scale: float,
        length_scale: float,
        planner: PlannerConfig | None = None,
        guides=(),
        cost_offset: float = 0.0,
    ):
        super().__init__(name, planner, guides=guides)
        self.network = network
        try:
            self.object_names, self.objects = object_positions(objects)
        except ValueError as error:
            raise ValueError(f"intent {name!r}: {error}") from None
        # length_scale divides the features (0 gives NaN costs); a cost_scale <= 0 is no cost.
        require_positive(f"intent {name!r}", cost_scale=cost_scale, length_scale=length_scale)
        self.cost_scale = float(cost_scale)
        self.length_scale = float(length_scale)
        self.cost_offset = float(cost_offset)
        if not np.isfinite(self.cost_offset):
            raise ValueError(f"intent {name!r}: cost_offset must be finite, got {cost_offset!r}")
        self._objects_t = torch.as_tensor(self.objects, dtype=torch.float64)
        for parameter in self.network.parameters():
            parameter.requires_grad_(False)
        # The same cost for the planner, in numpy (the weights as they are now).
        self._numpy_cost = NumpyStateCost(
            network,
            objects=self.objects,
            length_scale=self.length_scale,
            cost_scale=self.cost_scale,
            offset=self.cost_offset,
        )

    def __repr__(self) -> str:
        return f"NeuralIntent({self.name!r}, objects={self.object_names})"

    @property
    def features(self) -> list[str]:
        """Names of the network's inputs."""
        return feature_names(self.object_names)

    @property
    def object_map(self) -> dict[str, np.ndarray]:
        """The objects as the mapping name -> position the constructor takes."""
        return dict(zip(self.object_names, self.objects, strict=True))

    @property
    def planning_cost(self) -> NumpyStateCost:
        """:meth:`state_cost` in numpy, with its gradient (the network as at construction)."""
        return self._numpy_cost

    def state_cost(self, states: torch.Tensor) -> torch.Tensor:
        logits = cost_logits(
            self.network, states, objects=self._objects_t, length_scale=self.length_scale
        )
        return bounded_cost(logits, self.cost_scale, offset=self.cost_offset)


def calibrate(intent: NeuralIntent, start, *, cost: str) -> tuple[NeuralIntent, float]:
    """The intent with its cost scaled to match a goal intent's (``IRLConfig.calibration``).

    The factor makes the intent's optimal cost from ``start`` equal that of a
    :class:`~casa_core.assist.intents.GoalIntent` of cost form ``cost`` whose goal is where
    that optimal trajectory ends. Returns the calibrated intent (a new one: plans are
    not shared) and the factor applied. Where the learned optimum from ``start``
    costs nothing (the person stays where they are), there is nothing to match and
    the factor is 1.
    """
    if cost not in COST_FORMS:
        raise ValueError(f"calibration must be one of {COST_FORMS} or None, got {cost!r}")
    planner = intent.planner
    plan = intent.plan(start, planner.horizon)
    learned = float(plan.costs[0])
    goal = GoalIntent("reference", plan.states[0, -1, :3], cost=cost, dt=planner.dt)
    reference = goal.cost_to_go(start, planner.horizon)
    factor = reference / learned if learned > 1e-9 and reference > 1e-9 else 1.0
    calibrated = NeuralIntent(
        intent.name,
        intent.network,
        objects=intent.object_map,
        cost_scale=intent.cost_scale * factor,
        length_scale=intent.length_scale,
        planner=planner,
        guides=intent.guides,
        cost_offset=intent.cost_offset * factor,
    )
    # The calibrated cost is the learned one times factor > 0: the same optimum.
    calibrated.seed_plan(start, planner.horizon, Plan(plan.states, plan.costs * factor, 0))
    return calibrated, factor
