"""The torch trajectory optimizer (casa_core.planning) against closed-form optima.

Closed forms used here. For a per-state cost ``sum_i f(||x_i - g||)`` with f
increasing, each state's cost depends on that state alone, and the states
reachable i steps after ``x0`` form a set S_i (a box of half-width ``i s`` per
axis under per-axis limits, a ball of radius ``i s`` under a norm limit). The
point of S_i nearest to g minimises term i, and consecutive nearest points are
one feasible step apart (per axis: ``clip(g - x0, -i s, i s)`` changes by at
most s per axis; in a ball they lie on the segment to g, s apart). So the
optimum is ``x_i = x0 + clip(g - x0, -i s, i s)`` (per axis) and ``x_i = x0 +
min(i s, d) (g - x0) / d`` (norm), the latter being GoalIntent's
``distance_sum`` optimum (casa_core.assist.intents).
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from casa_core.assist.intents import GoalIntent
from casa_core.defaults import COST_PER_METRE
from casa_core.planning import (
    PlannedIntent,
    PlannerConfig,
    feasible,
    optimize,
    steps_left,
    warm_start_from,
)

START = np.array([0.45, -0.22, 0.38, 0.0])  # config/scene.yaml start
RED = np.array([0.40, 0.22, 0.12])  # config/scene.yaml red goal
STEP = 0.05 * 0.5  # keyboard speed x dt


def distance_cost(goal):
    goal_t = torch.as_tensor(np.asarray(goal, dtype=float))
    return lambda s: torch.linalg.vector_norm(s[..., :3] - goal_t, dim=-1)


def per_axis_optimum(start, goal, n):
    reach = STEP * np.arange(n + 1)[:, None]
    return start[:3] + np.clip(goal - start[:3], -reach, reach)


class GoalCost(PlannedIntent):
    """A PlannedIntent with GoalIntent's distance_sum cost (scale * dt * distance)."""

    def __init__(self, goal, planner=None, scale=COST_PER_METRE):
        super().__init__("goal", planner)
        self.goal = torch.as_tensor(goal, dtype=torch.float64)
        self.scale = scale

    def state_cost(self, states):
        return self.scale * self.dt * torch.linalg.vector_norm(states[..., :3] - self.goal, dim=-1)


def test_per_axis_limits_reach_closed_form_optimum():
    plan = optimize(distance_cost(RED), START, 30)
    expected = per_axis_optimum(START, RED, 30)
    np.testing.assert_allclose(plan.states[0, :, :3], expected, atol=1e-3)
    closed_cost = np.linalg.norm(expected[1:] - RED, axis=1).sum()
    assert plan.costs[0] == pytest.approx(closed_cost, rel=1e-4)
    assert plan.states.shape == (1, 31, 4)  # T = 15 s every 0.5 s
    np.testing.assert_array_equal(plan.states[0, 0], START)


def test_norm_limit_matches_goal_intent_closed_form():
    config = PlannerConfig(limit="norm")
    goal = GoalIntent("red", RED, cost="distance_sum")
    planned = GoalCost(RED, config)
    np.testing.assert_allclose(
        planned.optimal_trajectory(START, 15.0), goal.optimal_trajectory(START, 15.0), atol=1e-3
    )
    assert planned.cost_to_go(START, 15.0) == pytest.approx(goal.cost_to_go(START, 15.0), rel=1e-3)


def test_steps_respect_speed_limits():
    config = PlannerConfig()
    # A far goal and a rot pull: every step saturates somewhere.
    far = torch.tensor([2.0, -1.0, 1.0, 5.0], dtype=torch.float64)
    plan = optimize(lambda s: ((s - far) ** 2).sum(-1), START, 30, config=config)
    steps = np.diff(plan.states[0], axis=0)
    assert (np.abs(steps) <= config.max_step() + 1e-12).all()
    norm = PlannerConfig(limit="norm")
    plan = optimize(lambda s: ((s - far) ** 2).sum(-1), START, 30, config=norm)
    steps = np.diff(plan.states[0], axis=0)
    assert (np.linalg.norm(steps[:, :3], axis=1) <= STEP + 1e-12).all()


def test_batch_rows_with_their_own_costs_equal_single_solves():
    goals = torch.tensor(np.array([RED, [0.58, 0.0, 0.30]]), dtype=torch.float64)

    def cost(states):  # row b is the distance to goal b
        return torch.linalg.vector_norm(states[..., :3] - goals[:, None, :], dim=-1)

    starts = np.array([START, START + [0.02, 0.0, -0.01, 0.0]])
    batch = optimize(cost, starts, 30)
    for b in range(2):
        single = optimize(distance_cost(goals[b].numpy()), starts[b], 30)
        np.testing.assert_allclose(batch.states[b], single.states[0], atol=1e-3)
        np.testing.assert_allclose(
            batch.states[b, :, :3], per_axis_optimum(starts[b], goals[b].numpy(), 30), atol=1e-3
        )


def test_deterministic():
    a = optimize(distance_cost(RED), START, 30)
    b = optimize(distance_cost(RED), START, 30)
    np.testing.assert_array_equal(a.states, b.states)


