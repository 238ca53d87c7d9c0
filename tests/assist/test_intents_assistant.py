"""Goal intents and the assistant: closed forms and the behaviour the paper describes.

Closed forms are derived in the GoalIntent docstring; each test states the arithmetic.
"""

import numpy as np
import pytest

from casa_core.assist.assistant import Assistant
from casa_core.assist.intents import GoalIntent

START = np.array([0.0, 0.0, 0.0, 0.0])
GOAL = np.array([0.3, 0.4, 0.0])  # 0.5 m from START


def straight_line(goal, n_steps, speed=0.05, dt=0.5, start=START):
    """States every dt along the straight line at full speed, stopping at the goal."""
    offset = goal - start[:3]
    d = np.linalg.norm(offset)
    travelled = np.minimum(speed * dt * np.arange(n_steps + 1), d)
    positions = start[:3] + travelled[:, None] * offset / d
    return np.column_stack([positions, np.zeros(n_steps + 1)])


@pytest.mark.parametrize("cost", ["path_length", "distance_sum"])
def test_straight_line_to_the_goal_has_zero_suboptimality(cost):
    intent = GoalIntent("g", GOAL, cost=cost)
    horizon = 15.0
    optimal = intent.cost_to_go(START, horizon)
    states = straight_line(GOAL, 30)
    for t in range(1, 31):
        prefix = intent.prefix_cost(states[: t + 1])
        to_go = intent.cost_to_go(states[t], horizon - 0.5 * t)
        assert prefix + to_go - optimal == pytest.approx(0.0, abs=1e-9)


def test_path_length_cost_to_go_is_the_straight_line_whatever_the_time_left():
    intent = GoalIntent("g", GOAL, cost="path_length", scale=227.0)
    # 0.5 m at 227 per metre, with time enough (10 s at 0.05 m/s) or not
    for time_left in (15.0, 4.0, 0.0):
        assert intent.cost_to_go(START, time_left) == pytest.approx(113.5)
    # the default scale is the original's 50 / 0.22 per metre
    assert GoalIntent("g", GOAL).cost_to_go(START, 15.0) == pytest.approx(0.5 * 50 / 0.22)


def test_distance_sum_closed_form_matches_its_optimal_trajectory():
    intent = GoalIntent("g", GOAL, cost="distance_sum", scale=1.0)
    # step s = 0.025 m, d = 0.5 m: m = 20 steps -> dt * (20 * 0.5 - 0.025 * 20 * 21 / 2)
    assert intent.cost_to_go(START, 15.0) == pytest.approx(0.5 * (10.0 - 5.25))
    # and the cost summed along the optimal trajectory agrees, also when time runs out
    for time_left in (15.0, 4.0, 0.0):
        trajectory = intent.optimal_trajectory(START, time_left)
        assert intent.prefix_cost(trajectory) == pytest.approx(intent.cost_to_go(START, time_left))


def test_optimal_trajectory_is_the_straight_line_at_speed():
    intent = GoalIntent("g", GOAL)
    trajectory = intent.optimal_trajectory(START, 15.0)
    assert trajectory.shape == (31, 4)  # T = 15 s, dt = 0.5 s: 31 waypoints
    steps = np.linalg.norm(np.diff(trajectory[:, :3], axis=0), axis=1)
    assert steps.max() == pytest.approx(0.025)
    np.testing.assert_allclose(trajectory[-1, :3], GOAL)


