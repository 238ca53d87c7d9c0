"""Trajectory optimization in torch, and intents planned by it.

The paper computes optimal trajectories xi* "with any off-the-shelf trajectory
optimizer" (footnote to Sec. II-B; the original used TrajOpt). Goal intents have a
closed-form optimum (:mod:`casa_core.assist.intents`); the pouring skill and learned
(neural) costs do not, and are planned here:

- :mod:`~casa_core.planning.optimizer`: the optimizer (:func:`optimize`) and its
  settings (:class:`PlannerConfig`);
- :mod:`~casa_core.planning.planned_intent`: :class:`PlannedIntent`, an intent whose
  cost is a per-state cost, planned and cached;
- :mod:`~casa_core.planning.rotation`: the end effector's orientation as a differentiable
  function of ``rot``;
- :mod:`~casa_core.planning.pouring`: the pouring skill as a hand-written cost, and the
  cup's tilt.
"""

from casa_core.planning.optimizer import (
    LIMITS,
    Plan,
    PlannerConfig,
    StateCost,
    feasible,
    optimize,
    steps_left,
    warm_start_from,
)
from casa_core.planning.planned_intent import PlannedIntent

__all__ = [
    "LIMITS",
    "Plan",
    "PlannedIntent",
    "PlannerConfig",
    "StateCost",
    "feasible",
    "optimize",
    "steps_left",
    "warm_start_from",
]
