"""``casa bench`` helpers (the benchmark itself is not a test; its numbers go in reports)."""

import numpy as np
import pytest

from casa_core import bench
from casa_core.scene import load_scene


@pytest.fixture(scope="module")
def scene():
    return load_scene()


def test_linear_fit_recovers_an_exact_line_and_flags_a_curve():
    sizes = [2, 4, 8, 16, 32, 64]
    a, b, r2 = bench.linear_fit_r2(sizes, [30 + 5 * n for n in sizes])
    assert (a, b, r2) == pytest.approx((30, 5, 1))
    assert bench.linear_fit_r2(sizes, [n**2 for n in sizes])[2] < 0.99


def test_goal_intents_start_with_the_scene_goals_and_are_seeded(scene):
    first = bench.goal_intents(scene, 8, np.random.default_rng(1))
    again = bench.goal_intents(scene, 8, np.random.default_rng(1))
    assert [i.name for i in first][:3] == ["green", "purple", "red"]
    assert len(first) == 8
    np.testing.assert_array_equal(first[-1].goal, again[-1].goal)
    assert [i.name for i in bench.goal_intents(scene, 2, np.random.default_rng(1))] == [
        "green",
        "purple",
    ]


def test_bench_trajectory_covers_the_horizon_every_half_second(scene):
    states = bench.bench_trajectory(scene)
    assert states.shape == (31, 4)
    np.testing.assert_allclose(states[0], scene.start_state)
    np.testing.assert_allclose(states[-1, :3], scene.goals["red"])


def test_time_assistance_step_and_table(scene):
    rng = np.random.default_rng(0)
    intents = bench.goal_intents(scene, 3, rng)
    step = bench.time_assistance_step(
        lambda: intents, bench.bench_trajectory(scene), rng, repeats=3
    )
    assert step > 0
    with pytest.raises(ValueError, match="needs > 40"):
        bench.time_assistance_step(lambda: intents, np.zeros((10, 4)), rng, late_step=40)
    results = {
        "step_us_goal3": step,
        "step_us_neural1": None,
        "scaling": [{"n_intents": n, "step_us": 10.0 * n} for n in (2, 4, 8)],
        "trial_realtime_factor": 150.0,
    }
    table = bench.format_table(results)
    assert "n/a" in table and "150.0" in table and "R^2" in table


def test_trial_realtime_factor_runs_the_unknown_goal_trial(scene):
    cpu, wall = bench.trial_realtime_factor(scene, duration=1.0, repeats=1)
    assert cpu > 0 and wall > 0