def test_goal_intent_rejects_bad_parameters():
    with pytest.raises(ValueError, match="cost must be one of"):
        GoalIntent("g", GOAL, cost="euclid")
    with pytest.raises(ValueError, match="goal of intent 'g'"):
        GoalIntent("g", [0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="speed of intent 'g' must be a positive number, got 0"):
        GoalIntent("g", GOAL, speed=0)
    with pytest.raises(ValueError, match="dt of intent 'g' must be a positive number, got -0.5"):
        GoalIntent("g", GOAL, dt=-0.5)


def test_goal_intent_takes_its_options_by_keyword_only():
    with pytest.raises(TypeError):
        GoalIntent("g", GOAL, "distance_sum")


def make_assistant(arbitration="confidence", **kwargs):
    intents = [GoalIntent("green", GOAL), GoalIntent("purple", [-0.4, 0.1, 0.2])]
    assistant = Assistant(intents, arbitration=arbitration, **kwargs)
    assistant.reset(START)
    return assistant


def test_known_goal_confidence_rises_and_alpha_falls():
    # Paper Sec. IV-C: moving optimally to a known goal, its beta_hat rises and alpha falls.
    assistant = make_assistant()
    steps = [assistant.update(s, user_input=True) for s in straight_line(GOAL, 16)[1:]]
    green = [step.beta["green"] for step in steps]
    assert (np.diff(green) > 0).all()
    assert steps[-1].beta["purple"] < 1.0 < steps[-1].beta["green"]
    assert all(step.intent == "green" for step in steps)
    alphas = [step.alpha for step in steps]
    assert (np.diff(alphas) <= 1e-12).all() and alphas[-1] < 0.2
    assert not steps[-1].misspecified


def test_unknown_goal_is_flagged_misspecified_and_casa_gives_control_back():
    # Moving to a goal far from both known ones: every beta_hat drops below epsilon.
    assistant = make_assistant()
    unknown = np.array([0.0, -0.5, 0.0])
    steps = [assistant.update(s, user_input=True) for s in straight_line(unknown, 16)[1:]]
    assert steps[-1].misspecified
    assert steps[-1].alpha == 1.0
    # belief arbitration would still hand control to the robot (paper, Fig. alpha_methods)
    assert steps[-1].alpha_by_arbitration["belief"] < steps[-1].alpha


def test_pba_fixes_beta_at_one_for_inference_and_arbitrates_on_distance():
    assistant = make_assistant("distance", pba_distance=0.55)
    step = None
    for state in straight_line(GOAL, 10)[1:]:
        step = assistant.update(state, user_input=True)
    distance = np.linalg.norm(straight_line(GOAL, 10)[-1, :3] - GOAL)
    assert step.alpha == pytest.approx(min(1.0, distance / 0.55))


def test_no_assistance_leaves_the_user_in_control():
    assistant = make_assistant("none")
    for state in straight_line(GOAL, 5)[1:]:
        assistant.update(state, user_input=True)
    user = np.array([0.0, 0.05, 0.0, 0.0])
    np.testing.assert_allclose(assistant.act(straight_line(GOAL, 5)[-1], user), user)


def test_blended_action_moves_toward_the_most_likely_goal_when_confident():
    assistant = make_assistant()
    states = straight_line(GOAL, 12)
    for state in states[1:]:
        assistant.update(state, user_input=True)
    action = assistant.act(states[-1], np.zeros(4))  # no key held: the robot still assists
    direction = (GOAL - states[-1, :3]) / np.linalg.norm(GOAL - states[-1, :3])
    assert action[:3] @ direction > 0
    assert np.linalg.norm(action[:3]) <= 0.05 + 1e-12


def test_assistant_is_incremental_and_matches_batch_costs():
    # the incremental prefix cost equals the batch prefix cost of the whole trajectory
    assistant = make_assistant(lam=0.0, subopt_scale=1.0)
    rng = np.random.default_rng(1)
    states = np.cumsum(rng.normal(scale=0.02, size=(12, 4)), axis=0)
    states[0] = START
    for state in states[1:]:
        step = assistant.update(state, user_input=True)
    intent = assistant.intents[0]
    expected = (
        intent.prefix_cost(states)
        + intent.cost_to_go(states[-1], 15.0 - 0.5 * 11)
        - intent.cost_to_go(START, 15.0)
    )
    assert step.suboptimality["green"] == pytest.approx(max(expected, 0.0))


def test_assistant_guards():
    with pytest.raises(ValueError, match="arbitration must be one of"):
        Assistant([GoalIntent("a", GOAL)], arbitration="magic")
    with pytest.raises(ValueError, match="unique"):
        Assistant([GoalIntent("a", GOAL), GoalIntent("a", -GOAL)])
    with pytest.raises(ValueError, match="pba_distance of Assistant must be a positive number"):
        Assistant([GoalIntent("a", GOAL)], pba_distance=0.0)
    with pytest.raises(ValueError, match="lam of Assistant must be a number >= 0"):
        Assistant([GoalIntent("a", GOAL)], lam=-1.0)
    with pytest.raises(TypeError):
        Assistant([GoalIntent("a", GOAL)], "distance")  # options are keyword-only
    assistant = make_assistant()
    with pytest.raises(ValueError, match="finite"):
        assistant.update([0.0, np.nan, 0.0, 0.0])
    with pytest.raises(ValueError, match="start state must be finite"):
        assistant.reset([0.0, np.inf, 0.0, 0.0])


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        # NaN or a threshold <= 0 would silently switch misspecification detection off
        # (beta_hat >= 0 is never below it); config.schema.yaml asks epsilon > 0 too.
        ("epsilon", np.nan, "epsilon of Assistant must be a positive number, got nan"),
        ("epsilon", 0.0, "epsilon of Assistant must be a positive number, got 0.0"),
        ("epsilon", "high", "epsilon of Assistant must be a positive number, got 'high'"),
        # a negative speed limit would turn u* away from the goal
        ("speed", -0.05, "speed of Assistant must be a positive number, got -0.05"),
        ("rot_speed", np.nan, "rot_speed of Assistant must be a positive number, got nan"),
        ("k", 7.5, "k of Assistant must be an integer, got 7.5"),
        ("lam", "4", "lam of Assistant must be a number >= 0, got '4'"),
        ("lam", np.nan, "lam of Assistant must be a number >= 0, got nan"),
    ],
)
def test_assistant_refuses_out_of_range_options(option, value, message):
    with pytest.raises(ValueError, match=message):
        Assistant([GoalIntent("a", GOAL)], **{option: value})


def test_goal_intent_refuses_a_negative_speed():
    with pytest.raises(ValueError, match="speed of intent 'a' must be a positive number"):
        GoalIntent("a", GOAL, speed=-0.05)


