"""Deep maximum-entropy IRL of a new intent from a few demonstrations (paper, Sec. II-E).

When no known intent explains the person, the robot asks for demonstrations and
learns the missing intent as a neural cost C_phi over states
(:mod:`casa_core.learning.features`). The gradient of the IRL objective is estimated
as (paper, after Finn et al. 2016)

    grad L = mean over D* of grad C_phi(tau)  -  mean over D^phi of grad C_phi(tau),

the demonstrations D* minus trajectories D^phi near-optimal under the current cost:
the loss is the mean cost of D* minus the mean cost of D^phi and torch's autograd
gives its gradient. D^phi holds, for each demonstration, the planner-optimal
trajectory under the current cost from the demonstration's start over the common
horizon (:mod:`casa_core.learning.demonstrations`), its end left free. The settings,
and where they depart from the original implementation, are those of
:class:`~casa_core.learning.config.IRLConfig` (docs/departures.md).

Determinism: the network is initialised from a ``torch.Generator`` seeded with
``seed`` (no global random state), the planner is deterministic, training runs
on one thread and the network's products sum in a fixed order
(:mod:`casa_core.learning.network`), so the same demonstrations, objects and seed give
the same weights on every processor.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable, Mapping

import numpy as np
import torch

from casa_core.fixed_order import length
from casa_core.learning.adam import Adam
from casa_core.learning.config import IRLConfig
from casa_core.learning.demonstrations import demo_steps, demo_waypoints
from casa_core.learning.features import (
    bounded_cost,
    cost_logits,
    cost_network,
    feature_names,
    object_positions,
)
from casa_core.learning.neural_intent import NeuralIntent, calibrate
from casa_core.learning.numpy_cost import NumpyStateCost
from casa_core.planning import Plan, optimize

#: Metres of end-position error that one radian of rot error counts as (:func:`end_match`).
ROT_METRES_PER_RADIAN = 0.1


def end_match(distance_m, rot_error):
    """How far trajectories end from the demonstrations: metres plus 0.1 m per radian of rot.

    Examples
    --------
    >>> round(end_match(0.02, 0.5), 12)
    0.07
    """
    return distance_m + ROT_METRES_PER_RADIAN * rot_error


def stop_reason(history: list[dict]) -> str:
    """Why IRL stopped: ``"converged"`` or ``"budget"`` (it ran ``max_iterations``).

    ``converged`` is :class:`IRLConfig`'s criterion (``tol_gap``, ``tol_end``,
    ``tol_match``) at the last iteration. It says when training stopped, not how good the
    intent is: the weights kept are those of the ``kept`` iteration, chosen by planning
    (:class:`MaxEntIRL`), not necessarily the last (docs/data-contracts.md).

    Examples
    --------
    >>> stop_reason([{"converged": False}]), stop_reason([{}, {"converged": True}])
    ('budget', 'converged')
    """
    return "converged" if history and history[-1].get("converged") else "budget"


def kept_record(history: list[dict]) -> dict | None:
    """The record of the iteration whose weights the intent has, if the history marks it.

    Examples
    --------
    >>> kept_record([{"iteration": 1}, {"iteration": 2, "kept": True}])
    {'iteration': 2, 'kept': True}
    """
    return next((record for record in history if record.get("kept")), None)


class MaxEntIRL:
    """Deep maximum-entropy IRL as an estimator: configure, then :meth:`fit`.

    Parameters
    ----------
    name : str
        Name of the intent to learn.
    config : IRLConfig, optional
        Network, optimizer, convergence and planner settings (defaults if None).
    seed : int
        Seed of the network's initialisation.
    progress : callable, optional
        ``progress(iteration, max_iterations)`` after each IRL iteration (a progress
        bar); an exception it raises stops the training.

    Attributes
    ----------
    intent_ : NeuralIntent
        The learned intent (set by :meth:`fit`).
    history_ : list of dict
        One record per iteration: ``iteration``, ``loss`` (mean demo cost minus
        mean D^phi cost), ``demo_cost``, ``sample_cost``, ``gap`` (loss per state
        relative to ``cost_scale``), ``end_distance_m`` (mean distance between
        the ends of D^phi and of the demonstrations), ``end_rot_error`` (mean
        absolute difference of their rot, rad), ``end_moved_m`` (how far the
        ends of D^phi moved since the last iteration; None on the first),
        ``planner_iterations``, ``seconds``; on the last, ``converged``; on the
        iterations checked at the end, ``verified_match``; on the iteration
        whose weights are returned, ``kept`` (True) and, if the cost was
        calibrated, ``calibration`` (the factor applied).
    n_iter_ : int
        Iterations run.
    converged_ : bool
        Whether the convergence criterion held at the last iteration.
    kept_iteration_ : int
        The iteration whose weights the intent has.
    calibration_ : float or None
        The calibration factor applied (None without calibration).

    Notes
    -----
    The intent's ``cost_offset`` is the lowest per-state cost among the states
    of the kept iteration's D^phi and of the demonstrations: where the person
    comes to rest, resting is free (see :class:`NeuralIntent`).

    The weights returned are those under which D^phi was planned in one of the
    ``verify_candidates`` iterations whose D^phi ended closest to the
    demonstrations (:func:`end_match`): of those, the one whose optimum, planned
    as assistance plans it, ends closest. Costs are checked by planning rather
    than taken after further, unchecked gradient steps.

    Examples
    --------
    A short run (2 iterations, a 2 s horizon) on one demonstration along x:

    >>> from casa_core.planning import PlannerConfig
    >>> t = np.linspace(0.0, 2.0, 9)
    >>> demo = np.column_stack([t, 0.4 + 0.05 * t, np.full(9, 0.1), np.full(9, 0.3), 0 * t])
    >>> quick = IRLConfig(
    ...     max_iterations=2, min_iterations=2, explore_iterations=5, verify_candidates=1,
    ...     planner=PlannerConfig(horizon=2.0, iterations=20),
    ... )
    >>> learner = MaxEntIRL("reach", config=quick, seed=0).fit([demo], {"goal": (0.5, 0.1, 0.3)})
    >>> learner.n_iter_, learner.intent_.name, learner.intent_.object_names
    (2, 'reach', ['goal'])
    >>> [record["iteration"] for record in learner.history_]
    [1, 2]
    """

    def __init__(
        self,
        name: str = "learned",
        *,
        config: IRLConfig | None = None,
        seed: int = 0,
        progress: Callable[[int, int], None] | None = None,
    ):
        self.name = name
        self.config = config
        self.seed = seed
        self.progress = progress

    def fit(self, demonstrations, objects: Mapping) -> MaxEntIRL:
        """Learn the intent from demonstrations in a scene of named objects.

        Parameters
        ----------
        demonstrations : list of array_like
            Each ``(n, 5)`` of ``[t, x, y, z, rot]`` (5 in the study).
        objects : mapping of str to array_like (3,)
            The scene objects whose positions are features, in feature order
            (e.g. :func:`casa_core.study.learning_evidence.scene_objects`).

        Returns
        -------
        MaxEntIRL
            self, with ``intent_``, ``history_`` and the other fitted attributes set.
        """
        config = IRLConfig() if self.config is None else self.config
        name = self.name
        demos = [np.asarray(d, dtype=float) for d in demonstrations]
        if not demos:
            raise ValueError(f"learning intent {name!r} needs at least one demonstration")
        planner = config.planner
        try:
            n_steps = demo_steps(demos, dt=planner.dt, horizon=planner.horizon)
            waypoints = np.stack([demo_waypoints(d, dt=planner.dt, n_steps=n_steps) for d in demos])
            object_names, positions = object_positions(objects)
        except ValueError as error:
            raise ValueError(f"learning intent {name!r}: {error}") from None
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # deterministic and fair to the other processes
        try:
            network = cost_network(
                len(feature_names(object_names)),
                hidden=config.hidden,
                negative_slope=config.negative_slope,
                seed=self.seed,
            )
            training = _Training(network, positions, waypoints, n_steps, config)
            history, candidates, converged = training.run(self.progress)
            build = _intent_builder(name, object_names, positions, waypoints, config)
            intent, kept, factor = _verified_choice(
                candidates,
                history,
                network,
                training.per_state,
                training.demo_states,
                waypoints,
                build,
                config.verify_candidates,
            )
        finally:
            torch.set_num_threads(threads)
        history[kept - 1]["kept"] = True
        if factor is not None:
            history[kept - 1]["calibration"] = factor
        self.intent_ = intent
        self.history_ = history
        self.n_iter_ = len(history)
        self.converged_ = converged
        self.kept_iteration_ = kept
        self.calibration_ = factor
        return self


def _intent_builder(name: str, object_names, positions, waypoints, config: IRLConfig):
    """``build(network, offset)``: a candidate network's intent (calibrated, and its factor)."""
    start = waypoints[:, 0, :].mean(axis=0)

    def build(weights_of: torch.nn.Module, offset: float):
        intent = NeuralIntent(
            name,
            weights_of,
            objects=dict(zip(object_names, positions, strict=True)),
            cost_scale=config.cost_scale,
            length_scale=config.length_scale,
            planner=config.assist_planner(),
            guides=[waypoints.mean(axis=0)],
            cost_offset=offset,
        )
        if config.calibration is None:
            return intent, None
        return calibrate(intent, start, cost=config.calibration)

    return build


