"""Metrics against hand-computed trajectories; each expected number is derived in its test."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from test_logs_synthetic import SCENE, keys_of_motion

from casa_core import metrics, tasks

DT = 0.05
# Intended: 0.05 m along x in 1 s (20 ticks), then holding there.
INTENDED = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.05, 0.0, 0.0, 0.0]])


def line(t_end: float, x_end: float, n: int, rot_end: float = 0.0) -> np.ndarray:
    t = np.linspace(0.0, t_end, n)
    zeros = np.zeros(n)
    return np.column_stack([t, x_end * t / t_end, zeros, zeros, rot_end * t / t_end])


def test_error_is_zero_on_the_intended_trajectory():
    intended = tasks.intended_trajectory("unknown_skill", SCENE)
    assert metrics.trajectory_error(intended, intended, dt=DT) == (0.0, 0.0)


def test_constant_offset_gives_ticks_times_offset_squared():
    # Grid s_j = 0, 0.05, ..., 1.0: 21 points, each off by c in y and r in rot.
    c, r = 0.01, 0.2
    executed = line(1.0, 0.05, 21)
    executed[:, 2] += c
    executed[:, 4] += r
    error, error_rot = metrics.trajectory_error(executed, INTENDED, dt=DT)
    assert error == pytest.approx(21 * c**2, rel=1e-12)
    assert error_rot == pytest.approx(21 * r**2, rel=1e-12)


def test_standing_still_is_compared_with_the_whole_reference():
    # Executed stays at the start for 1 s: differences 0.05 j/20, j = 0..20,
    # sum = 0.05^2 / 400 * sum_j j^2 = 0.0025 / 400 * 2870.
    executed = np.array([[0.0, 0, 0, 0, 0], [1.0, 0, 0, 0, 0]])
    error, _ = metrics.trajectory_error(executed, INTENDED, dt=DT)
    assert error == pytest.approx(0.0025 / 400 * 2870, rel=1e-12)


def test_half_speed_lags_behind_a_reference_that_waits_at_its_goal():
    # Executed reaches x = 0.05 at t = 2 s. On s = j/20 for j = 0..40 the
    # difference is -0.025 s for s <= 1 and -0.025 (2 - s) after, so the sum is
    # 0.025^2 / 400 * (sum_{j<=20} j^2 + sum_{k<=19} k^2) = 0.000625 / 400 * (2870 + 2470).
    executed = line(2.0, 0.05, 41)
    error, _ = metrics.trajectory_error(executed, INTENDED, dt=DT)
    assert error == pytest.approx(0.000625 / 400 * (2870 + 2470), rel=1e-12)
    # Aligned in time, not in space: the same path at the reference's pace has no error.
    assert metrics.trajectory_error(line(1.0, 0.05, 21), INTENDED, dt=DT)[0] == pytest.approx(0.0)


def test_efficiency_cost_of_constant_and_uneven_velocities():
    # Constant 0.05 m/s over n rows: (n - 1) intervals of 0.05^2.
    executed = line(1.0, 0.05, 21)
    assert metrics.efficiency_cost(executed[:, 0], executed[:, 1:4]) == pytest.approx(
        20 * 0.0025, rel=1e-12
    )
    # Uneven: 0.1 m in 0.5 s (0.2 m/s), then 0.3 m in 1 s (0.3 m/s): 0.04 + 0.09.
    t = np.array([0.0, 0.5, 1.5])
    p = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.3, 0]])
    assert metrics.efficiency_cost(t, p) == pytest.approx(0.13, rel=1e-12)
    assert metrics.efficiency_cost(t[:1], p[:1]) == 0.0


def test_key_presses_count_press_events_and_ticks_count_held_keys():
    keys = ["", "x+", "x+", "", "x+ y+", "y+", "y+ z-"]
    # Presses: x+ at tick 1; x+ and y+ at tick 4 (x+ was released at 3); z- at 6.
    assert metrics.key_presses(keys) == 4
    # Held per tick: 0 1 1 0 2 1 2.
    assert metrics.key_ticks(keys) == 7
    # Keys held at the first tick are pressed then.
    assert metrics.key_presses(["rot+ rot-", "rot+"]) == 2


def _trials(efforts: dict) -> pd.DataFrame:
    rows = [
        {"participant": p, "task": t, "method": m, "phase": ph, "effort": e}
        for (p, t, m, ph), e in efforts.items()
    ]
    return pd.DataFrame(rows)


def test_relative_effort_divides_by_the_same_participants_na_on_the_same_task():
    trials = _trials(
        {
            ("p1", "unknown_goal", "NA", "before_learning"): 40,
            ("p1", "unknown_goal", "CASA", "after_learning"): 10,
            ("p1", "unknown_goal", "NA", "demonstration"): 99,  # not the reference
            ("p2", "unknown_goal", "NA", "before_learning"): 20,
            ("p2", "unknown_goal", "PBA", "before_learning"): 30,
            ("p2", "known_goal", "CASA", "no_misspecification"): 5,  # no NA on this task
            ("p3", "known_goal", "NA", "no_misspecification"): 0,  # undefined ratio
        }
    )
    relative = metrics.relative_effort(trials).tolist()
    expected = [1.0, 0.25, 99 / 40, 1.0, 1.5, np.nan, np.nan]
    np.testing.assert_allclose(relative, expected)


def test_relative_effort_refuses_two_references():
    trials = _trials(
        {
            ("p1", "known_goal", "NA", "no_misspecification"): 4,
            ("p1", "known_goal", "CASA", "no_misspecification"): 2,
        }
    )
    trials = pd.concat([trials, trials.iloc[[0]]])
    with pytest.raises(ValueError, match="p1.*known_goal"):
        metrics.relative_effort(trials)


def test_trial_metrics_of_a_logged_trial():
    # The intended trajectory replayed at its own samples, with the keys of its motion.
    intended = tasks.intended_trajectory("known_goal", SCENE)
    frame = pd.DataFrame(intended, columns=["t", "x", "y", "z", "rot"])
    frame["keys"] = keys_of_motion(intended[:, 1:])
    result = metrics.trial_metrics(frame, intended, dt=DT)
    assert result["error"] == pytest.approx(0.0, abs=1e-20)
    assert result["duration"] == intended[-1, 0]
    # known_goal is one straight segment: the same three keys held until the last tick.
    assert result["effort"] == 3
    assert result["effort_ticks"] == 3 * (len(frame) - 1)
    # Driven at teleop.speed throughout (the last, shorter interval too): (n - 1) speed^2.
    speed = SCENE.teleop.speed
    assert result["efficiency"] == pytest.approx((len(frame) - 1) * speed**2, rel=1e-9)
    assert result["ticks"] == len(frame)
