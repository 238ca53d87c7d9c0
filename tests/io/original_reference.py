"""Test-side reference of what the original shared-autonomy code computed at each step.

Written in plain numpy from the original's "section 4", independently of the package
(only :func:`casa_core.robot.kinematics.link7_position` is used), to generate synthetic
session files whose logged histories the package's replay must reproduce to 1e-9.

Specification. Step ``i = 0, 1, ...`` sees the link-7 waypoints ``w_0..w_i`` (metres,
one every 0.5 s); goal ``gi`` is at ``G_gi``, goal 0 is ``G_0``.

* cost ``C(path) = 50 / 0.22 * path length``; prefix ``C(w_0..w_i)`` (0 at ``i = 0``),
  to-go ``C(w_i, G_gi)``, optimal ``C(w_0, G_gi)``;
* ``S_gi = (prefix + to-go_gi - optimal_gi) / 1.8``;
* faithful: ``S = max(S, 0)``, ``beta = 3.5 i / (S + 4)``, belief ``~ exp(-beta S)
  (beta / 2 pi)^(3.5 i)`` with a uniform prior, in log space; the log-likelihood is 0
  at ``i = 0`` (``0 log 0 = 0``) and a zero ``beta S`` counts as 0;
* defects (as it ran in Python 2): (a) ``beta = floor(3.5 i) / (S + 4)`` and exponent
  ``3 i``; (b) the prefix of every goal gets ``100 |w_i - G_0|`` added (also at
  ``i = 0``); (c) ``S`` not clamped; (d) belief in linear space, ``exp(-beta S)
  (beta / 2 pi)**(3 i)`` normalised over goals, 0/0 giving nan;
* arbitration (alpha, the human's share): CASA ``clip(1 / beta[argmax belief], 0, 1)``;
  PBA uses the belief at ``beta = 1`` for every goal and ``clip(|w_i - G*| / 0.55, 0, 1)``
  for its most likely goal ``G*``; NA ``1``. ``argmax`` is ``np.argmax``: first index on
  ties, and the first nan if the belief has one (so an all-nan belief picks goal 0).

The session's rows (NOTES section 4, corrected 2026-12-06): waypoint ``j`` is recorded at
``0.5 j`` s; timed step ``k`` starts when its waypoint ``w_k`` is recorded (``w_k = k + 1``
unless a step ran late) and runs over waypoints ``0..w_k``; the last row is the final step
after the trial, over every waypoint, each goal charged its own pose penalty of 100 per
metre from the last waypoint and no cost to go: ``S = (C(w_0..w_n) + 100 |w_n - G| -
C(w_0, G)) / 1.8`` at ``i = n + 1`` (the original's ``len(traj_hist)``), not clamped, so a
trial that ends short of a goal gives it a negative beta. A method without betas (NA,
PBA: the joint table was never saved) logs the uniform prior on every row.
"""

from __future__ import annotations

import numpy as np

from casa_core.robot.kinematics import link7_position

COST_PER_METRE = 50 / 0.22
SUB_SCALE = 1.8
POSE_PENALTY_PER_METRE = 100.0
PBA_DISTANCE = 0.55
METHODS = ("CASA", "PBA", "NA")


def link7_waypoints(q_waypoints) -> np.ndarray:
    """Link-7 positions ``(m+1, 3)`` of joint waypoints ``(m+1, 7)`` in radians."""
    return np.array([link7_position(np.asarray(q, dtype=float)) for q in q_waypoints])


def path_cost(points) -> float:
    """``50 / 0.22`` times the length of the polyline through ``points`` ``(n, 3)``."""
    segments = np.diff(np.asarray(points, dtype=float), axis=0)
    return COST_PER_METRE * float(np.sum(np.linalg.norm(segments, axis=1)))