class _Training:
    """One run of the IRL iterations: the network, its optimizer and the demonstrations."""

    def __init__(self, network, positions, waypoints, n_steps: int, config: IRLConfig):
        self.network = network
        self.config = config
        self.n_steps = n_steps
        self.positions = positions
        self.objects_t = torch.as_tensor(positions, dtype=torch.float64)
        self.optimizer = Adam(network.parameters(), lr=config.lr, weight_decay=config.weight_decay)
        self.demo_states = torch.from_numpy(waypoints[:, 1:, :])
        self.demo_ends = waypoints[:, -1, :]
        self.starts = waypoints[:, 0, :]

    def logits(self, states: torch.Tensor) -> torch.Tensor:
        return cost_logits(
            self.network, states, objects=self.objects_t, length_scale=self.config.length_scale
        )

    def per_state(self, states: torch.Tensor) -> torch.Tensor:
        return bounded_cost(self.logits(states), self.config.cost_scale)

    def run(self, progress=None) -> tuple[list[dict], list[tuple], bool]:
        """Iterate to convergence; the history, every iteration's candidate and convergence.

        A candidate is ``(match, iteration, weights, D^phi states)``, the weights being
        those under which that D^phi was planned.
        """
        config = self.config
        history: list[dict] = []
        candidates = []
        samples = None
        began = time.perf_counter()
        for iteration in range(1, config.max_iterations + 1):
            plan = self.plan_samples(samples)
            # The cost under which this D^phi is optimal, kept in case it is the best.
            planned_under = {k: v.clone() for k, v in self.network.state_dict().items()}
            costs = self.descend(plan.states)
            history.append(self.record(iteration, plan, samples, costs[0], began))
            samples = plan.states
            candidates.append((_match(history[-1]), iteration, planned_under, plan.states))
            converged = _converged(history[-1], config)
            if progress is not None:
                progress(iteration, config.max_iterations)
            if iteration >= config.min_iterations and converged:
                break
        history[-1]["converged"] = converged
        return history, candidates, converged

    def plan_samples(self, samples) -> Plan:
        """D^phi under the current cost: cold at first, then warm or exploring, the cheaper."""
        # The current cost, in numpy for the planner (the same formula as per_state).
        cost = NumpyStateCost(
            self.network,
            objects=self.positions,
            length_scale=self.config.length_scale,
            cost_scale=self.config.cost_scale,
        )
        planner, n_steps = self.config.planner, self.n_steps
        if samples is None:
            return optimize(cost, self.starts, n_steps, config=planner)
        warm = optimize(cost, self.starts, n_steps, config=planner, warm_start=samples[:, 1:])
        cold = optimize(
            cost,
            self.starts,
            n_steps,
            config=planner,
            iterations=self.config.explore_iterations,
        )
        better = (cold.costs < warm.costs)[:, None, None]
        return Plan(
            np.where(better, cold.states, warm.states),
            np.minimum(cold.costs, warm.costs),
            warm.iterations + cold.iterations,
        )

    def descend(self, plan_states: np.ndarray) -> list[tuple[float, float, float]]:
        """Adam steps on the cost; (loss, demo cost, sample cost) before each step."""
        config = self.config
        sample_states = torch.from_numpy(plan_states[:, 1:, :])
        costs = []
        for _ in range(config.steps_per_iteration):
            demo_logits, sample_logits = self.logits(self.demo_states), self.logits(sample_states)
            demo_cost = bounded_cost(demo_logits, config.cost_scale, mean_trajectory=True)
            sample_cost = bounded_cost(sample_logits, config.cost_scale, mean_trajectory=True)
            loss = demo_cost - sample_cost
            penalty = config.logit_penalty * ((demo_logits**2).mean() + (sample_logits**2).mean())
            self.optimizer.zero_grad()
            (loss / config.cost_scale + penalty).backward()
            self.optimizer.step()
            costs.append((loss.item(), demo_cost.item(), sample_cost.item()))
        return costs

    def record(self, iteration: int, plan: Plan, previous, costs, began: float) -> dict:
        """The history record of one iteration (see ``MaxEntIRL.history_``)."""
        ends = plan.states[:, -1, :]
        moved = (
            None
            if previous is None
            else float(np.linalg.norm(ends[:, :3] - previous[:, -1, :3], axis=1).max())
        )
        loss_value, demo_value, sample_value = costs
        return {
            "iteration": iteration,
            "loss": loss_value,
            "demo_cost": demo_value,
            "sample_cost": sample_value,
            "gap": loss_value / (self.n_steps * self.config.cost_scale),
            "end_distance_m": float(
                np.linalg.norm(ends[:, :3] - self.demo_ends[:, :3], axis=1).mean()
            ),
            "end_rot_error": float(np.abs(ends[:, 3] - self.demo_ends[:, 3]).mean()),
            "end_moved_m": moved,
            "planner_iterations": plan.iterations,
            "seconds": time.perf_counter() - began,
        }


