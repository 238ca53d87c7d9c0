"""StageClock: CPU time charged to the functions of each stage, counted against closed forms."""

from __future__ import annotations

import math
import time
import types

import pybullet
import pytest

from casa_core.bench import protocol as bench_protocol
from casa_core.bench import stages, trial
from casa_core.robot.sim import ArmSimulation


def busy(seconds: float) -> None:
    """Spin for ``seconds`` of this process's CPU time."""
    until = time.process_time() + seconds
    while time.process_time() < until:
        pass


def test_a_stage_is_charged_its_calls_and_the_function_is_put_back():
    module = types.SimpleNamespace(work=busy)
    clock = stages.StageClock([(module, "work", "work")])
    with clock:
        for _ in range(4):
            module.work(0.02)
    assert module.work is busy
    assert clock.calls["work"] == 4
    assert clock.seconds["work"] == pytest.approx(0.08, abs=0.01)


def test_an_inner_stage_is_not_counted_twice():
    module = types.SimpleNamespace()
    module.inner = busy
    module.outer = lambda: (busy(0.03), module.inner(0.05))
    clock = stages.StageClock([(module, "outer", "outer"), (module, "inner", "inner")])
    with clock:
        module.outer()
    assert clock.seconds["inner"] == pytest.approx(0.05, abs=0.01)
    assert clock.seconds["outer"] == pytest.approx(0.03, abs=0.01)


def test_the_functions_are_put_back_after_an_error():
    sqrt = math.sqrt
    with pytest.raises(ValueError), stages.StageClock([(math, "sqrt", "roots")]):
        math.sqrt(-1.0)
    assert math.sqrt is sqrt


def test_the_pybullet_clock_sees_every_physics_substep(scene):
    # A trial of n ticks steps the physics n times `substeps` (the simulation's setting).
    with ArmSimulation(scene) as sim:
        with stages.StageClock([(pybullet, "stepSimulation", "step")]) as clock:
            for _ in range(10):
                sim.step([0.01, 0.0, 0.0, 0.0])
        assert clock.calls["step"] == 10 * sim.settings.substeps
    with stages.StageClock.pybullet() as everything:
        trial.trial_physics_cpu_s(scene, duration=1.0, repeats=1)
    # Every pybullet function is wrapped, also the ones the simulation calls to connect.
    assert everything.calls["pybullet"] > 20 * 2


def test_a_trial_costs_more_than_its_physics(scene):
    physics = trial.trial_physics_cpu_s(scene, duration=2.0, repeats=1)
    factor, _ = trial.trial_realtime_factor(scene, duration=2.0, repeats=1)
    assert 0 < physics < 2.0 / factor  # the trial's CPU holds its physics


def test_the_protocol_split_adds_up_to_the_protocol(scene):
    from casa_core.config import DEFAULT_CONFIG, load_config

    config = load_config(DEFAULT_CONFIG)
    config["simulation"]["max_duration"] = 2.0  # short trials; learning still runs
    measured = bench_protocol.participant_benchmark(scene, config=config, participants=(0,))
    split = measured["protocol_split_s"]
    assert list(split) == ["trials", "learning", "logging", "rest"]
    assert sum(split.values()) == pytest.approx(measured["participant_cpu_s"], rel=1e-9)
    assert all(seconds > 0 for seconds in split.values()), split
    # The learning stage is the protocol's own learning steps, timed around the same calls.
    assert split["learning"] == pytest.approx(sum(measured["irl_s_all"]), rel=0.05)
