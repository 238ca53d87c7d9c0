"""Trajectory optimization in torch for any differentiable per-state cost.

The paper computes optimal trajectories xi* "with any off-the-shelf trajectory
optimizer" (footnote to Sec. II-B; the original used TrajOpt). Goal intents have
a closed-form optimum (:mod:`casa_core.assist.intents`); the pouring skill and learned
(neural) costs do not, and are planned here.

A trajectory is ``n + 1`` states ``[x, y, z, rot]`` every ``dt`` seconds (the
original: T = 15 s, dt = 0.5 s, 31 states), the first being the given start.
Its cost is the sum of a per-state cost over the states *after* the start, so
that costs are additive along the trajectory and a prefix cost plus an optimal
cost-to-go is the cost of the whole (the decomposition the paper's eq. 3 needs).

Each step is bounded by the keyboard's speed limits times ``dt``: by default
0.05 m/s on each Cartesian axis and 0.5 rad/s on rot (the original's keyboard), i.e. a
box of 0.025 m x 3 and 0.25 rad per step; ``limit="norm"`` bounds the Euclidean
speed of the position instead (what :class:`casa_core.assist.assistant.Assistant` uses
for its own action u*).

The optimizer works on the states themselves, in units of the per-step limit,
where a per-state cost is well conditioned (optimizing the steps instead couples
every state to all earlier ones and converges far more slowly). Each iteration
takes an Adam step on the states with the gradient of the cost, then makes the
trajectory feasible again by walking from the start and clipping every step to
its limit (:func:`feasible`); the step size decays geometrically, and the
cheapest iterate met is returned (on a non-convex cost, Adam may climb out of a
good initial guess). With ``limit="norm"`` Adam's second moment is shared by the
three position axes so that a step keeps the gradient's direction.

The optimizer is deterministic (no random numbers, fixed order of operations; its
per-iteration loops are compiled, :mod:`casa_core.planning._kernels`), runs on the
CPU and optimizes a batch of trajectories at once: each row may have its own start
and, through the cost function, its own cost. Batching pays where
one network evaluates many rows: IRL plans D^phi for all demonstrations in one
batch, and a learned intent's cold plan tries all its starting guesses in one.
Different intents are planned one by one
(:class:`~casa_core.planning.planned_intent.PlannedIntent`), each warm started from
its own previous plan, which is what keeps an inference step short.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

from casa_core.defaults import DT, HORIZON, ROT_SPEED, SPEED
from casa_core.model._checks import require_positive
from casa_core.planning import _kernels

#: Cost of states: takes a tensor ``(B, n, 4)`` and returns per-state costs ``(B, n)``.
#: A per-state cost: torch tensors in and out, or numpy arrays for a cost with its own
#: gradient (``value_and_grad``).
StateCost = Callable[[Any], Any]

LIMITS = ("axis", "norm")


@dataclass(frozen=True)
class PlannerConfig:
    """Settings of the trajectory optimizer.

    Attributes
    ----------
    horizon : float
        T, seconds (15 in the original).
    dt : float
        Seconds between states (0.5 in the original).
    speed : float
        End-effector speed limit, m/s (the keyboard's 0.05).
    rot_speed : float
        Limit on the rate of rot, rad/s (the keyboard's 0.5).
    limit : {"axis", "norm"}
        ``"axis"``: ``speed`` bounds each Cartesian axis (keys held together add
        up, as on the keyboard); ``"norm"``: ``speed`` bounds the Euclidean speed.
    iterations : int
        Most optimizer iterations from a cold start (steps all zero).
    warm_iterations : int
        Most iterations when warm started from a previous solution.
    lr : float
        Initial Adam step from a cold start, in units of the per-step limit.
    warm_lr : float
        Initial Adam step when warm started (the guess is already close).
    decay : float
        Factor applied to the step size at every iteration.
    tol : float
        Stop when no normalised step moves more than this in one iteration.
    """

    horizon: float = HORIZON
    dt: float = DT
    speed: float = SPEED
    rot_speed: float = ROT_SPEED
    limit: str = "axis"
    iterations: int = 400
    warm_iterations: int = 60
    lr: float = 0.5
    warm_lr: float = 0.1
    decay: float = 0.99
    tol: float = 1e-4

    def __post_init__(self):
        if self.limit not in LIMITS:
            raise ValueError(f"PlannerConfig.limit must be one of {LIMITS}, got {self.limit!r}")
        require_positive(
            "PlannerConfig",
            horizon=self.horizon,
            dt=self.dt,
            speed=self.speed,
            rot_speed=self.rot_speed,
            lr=self.lr,
            warm_lr=self.warm_lr,
            tol=self.tol,
        )
        if not 0 < self.decay <= 1:
            raise ValueError(f"PlannerConfig.decay must be in (0, 1], got {self.decay!r}")
        if self.iterations < 1 or self.warm_iterations < 1:
            raise ValueError("PlannerConfig.iterations and warm_iterations must be >= 1")

    @property
    def n_steps(self) -> int:
        """Steps in a full horizon (30 for T = 15 s, dt = 0.5 s)."""
        return steps_left(self.horizon, self.dt)

    def max_step(self) -> np.ndarray:
        """Largest change of ``[x, y, z, rot]`` in one step: speed limits times ``dt``."""
        return np.array([self.speed, self.speed, self.speed, self.rot_speed]) * self.dt


@dataclass(frozen=True)
class Plan:
    """Optimal trajectories of a batch.

    Attributes
    ----------
    states : numpy.ndarray, shape (B, n + 1, 4)
        The trajectories, the given starts included.
    costs : numpy.ndarray, shape (B,)
        Their costs (sum of the per-state cost over the states after the start).
    iterations : int
        Optimizer iterations run.
    """

    states: np.ndarray
    costs: np.ndarray
    iterations: int


def steps_left(time_left: float, dt: float) -> int:
    """Number of whole steps of ``dt`` in ``time_left`` seconds (never negative)."""
    return max(int(np.floor(max(float(time_left), 0.0) / dt + 1e-9)), 0)


def feasible(starts: np.ndarray, targets: np.ndarray, limit: str) -> np.ndarray:
    """Walk from ``starts`` ``(B, 4)`` toward ``targets`` ``(B, n, 4)``, one limited step each.

    Both in units of the per-step limit: a step is clipped to [-1, 1] on each
    axis (``limit="axis"``) or its position part scaled to norm <= 1 and its rot
    clipped (``limit="norm"``). States that are already feasible come back unchanged.

    Examples
    --------
    >>> starts = np.zeros((1, 4))
    >>> feasible(starts, np.array([[[3.0, 0.5, 0.0, -2.0]]]), "axis").tolist()
    [[[1.0, 0.5, 0.0, -1.0]]]
    >>> feasible(starts, np.array([[[3.0, 4.0, 0.0, 0.0]]]), "norm").tolist()
    [[[0.6, 0.8, 0.0, 0.0]]]
    """
    if limit not in LIMITS:
        raise ValueError(f"limit must be one of {LIMITS}, got {limit!r}")
    targets = np.ascontiguousarray(targets, dtype=float)
    out = np.empty_like(targets)
    _kernels.walk(np.ascontiguousarray(starts, dtype=float), targets, limit == "norm", out)
    return out


def warm_start_from(states: np.ndarray, n_done: int, n_steps: int) -> np.ndarray:
    """Initial guess ``(B, n_steps, 4)`` from a previous solution ``(B, m + 1, 4)``.

    The first ``n_done`` steps, already taken, are dropped; the guess is cut or
    padded (by holding the last state) to ``n_steps`` states after the start.
    """
    states = np.asarray(states, dtype=float)
    rest = states[:, 1 + max(n_done, 0) :, :][:, :n_steps, :]
    if rest.shape[1] == 0:
        rest = states[:, -1:, :]
    pad = n_steps - rest.shape[1]
    if pad > 0:
        rest = np.concatenate([rest, np.repeat(rest[:, -1:, :], pad, axis=1)], axis=1)
    return rest


def optimize(
    state_cost: StateCost,
    starts,
    n_steps: int,
    *,
    config: PlannerConfig | None = None,
    warm_start=None,
    initial_guess=None,
    iterations: int | None = None,
) -> Plan:
    """Minimise the summed per-state cost over trajectories from ``starts``.

    Parameters
    ----------
    state_cost : callable
        Maps states ``(B, n, 4)`` (float64 tensor, metres and radians) to
        per-state costs ``(B, n)``; must be differentiable in torch. Row b may
        encode a different cost than row b' (batching across intents). A cost with a
        method ``value_and_grad`` (e.g.
        :class:`~casa_core.learning.numpy_cost.NumpyStateCost`) is instead called on
        numpy arrays, and that method gives the per-state costs and the gradient of
        their sum in the states, without autograd.
    starts : array_like, shape (B, 4) or (4,)
        First state of each trajectory.
    n_steps : int
        Number of steps (states after the start); 0 gives the start alone.
    config : PlannerConfig, optional
        Speed limits, ``dt`` and optimizer settings (defaults if None).
    warm_start : array_like, shape (B, n_steps, 4), optional
        States after the start to begin from (e.g. :func:`warm_start_from` a
        previous :attr:`Plan.states`); made feasible first. Cold start (stay at
        the start) if None. Runs ``config.warm_iterations`` from ``warm_lr``.
    initial_guess : array_like, shape (B, n_steps, 4), optional
        Like ``warm_start`` but run as a cold start (``config.iterations`` from
        ``lr``): a rough guess such as a demonstration. Not both.
    iterations : int, optional
        Most iterations, instead of the config's (e.g. a short exploratory run).

    Returns
    -------
    Plan
        The optimized trajectories and their costs.
    """
    config = PlannerConfig() if config is None else config
    starts_np = np.atleast_2d(np.asarray(starts, dtype=float))
    if starts_np.ndim != 2 or starts_np.shape[1] != 4 or not np.isfinite(starts_np).all():
        raise ValueError(f"starts must be finite states [x, y, z, rot], got {starts_np.shape}")
    batch = starts_np.shape[0]
    if n_steps < 0:
        raise ValueError(f"n_steps must be >= 0, got {n_steps}")
    if n_steps == 0:
        return Plan(starts_np[:, None, :].copy(), np.zeros(batch), 0)
    scale = config.max_step()
    start_u = starts_np / scale
    guess = _first_guess(start_u, n_steps, scale, warm_start, initial_guess)
    if warm_start is None:
        budget, lr = config.iterations, config.lr
    else:
        budget, lr = config.warm_iterations, config.warm_lr
    budget = budget if iterations is None else int(iterations)
    states_u = feasible(start_u, guess, config.limit)
    scale_t = torch.as_tensor(scale, dtype=torch.float64)
    # Adam's moments (written out so that the feasibility step and decay stay explicit),
    # and the best iterate per row: on a non-convex cost Adam can leave a good guess behind.
    m = np.zeros_like(states_u)
    v = np.zeros_like(states_u)
    best_u = states_u.copy()
    best_cost = np.full(batch, np.inf)
    value_and_grad = getattr(state_cost, "value_and_grad", None)
    # The gradient in the states' units: autograd's already is, the numpy cost's is in metres.
    grad_scale = np.ones(4) if value_and_grad is None else scale
    norm = config.limit == "norm"
    iterations = 0
    for iterations in range(1, budget + 1):  # noqa: B007 (the count is reported)
        row_costs, grad = _costs_and_gradient(state_cost, value_and_grad, states_u, scale, scale_t)
        # Best iterate, Adam step, walk and the largest move, in one compiled loop.
        moved = _kernels.adam_step(
            states_u,
            np.ascontiguousarray(grad, dtype=float),
            grad_scale,
            np.ascontiguousarray(row_costs, dtype=float),
            m,
            v,
            best_u,
            best_cost,
            start_u,
            lr,
            1 - _kernels.ADAM_BETA1**iterations,
            1 - _kernels.ADAM_BETA2**iterations,
            norm,
        )
        lr *= config.decay
        if moved < config.tol:
            break
    states = np.concatenate([starts_np[:, None, :], states_u * scale], axis=1)
    states, costs = _best_of(state_cost, states, best_u * scale, best_cost)
    return Plan(states=states, costs=costs, iterations=iterations)


def _costs_and_gradient(state_cost, value_and_grad, states_u, scale, scale_t):
    """Each row's summed cost and the gradient in the states (step units): by autograd, or
    by the cost's own ``value_and_grad`` on numpy arrays (its gradient in metres)."""
    if value_and_grad is None:
        x = torch.from_numpy(states_u).requires_grad_(True)
        summed = state_cost(x * scale_t).sum(dim=1)
        (gradient,) = torch.autograd.grad(summed.sum(), x)
        return summed.detach().numpy(), gradient.numpy()
    per_state, grad = value_and_grad(states_u * scale)
    return per_state.sum(axis=1), grad


def _first_guess(start_u, n_steps: int, scale, warm_start, initial_guess) -> np.ndarray:
    """The states after the start the optimizer begins from, in step units: staying at
    the start, or the warm start or initial guess given (checked)."""
    batch = start_u.shape[0]
    if warm_start is not None and initial_guess is not None:
        raise ValueError("give warm_start or initial_guess, not both")
    if warm_start is None and initial_guess is None:
        return np.repeat(start_u[:, None, :], n_steps, axis=1)
    given = np.asarray(initial_guess if warm_start is None else warm_start, dtype=float)
    if given.shape != (batch, n_steps, 4) or not np.isfinite(given).all():
        raise ValueError(
            f"warm_start/initial_guess must be finite with shape {(batch, n_steps, 4)}, "
            f"got {given.shape}"
        )
    return given / scale


def _best_of(state_cost, states: np.ndarray, best: np.ndarray, best_cost: np.ndarray):
    """Per row, the last iterate ``states`` (start included) with its cost, or the best
    iterate seen (``best``, after the start) where that cost less."""
    if getattr(state_cost, "value_and_grad", None) is None:
        with torch.no_grad():
            costs = state_cost(torch.from_numpy(states[:, 1:, :])).sum(dim=1).numpy().copy()
    else:
        costs = state_cost(states[:, 1:, :]).sum(axis=1)
    keep = best_cost < costs
    if keep.any():
        states[keep, 1:, :] = best[keep]
        costs[keep] = best_cost[keep]
    return states, costs
