"""What the original implementation computed at an inference step, its defects included.

The replay preset ``original_defects`` (:data:`~casa_core.vocabulary.DEFECTS_PRESET`)
redoes this over an imported session, so that its logged beliefs and betas can be checked
against what their own code would give on the same path; the import recomputes a PBA
session's most likely goal with it where the session did not save its posterior. It is a
check of imports, not a model to analyse with: the preset ``original`` computes the same
without the defects.
``docs/replay.md`` lists both. At step ``i`` over the waypoints ``w_0 .. w_i`` (link 7,
every 0.5 s) and goals ``G``:

* costs are 50 / 0.22 per metre of path; the prefix is the path ``w_0 .. w_i``, the cost to
  go the straight line ``w_i -> G_g``, the optimum the straight line ``w_0 -> G_g``;
* defect 1: a ``False`` passed as a goal index adds a pose penalty of 100 per metre from
  ``w_i`` to goal 0 into every goal's prefix cost;
* the suboptimality ``S = (prefix + to go - optimal) / 1.8``; defect 2: not clamped;
* defect 3, Python 2 integer division: ``beta = floor(3.5 i) / (S + 4)``, and the posterior
  ``exp(-beta S) (beta / 2 pi) ** (3 i)``, not ``3.5 i``;
* defect 4: the posterior normalised in linear space (0 / 0 when every term underflows);
* alpha: CASA ``clip(1 / beta of the most likely goal, 0, 1)``; PBA the belief under
  beta = 1 and ``clip(|w_i - G*| / 0.55, 0, 1)``; NA 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from casa_core.defaults import COST_PER_METRE, EPSILON, LAM, PBA_DISTANCE
from casa_core.fixed_order import length

#: The pose penalty per metre that the original added to every prefix cost.
POSE_PENALTY = 100.0
#: The original's divisor of the suboptimality.
SUBOPT_DIVISOR = 1.8


@dataclass(frozen=True)
class OriginalStep:
    """One step's ``suboptimality``, ``beta``, ``belief`` (per goal), ``star``, ``alpha``."""

    suboptimality: np.ndarray
    beta: np.ndarray
    belief: np.ndarray
    star: int
    alpha: float


def _length(points: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))


def _posterior(subopt: np.ndarray, beta: np.ndarray, i: int) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        terms = np.exp(-beta * subopt) * (beta / (2 * np.pi)) ** (3 * i)
        return terms / np.sum(terms)


def original_step(waypoints: np.ndarray, goals: np.ndarray, arbitration: str) -> OriginalStep:
    """The original's inference over ``waypoints`` (i + 1, 3) toward ``goals`` (g, 3).

    ``arbitration`` is ``"confidence"`` (CASA), ``"distance"`` (PBA) or anything else
    (alpha 1).

    Examples
    --------
    One step of 0.1 m straight toward goal 0: its suboptimality is the penalty alone,
    100 x 0.9 / 1.8 = 50, and beta = floor(3.5) / (50 + 4):

    >>> goals = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    >>> step = original_step(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]), goals, "confidence")
    >>> step.suboptimality.round(3).tolist(), round(float(step.beta[0]), 6), step.alpha
    ([50.0, 63.256], 0.055556, 1.0)
    """
    i = len(waypoints) - 1
    current = waypoints[-1]
    prefix = COST_PER_METRE * _length(waypoints) + POSE_PENALTY * length(current - goals[0])
    to_go = COST_PER_METRE * np.linalg.norm(goals - current, axis=1)
    optimal = COST_PER_METRE * np.linalg.norm(goals - waypoints[0], axis=1)
    subopt = (prefix + to_go - optimal) / SUBOPT_DIVISOR
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = ((7 * i) // 2) / (subopt + LAM)
    if arbitration == "distance":
        belief = _posterior(subopt, np.ones_like(beta), i)
    else:
        belief = _posterior(subopt, beta, i)
    star = int(np.argmax(belief))
    alpha = 1.0
    if arbitration == "confidence":
        with np.errstate(divide="ignore"):
            alpha = float(np.clip(1.0 / beta[star], 0.0, 1.0))
    elif arbitration == "distance":
        alpha = float(np.clip(length(current - goals[star]) / PBA_DISTANCE, 0.0, 1.0))
    return OriginalStep(subopt, beta, belief, star, alpha)


def original_rows(steps, waypoints, goals, names, arbitration, epsilon=EPSILON) -> list[dict]:
    """One replay row per step and goal.

    ``steps`` holds ``(t, w)`` per step: its time and the last of ``waypoints`` it ran over
    (``waypoints[0..w]``, w >= 1); ``names`` are the goals' names, ``epsilon`` the threshold
    below which every beta makes the step misspecified.

    Examples
    --------
    >>> goals = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    >>> path = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])
    >>> rows = original_rows([(0.52, 2)], path, goals, ["green", "purple"], "confidence")
    >>> [(row["t"], row["intent"], row["theta_star"]) for row in rows]
    [(0.52, 'green', 'green'), (0.52, 'purple', 'green')]
    """
    rows = []
    for t, w in steps:
        step = original_step(np.asarray(waypoints[: w + 1]), goals, arbitration)
        misspecified = bool(np.all(step.beta < epsilon))
        for g, name in enumerate(names):
            rows.append(
                {
                    "t": float(t),
                    "intent": name,
                    "suboptimality": float(step.suboptimality[g]),
                    "beta": float(step.beta[g]),
                    "belief": float(step.belief[g]),
                    "theta_star": names[step.star],
                    "alpha": step.alpha,
                    "misspecified": misspecified,
                }
            )
    return rows
