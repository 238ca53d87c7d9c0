"""The assistant's tick on live inputs (:class:`AssistLoop`), without DDS: the fault rules."""

from __future__ import annotations

import json

import numpy as np
import pytest

from casa_core.assist.presets import preset
from casa_core.robot import kinematics as kin
from casa_core.ros2.loop import AssistLoop
from casa_core.ros2.messages import MAX_COMMAND_AGE, MAX_JOINT_STATE_AGE


@pytest.fixture
def loop(scene):
    logged = []
    loop = AssistLoop(
        scene,
        task="known_goal",
        method="CASA",
        participant="P03",
        phase="no_misspecification",
        inference=preset("casa"),
        log=logged.append,
    )
    loop.logged = logged
    yield loop
    loop.close()


def start_q(scene):
    return kin.inverse_kinematics(np.asarray(scene.start_state[:3]), scene.start_state[3])


def test_a_fresh_command_moves_the_arm_the_way_the_user_pushes(loop, scene):
    q = start_q(scene)
    tick = loop.step(1.0, q, 1.0, np.array([0.05, 0, 0, 0]), 1.0)
    assert tick.fault is None and tick.row["keys"] == "x+"
    # The joint velocities move the tool along +x (the kinematics' Jacobian).
    velocity = kin.jacobian(q)[:3] @ tick.qdot
    assert velocity[0] > 0.04 and abs(velocity[1]) < 0.01
    state = json.loads(tick.state_text)
    assert state["alpha"] == 1.0 and state["fault"] is None


@pytest.mark.parametrize(
    ("case", "fault"),
    [
        ("user silent", "user-silent"),
        ("user invalid", "user-invalid"),
        ("joint state stale", "joint-state-stale"),
        ("joint state invalid", "joint-state-invalid"),
    ],
)
def test_a_fault_stops_the_robot_and_is_logged_once(loop, scene, case, fault):
    q, push = start_q(scene), np.array([0.05, 0.05, -0.05, 0])  # the keys toward green
    for i in range(40):  # 2 s of assistance toward green: alpha falls below 1
        t = i * 0.05
        loop.step(t, q, t, push, t)
        q = q + 0.05 * loop.model.joint_velocities(push)
    assert loop.assistant.latest.alpha < 1.0
    now = 2.0
    inputs = {"q": q, "q_time": now, "action": push, "action_time": now}
    if case == "user silent":
        inputs["action_time"] = now - MAX_COMMAND_AGE - 0.01
    elif case == "joint state stale":
        inputs["q_time"] = now - MAX_JOINT_STATE_AGE - 0.01
    extra = {"user invalid": {"user_fault": fault}, "joint state invalid": {"joint_fault": fault}}
    for _ in range(3):
        tick = loop.step(now, **inputs, **extra.get(case, {}))
        now += 0.05
    assert tick.fault == fault and not tick.qdot.any()
    assert tick.row["alpha"] == 1.0 and tick.row["keys"] == ""
    assert json.loads(tick.state_text)["fault"] == fault
    assert [line for line in loop.logged if line.startswith(fault)] == [loop.logged[-1]]
    # Back to health: assisting again, said once.
    tick = loop.step(now, q, now, push, now)
    assert tick.fault is None and loop.logged[-1] == f"{fault} over: assisting again"


def test_no_joint_state_yet_logs_nothing(loop):
    tick = loop.step(0.0, None, None, None, None)
    assert tick.fault == "joint-state-stale" and tick.row == {} and not tick.qdot.any()
    assert loop.result().frame.empty


def test_a_command_between_ticks_is_answered_with_the_next_ticks_blend(loop, scene):
    q, push = start_q(scene), np.array([0.05, 0.05, -0.05, 0])
    assert loop.respond(0.0, q, 0.0, push) is None  # before the first tick: the tick decides
    for i in range(25):  # past two inference steps: the robot has a share
        t = i * 0.05
        loop.step(t, q, t, push, t)
        q = q + 0.05 * loop.model.joint_velocities(push)
    assert loop.assistant.latest.alpha < 1.0
    evidence = loop.assistant._robot_motion.copy()
    rows = len(loop.rows)
    now = 25 * 0.05
    # Answered at the tick's own time and inputs, the command is the tick's command.
    answer = loop.respond(now, q, now, push)
    assert len(loop.rows) == rows and np.array_equal(loop.assistant._robot_motion, evidence)
    tick = loop.step(now, q, now, push, now)
    np.testing.assert_allclose(answer.qdot, tick.qdot, rtol=0, atol=1e-12)
    np.testing.assert_allclose(answer.blended, tick.command.blended, rtol=0, atol=1e-12)
    # Under a fault, or with a stale joint state, the node waits for the tick.
    assert loop.respond(now + 0.01, q, now + 0.01 - MAX_JOINT_STATE_AGE - 0.01, push) is None
    loop.step(now + 0.05, q, now + 0.05, push, now + 0.05 - MAX_COMMAND_AGE - 0.01)
    assert loop.fault == "user-silent" and loop.respond(now + 0.06, q, now + 0.06, push) is None


def test_answering_between_ticks_leaves_the_recorded_trial_as_it_was(scene):
    # Two loops fed the same ticks; one also answers two commands between every two ticks.
    def run(answering: bool):
        loop = AssistLoop(
            scene,
            task="known_goal",
            method="CASA",
            participant="P03",
            phase="no_misspecification",
            inference=preset("casa"),
        )
        q, push = start_q(scene), np.array([0.05, 0.05, -0.05, 0])
        for i in range(45):
            t = i * 0.05
            tick = loop.step(t, q, t, push, t)
            if answering:
                for late in (0.01, 0.03):
                    loop.respond(t + late, q, t, push * 0.5)
            q = q + 0.05 * tick.qdot
        loop.close()
        return loop.result().frame

    quiet, answering = run(False), run(True)
    assert quiet["alpha"].min() < 1.0
    assert quiet.equals(answering)


def test_learned_intents_join_the_known_goals(scene, tmp_path):
    from casa_core.bench.suite import untrained_neural_intent
    from casa_core.learning import IRLConfig
    from casa_core.learning.library import save_intent
    from casa_core.planning import PlannerConfig

    # A short planner keeps the test fast; what the node knows is under test, not the plan.
    quick = PlannerConfig(iterations=20, warm_iterations=5)
    path = save_intent(
        tmp_path / "library",
        untrained_neural_intent(scene, seed=1, planner=quick),
        task="unknown_goal",
        participant="P03",
        seed=1,
        demos=[],
        history=[],
        config=IRLConfig(),
    )
    loop = AssistLoop(
        scene,
        task="unknown_goal",
        method="CASA",
        participant="P03",
        phase="after_learning",
        inference=preset("casa"),
        learned=[path],
    )
    try:
        assert loop.meta["intents"] == ["green", "purple", "neural"]
        q, push = start_q(scene), np.array([0.0, 0.05, 0.0, 0.0])
        for i in range(12):
            t = i * 0.05
            tick = loop.step(t, q, t, push, t)
            q = q + 0.05 * tick.qdot
        state = json.loads(tick.state_text)
        assert set(state["beta"]) == {"green", "purple", "neural"}
        assert "beta:neural" in loop.result().frame
    finally:
        loop.close()
    broken = tmp_path / "broken.intent.json"
    broken.write_text("{", encoding="utf-8")
    with pytest.raises(ValueError, match="broken.intent.json"):
        AssistLoop(
            scene,
            task="unknown_goal",
            method="CASA",
            participant="P03",
            phase="after_learning",
            inference=preset("casa"),
            learned=[broken],
        )