def test_belief_arbitration_with_one_intent_leaves_the_user_in_control():
    # A single intent has belief 1 by construction (no alternative): alpha = 1, as
    # casa_core.model.arbitration.alpha_belief documents, not the robot's full control.
    def one_intent(arbitration):
        assistant = Assistant([GoalIntent("green", GOAL)], arbitration=arbitration)
        assistant.reset(START)
        return assistant

    confidence, belief = one_intent("confidence"), one_intent("belief")
    for state in straight_line(GOAL, 6)[1:]:
        by_confidence, by_belief = (
            confidence.update(state, user_input=True),
            belief.update(state, user_input=True),
        )
        assert by_belief.belief == {"green": 1.0} and by_belief.alpha == 1.0
        assert by_confidence.alpha_by_arbitration["belief"] == 1.0
    assert by_confidence.alpha < 1.0  # confidence arbitration still assists a confident user
    user = np.array([0.05, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(belief.act(state, user), user)


def test_assistant_refuses_a_state_of_another_shape():
    assistant = make_assistant()
    with pytest.raises(ValueError, match="start state must be finite"):
        assistant.reset(np.zeros((2, 4)))
    with pytest.raises(ValueError, match=r"of shape \(4,\)"):
        assistant.update([0.0, 0.0, 0.0])


def test_assistant_needs_reset_before_a_trial():
    assistant = Assistant([GoalIntent("a", GOAL)])
    assert assistant.latest is None
    for call, args in (
        (assistant.update, (START,)),
        (assistant.act, (START, np.zeros(4))),
        (assistant.robot_action, (START,)),
    ):
        with pytest.raises(
            RuntimeError, match=rf"call reset\(start_state\) before {call.__name__}"
        ):
            call(*args)
    assistant.reset(START)
    assert assistant.latest is None
    user = np.array([0.05, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(assistant.act(START, user), user)  # full control before t = 1
    assert assistant.update(START, user_input=True).time == 0.5
    assert assistant.latest is not None


def drive(evidence, arbitration="confidence", switch_after=4, steps=24, tick=0.05):
    """Closed loop: the user heads for green, then from step `switch_after` on for purple.

    Each control tick the user commands full speed toward their goal, the assistant
    blends, and the arm moves by the blended action: the robot's share is real motion.
    """
    assistant = make_assistant(arbitration, evidence=evidence, tick=tick)
    purple = assistant.intents[1].goal
    state, inferences = START.copy(), []
    for k in range(steps):
        goal = GOAL if k < switch_after else purple
        for i in range(10):  # 0.5 s of 0.05 s ticks
            heading = goal - state[:3]
            distance = np.linalg.norm(heading)
            user = np.zeros(4)
            if distance > 1e-9:
                user[:3] = heading / distance * min(0.05, distance / tick)
            state = state + assistant.act(state, user, elapsed_in_step=i * tick) * tick
        inferences.append(assistant.update(state))
    return inferences


@pytest.mark.parametrize("arbitration", ["none", "confidence"])
def test_commanded_evidence_equals_executed_while_the_user_has_full_control(arbitration):
    # With alpha = 1 the arm goes exactly where the user commands, so both evidences
    # are the same trajectory. Under CASA that holds until the robot first assists.
    steps = 24 if arbitration == "none" else 2
    executed = drive("executed", arbitration, switch_after=0, steps=steps)
    commanded = drive("commanded", arbitration, switch_after=0, steps=steps)
    assert all(i.alpha == 1.0 for i in executed[:-1])
    assert [i.suboptimality for i in commanded] == [i.suboptimality for i in executed]


def test_the_robots_own_motion_is_not_evidence_under_commanded():
    # Green first, then purple. With the executed trajectory as evidence, the robot,
    # confident in green, pulls the arm there and that motion keeps confirming green
    # (the lock-in). With the user's commands as evidence, every step toward purple
    # is optimal for purple (path length: a step of length s at the goal lowers the
    # cost-to-go by 227 s), so purple's suboptimality stops growing and purple wins.
    executed = drive("executed")
    commanded = drive("commanded")
    assert executed[3].alpha < 1.0  # the robot assists green before the switch
    assert executed[-1].intent == "green" and executed[-1].alpha < 0.5
    assert commanded[-1].intent == "purple"
    # Constant up to the bend of the user's path within a step (the user steers from
    # the arm's actual, robot-moved position): 1e-3 of a cost that is 18 here.
    after_switch = [i.suboptimality["purple"] for i in commanded[5:16]]
    np.testing.assert_allclose(after_switch, after_switch[0], atol=1e-3)
    grown = executed[15].suboptimality["purple"] - executed[5].suboptimality["purple"]
    assert grown > 1.0


def test_each_trial_starts_its_intents_afresh():
    # Intents are shared by the trials after learning; the assistant's reset starts each
    # of them (a planned intent then drops the plans of the trial before).
    class Counted(GoalIntent):
        starts = 0

        def start_trial(self):
            Counted.starts += 1

    intents = [Counted("a", GOAL), Counted("b", -GOAL)]
    assistant = Assistant(intents)
    assert Counted.starts == 0  # constructing is not a trial
    assistant.reset(START)
    assistant.reset(START)
    assert Counted.starts == 4