def test_warm_start_from_shifted_optimum_needs_fewer_iterations():
    cold = optimize(distance_cost(RED), START, 30)
    warm = optimize(
        distance_cost(RED),
        cold.states[0, 4],
        26,
        warm_start=warm_start_from(cold.states, 4, 26),
    )
    assert warm.iterations < cold.iterations
    np.testing.assert_allclose(warm.states[0], cold.states[0, 4:], atol=1e-3)


def test_planned_intent_cost_decomposes_along_its_optimum():
    # Bellman: prefix cost of the optimum up to k plus the optimal cost-to-go from
    # there equals the optimal cost from the start (what the suboptimality relies on).
    intent = GoalCost(RED)
    trajectory = intent.optimal_trajectory(START, 15.0)
    total = intent.cost_to_go(START, 15.0)
    for k in (1, 6, 20):
        split = intent.prefix_cost(trajectory[: k + 1]) + intent.cost_to_go(
            trajectory[k], 15.0 - 0.5 * k
        )
        assert split == pytest.approx(total, rel=1e-3)
    assert intent.distance(START) == pytest.approx(np.linalg.norm(RED - START[:3]), abs=1e-3)


def test_edges_and_bad_input():
    plan = optimize(distance_cost(RED), START, 0)
    assert plan.states.shape == (1, 1, 4) and plan.costs[0] == 0
    assert steps_left(15.0, 0.5) == 30 and steps_left(-1.0, 0.5) == 0
    with pytest.raises(ValueError, match="starts"):
        optimize(distance_cost(RED), [0.0, np.nan, 0.0, 0.0], 5)
    with pytest.raises(ValueError, match="warm_start"):
        optimize(distance_cost(RED), START, 5, warm_start=np.zeros((1, 4, 4)))
    with pytest.raises(ValueError, match="limit"):
        PlannerConfig(limit="box")
    with pytest.raises(ValueError, match="dt of PlannerConfig must be a positive number"):
        PlannerConfig(dt=0.0)
    with pytest.raises(ValueError, match="tol of PlannerConfig"):
        PlannerConfig(tol=np.nan)
    with pytest.raises(TypeError):  # the planner's settings are keywords after the steps
        optimize(distance_cost(RED), START, 5, PlannerConfig())


def test_feasible_leaves_feasible_states_alone_and_clips_the_rest():
    starts = np.zeros((1, 4))
    ok = np.array([[[1.0, -1.0, 0.5, 1.0], [2.0, -1.5, 0.0, 0.0]]])
    np.testing.assert_array_equal(feasible(starts, ok, "axis"), ok)
    far = np.array([[[3.0, 0.0, 0.0, 0.0]]])
    np.testing.assert_array_equal(feasible(starts, far, "axis"), [[[1.0, 0.0, 0.0, 0.0]]])
    diagonal = np.array([[[3.0, 4.0, 0.0, 0.0]]])
    np.testing.assert_allclose(feasible(starts, diagonal, "norm"), [[[0.6, 0.8, 0.0, 0.0]]])


def test_costs_to_go_of_several_states_match_one_by_one_plans():
    # The assistant asks for the cost-to-go at the arm's state and at the state the
    # user's input alone reached; a planner batches both, warm started alike.
    batched, single = GoalCost(RED), GoalCost(RED)
    for intent in (batched, single):
        intent.cost_to_go(START, 15.0)  # the plan later plans warm start from
    a = START + np.array([0.02, 0.01, -0.02, 0.0])
    b = START + np.array([-0.01, 0.025, 0.0, 0.0])
    costs = batched.costs_to_go([a, b], 14.5)
    expected = [single.cost_to_go(a, 14.5), single.cost_to_go(b, 14.5)]
    np.testing.assert_allclose(costs, expected, rtol=1e-3)
    assert len(batched._cache) == 3  # both new plans kept: the next ask is free
    np.testing.assert_array_equal(batched.costs_to_go([a, b], 14.5), costs)


def test_a_trial_plans_the_same_whatever_trial_ran_before_it():
    # Two trials share one intent, as the trials after learning do. Trial B's plan at a
    # state trial A also visited must be the plan B makes on its own: a cached plan or a
    # warm start from A would make B's numbers depend on the order of the trials.
    config = PlannerConfig(warm_iterations=5)  # few iterations: the warm start shows
    visited = START + [0.05, 0.05, -0.05, 0.0]

    def trial_b(intent):
        intent.start_trial()
        intent.plan(START + [0.0, 0.1, 0.0, 0.0], 15.0)
        return intent.plan(visited, 14.5)

    alone = trial_b(GoalCost(RED, config))
    shared = GoalCost(RED, config)
    shared.start_trial()
    shared.plan(START, 15.0)  # trial A
    shared.plan(visited, 14.5)
    after_a = trial_b(shared)
    np.testing.assert_array_equal(after_a.states, alone.states)
    np.testing.assert_array_equal(after_a.costs, alone.costs)
    # The shared intent's cache does serve a trial's own repeated plans.
    assert shared.plan(visited, 14.5) is after_a


def test_a_seeded_plan_survives_the_start_of_a_trial():
    intent = GoalCost(RED)
    seeded = optimize(intent.state_cost, START, steps_left(15.0, intent.dt))
    intent.seed_plan(START, 15.0, seeded)
    intent.start_trial()
    assert intent.plan(START, 15.0) is seeded