def suboptimality(waypoints, goals, i, *, defects: bool) -> np.ndarray:
    """``S`` ``(g,)`` at step ``i``: clamped at 0 unless ``defects`` (which adds the penalty)."""
    w = np.asarray(waypoints, dtype=float)[: i + 1]
    goals = np.asarray(goals, dtype=float)
    prefix = path_cost(w)
    if defects:
        prefix += POSE_PENALTY_PER_METRE * float(np.linalg.norm(w[i] - goals[0]))
    to_go = np.array([path_cost([w[i], goal]) for goal in goals])
    optimal = np.array([path_cost([w[0], goal]) for goal in goals])
    sub = (prefix + to_go - optimal) / SUB_SCALE
    return sub if defects else np.maximum(sub, 0.0)


def map_beta(sub, i, *, defects: bool) -> np.ndarray:
    """``beta = 3.5 i / (S + 4)``, with ``floor(3.5 i) = (7 i) // 2`` if ``defects``."""
    numerator = float((7 * i) // 2) if defects else 3.5 * i
    return numerator / (np.asarray(sub, dtype=float) + 4.0)


def belief(sub, beta, i, *, defects: bool) -> np.ndarray:
    """Posterior ``(g,)`` over goals, uniform prior, given ``S`` and ``beta`` per goal."""
    sub = np.asarray(sub, dtype=float)
    beta = np.broadcast_to(np.asarray(beta, dtype=float), sub.shape)
    if defects:  # linear space, exponent 3 i; nan where 0/0 or inf * 0
        with np.errstate(all="ignore"):
            likelihood = np.exp(-beta * sub) * (beta / (2 * np.pi)) ** (3 * i)
            return likelihood / np.sum(likelihood)
    if i == 0:
        log_likelihood = np.zeros_like(sub)
    else:
        beta_sub = beta * sub
        beta_sub = np.where(beta_sub == 0, 0.0, beta_sub)
        log_likelihood = -beta_sub + 3.5 * i * np.log(beta / (2 * np.pi))
    peak = np.max(log_likelihood)
    log_norm = peak + np.log(np.sum(np.exp(log_likelihood - peak)))
    return np.exp(log_likelihood - log_norm)


def step(waypoints, goals, i, *, defects: bool) -> dict:
    """``{"sub", "beta", "belief"}``, each ``(g,)``, of step ``i`` over ``waypoints[0..i]``."""
    sub = suboptimality(waypoints, goals, i, defects=defects)
    beta = map_beta(sub, i, defects=defects)
    return {"sub": sub, "beta": beta, "belief": belief(sub, beta, i, defects=defects)}


def alpha(result, waypoint, goals, i, *, defects: bool, method: str) -> tuple[float, np.ndarray]:
    """``(alpha, belief the method uses)`` of one step's ``result`` (from :func:`step`)."""
    if method == "NA":
        return 1.0, result["belief"]
    if method == "CASA":
        likely = int(np.argmax(result["belief"]))
        with np.errstate(divide="ignore"):
            share = 1.0 / result["beta"][likely]  # beta = 0 -> inf -> 1
        return float(np.clip(share, 0.0, 1.0)), result["belief"]
    if method == "PBA":
        pba_belief = belief(result["sub"], 1.0, i, defects=defects)
        goal = np.asarray(goals, dtype=float)[int(np.argmax(pba_belief))]
        distance = float(np.linalg.norm(np.asarray(waypoint, dtype=float) - goal))
        return float(np.clip(distance / PBA_DISTANCE, 0.0, 1.0)), pba_belief
    raise ValueError(f"method must be one of {METHODS}, not {method!r}")


def final_step(waypoints, goals, *, defects: bool) -> dict:
    """``{"sub", "beta", "belief"}`` of the step after the trial, over every waypoint."""
    w = np.asarray(waypoints, dtype=float)
    goals = np.asarray(goals, dtype=float)
    i = len(w)
    penalty = POSE_PENALTY_PER_METRE * np.linalg.norm(goals - w[-1], axis=1)
    optimal = np.array([path_cost([w[0], goal]) for goal in goals])
    sub = (path_cost(w) + penalty - optimal) / SUB_SCALE
    if not defects:
        sub = np.maximum(sub, 0.0)
    beta = map_beta(sub, i, defects=defects)
    return {"sub": sub, "beta": beta, "belief": belief(sub, beta, i, defects=defects)}


def histories(waypoints, goals, *, defects: bool, method: str, at=None) -> dict:
    """The logged rows: timed step ``k`` over ``waypoints[0..at[k]]`` (default ``at`` =
    1..n-1 for waypoints 0..n), then the final step: ``sub``, ``beta`` (MAP), ``belief``
    (the method's) ``(m+1, g)``; ``alpha`` ``(m,)`` of the timed steps."""
    waypoints = np.asarray(waypoints, dtype=float)
    at = range(1, len(waypoints) - 1) if at is None else at
    rows = {"sub": [], "beta": [], "belief": [], "alpha": []}
    for i in at:
        result = step(waypoints, goals, i, defects=defects)
        share, used = alpha(result, waypoints[i], goals, i, defects=defects, method=method)
        rows["sub"].append(result["sub"])
        rows["beta"].append(result["beta"])
        rows["belief"].append(used)
        rows["alpha"].append(share)
    final = final_step(waypoints, goals, defects=defects)
    for key in ("sub", "beta", "belief"):
        rows[key].append(final[key])
    return {key: np.array(value, dtype=float) for key, value in rows.items()}


def session_of_trial(frame, names, *, logged=True, speed=0.05, rot_speed=0.5) -> dict:
    """The original-format arrays of a casa trial measured at link 7 (``names``: its goals).

    A key's command ``joy_cmd`` is the joint velocity that moves link 7 at the key's
    velocity (``speed`` along its axis; the pseudo-inverse of link 7's Jacobian), plus
    ``rot_speed`` on joint 7 for a rotate key (``rot+`` backwards), so that the importer's
    reading of keys from ``joy_cmd`` gives the trial's keys back. The waypoints
    ``traj_hist`` are the joint angles every 0.5 s (10 ticks); timed step k at waypoint
    k + 1 holds the trial's betas and beliefs there, the last waypoint the final step
    (the trial's last values). Without ``logged`` (NA, PBA) the beliefs are the uniform
    prior on every row and there are no betas.
    """
    from casa_core.robot.keys import KEY_DIRECTIONS, parse_keys
    from casa_core.robot.kinematics import jacobian

    t = frame["t"].to_numpy(dtype=float)
    q = frame[[f"q{i}" for i in range(1, 8)]].to_numpy(dtype=float)
    commands = np.zeros_like(q)
    for row, (angles, cell) in enumerate(zip(q, frame["keys"], strict=True)):
        direction = sum((KEY_DIRECTIONS[key] for key in parse_keys(cell)), np.zeros(4))
        if np.any(direction[:3]):
            link7 = jacobian(angles, "link7")[:3]
            commands[row] = np.linalg.pinv(link7) @ (speed * direction[:3])
        commands[row, 6] -= rot_speed * direction[3]
    waypoints = np.arange(0, len(t), 10)
    rows = waypoints[1:]  # the timed steps at waypoints 1..n-1, then the final step
    if logged:
        belief = frame[[f"belief:{name}" for name in names]].to_numpy(dtype=float)[rows]
        beta = frame[[f"beta:{name}" for name in names]].to_numpy(dtype=float)[rows]
    else:
        belief, beta = np.full((len(rows), len(names)), 1.0 / len(names)), np.zeros(0)
    return {
        "cmdpos_time": t,
        "curr_pos": q,
        "joy_cmd": commands,
        "traj_hist": q[waypoints],
        "inf_start_time": t[rows[:-1]],
        "belief_hist": belief,
        "beta_hist": beta,
        "start_T": np.array(1.6e9),
    }