def _verified_choice(candidates, history, network, per_state, demo_states, waypoints, build, k):
    """The learned intent to return, the iteration whose cost it has, and its calibration.

    The ``k`` iterations whose D^phi ended closest to the demonstrations are each
    made into the intent to return (offset and calibration included) and
    planned as assistance will plan it: a cold plan from the demonstrations'
    mean start, guided by the mean demonstration. D^phi is warm started and can
    miss a cheaper optimum elsewhere (e.g. the cup turned the other way) that
    such a plan finds; the intent whose own optimum ends closest to the
    demonstrations' mean end (:func:`end_match`) is kept. Each candidate's match is
    recorded in its history record as ``verified_match``. ``build(network,
    cost_offset)`` returns the intent and its calibration factor (None if not
    calibrated).
    """
    start = waypoints[:, 0, :].mean(axis=0)
    mean_end = waypoints[:, -1, :].mean(axis=0)
    best = None
    for _, iteration, weights, plan_states in sorted(candidates, key=lambda c: c[:2])[:k]:
        network.load_state_dict(weights)
        with torch.no_grad():  # the cost at rest: the cheapest state planned or demonstrated
            seen = torch.cat([torch.from_numpy(plan_states[:, 1:, :]), demo_states], dim=1)
            offset = float(per_state(seen).min())
        intent, factor = build(copy.deepcopy(network), offset)
        end = intent.optimal_trajectory(start, intent.planner.horizon)[-1]
        match = float(end_match(length(end[:3] - mean_end[:3]), abs(end[3] - mean_end[3])))
        history[iteration - 1]["verified_match"] = match
        if best is None or match < best[0]:
            best = (match, iteration, intent, factor)
    return best[2], best[1], best[3]


def _match(record: dict) -> float:
    """The :func:`end_match` of one history record (how far D^phi ends from the demos)."""
    return end_match(record["end_distance_m"], record["end_rot_error"])


def _converged(record: dict, config: IRLConfig) -> bool:
    """The convergence criterion of :class:`IRLConfig` on one history record."""
    return bool(
        abs(record["gap"]) < config.tol_gap
        and record["end_moved_m"] is not None
        and record["end_moved_m"] < config.tol_end
        and _match(record) < config.tol_match
    )
