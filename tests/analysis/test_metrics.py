"""Metrics against hand-computed trajectories; each expected number is derived in its test."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.analysis import effort, metrics
from casa_core.assist import tasks
from tests.io.test_logs_synthetic import SCENE, keys_of_motion

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
    assert effort.key_presses(keys) == 4
    # Held per tick: 0 1 1 0 2 1 2.
    assert effort.key_ticks(keys) == 7
    # Keys held at the first tick are pressed then.
    assert effort.key_presses(["rot+ rot-", "rot+"]) == 2


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


# --------------------------------------------------------------------------- time limit, success


@pytest.mark.parametrize(
    "duration, limit, expected",
    [
        (40.0, 40.0, True),  # the loop's last tick is at the limit
        (39.97, 40.0, True),  # a logged clock: 0.03 s short, within one 0.05 s tick
        (39.95, 40.0, False),  # one whole tick before the limit: the operator was done
        (12.0, 40.0, False),
        (12.0, None, None),  # the log does not say its limit
    ],
)
def test_timed_out_means_the_last_tick_within_one_tick_of_the_limit(duration, limit, expected):
    assert metrics.timed_out(duration, limit, dt=DT) is expected


def _ending_at(task: str, offset=(0.0, 0.0, 0.0), rot: float | None = None) -> np.ndarray:
    """A two-row trial from the start to the task's intended end moved by ``offset``."""
    intended = tasks.intended_trajectory(task, SCENE)
    end = intended[-1].copy()
    end[0] += 5.0  # later than the reference: only where it ends counts
    end[1:4] += offset
    if rot is not None:
        end[4] = rot
    return np.array([intended[0], end])


@pytest.mark.parametrize(
    "task, offset, rot, expected",
    [
        # Goals: within SUCCESS_RADIUS = 0.05 m of the goal; the rotation is not judged.
        ("known_goal", (0.0, 0.04, 0.0), None, True),
        ("known_goal", (0.03, 0.04, 0.0), None, True),  # 3-4-5: exactly 0.05 m counts
        ("known_goal", (0.0, 0.0, 0.06), None, False),
        ("known_goal", (0.0, 0.0, 0.0), 1.0, True),
        ("unknown_goal", (0.0, -0.051, 0.0), None, False),
        # The pour (tilt 1.8 rad): also within POUR_TILT_TOLERANCE = 0.2 rad of the tilt.
        ("unknown_skill", (0.0, 0.0, 0.0), 1.65, True),  # 0.15 rad short
        ("unknown_skill", (0.0, 0.0, 0.0), 1.55, False),  # 0.25 rad short
        ("unknown_skill", (0.0, 0.0, 0.0), 0.0, False),  # carried there, never poured
        ("unknown_skill", (0.0, 0.06, 0.0), 1.8, False),  # poured 6 cm off
    ],
)
def test_success_is_ending_at_the_intended_end(task, offset, rot, expected):
    intended = tasks.intended_trajectory(task, SCENE)
    assert metrics.task_success(_ending_at(task, offset, rot), intended) is expected


def test_success_radius_and_tilt_tolerance():
    # The documented values (docs/data-contracts.md): 5 cm and 0.2 rad.
    assert metrics.SUCCESS_RADIUS == 0.05 and metrics.POUR_TILT_TOLERANCE == 0.2
    # The pour's tilt stays past horizontal (pi / 2) at the tolerance's edge.
    assert SCENE.pouring.tilt - metrics.POUR_TILT_TOLERANCE > np.pi / 2


def test_trial_metrics_of_a_trial_that_ran_out_of_time():
    # Standing still at the start for 40 s at 20 Hz (801 ticks) under a 40 s limit: it
    # ran out of time and failed (0.27 m from the green goal).
    t = np.arange(801) * DT
    start = SCENE.start_state
    frame = pd.DataFrame({"t": t, "x": start[0], "y": start[1], "z": start[2], "rot": 0.0})
    frame["keys"] = ""
    intended = tasks.intended_trajectory("known_goal", SCENE)
    result = metrics.trial_metrics(frame, intended, dt=DT, max_duration=40.0)
    assert result["timed_out"] is True and result["success"] is False
    assert metrics.trial_metrics(frame, intended, dt=DT)["timed_out"] is None
    assert metrics.trial_metrics(frame, intended, dt=DT, max_duration=60.0)["timed_out"] is False


def test_success_radius_is_far_below_the_distance_between_task_ends():
    # docs/data-contracts.md: the nearest two ends of different tasks are 22 cm apart
    # (green goal and pouring position), so stopping at another task's end never succeeds.
    ends = {
        task: tasks.intended_trajectory(task, SCENE)[-1, 1:4]
        for task in ("known_goal", "unknown_goal", "unknown_skill")
    }
    gaps = [np.linalg.norm(ends[a] - ends[b]) for a in ends for b in ends if a < b]
    assert min(gaps) == pytest.approx(0.22, abs=0.005)
    assert min(gaps) > 4 * metrics.SUCCESS_RADIUS
