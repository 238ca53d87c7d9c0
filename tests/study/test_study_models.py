"""Simulated participants, the protocol, the Likert model and the arbitration comparison."""

import numpy as np
import pandas as pd
import pytest

from casa_core.assist.assistant import Assistant
from casa_core.assist.intents import GoalIntent
from casa_core.assist.tasks import intended_trajectory
from casa_core.robot.keys import keys_to_action
from casa_core.scene import load_scene
from casa_core.study import likert, protocol
from casa_core.study.arbitration_comparison import compare_arbitrations
from casa_core.study.participants import ParticipantParams, SimulatedParticipant, draw_participants
from casa_core.study.settings import Population
from casa_core.vocabulary import QUESTIONS

SCENE = load_scene()
EXPERT = ParticipantParams(0.25, 0.003, 0.008, 0.0, 0.5, 0.0, 3)
POPULATION = Population.from_config(
    {
        "reaction_time": {"median": 0.35, "sigma": 0.25},
        "perception_noise": {"median": 0.01, "sigma": 0.3},
        "deadband": {"median": 0.015, "sigma": 0.25},
        "lapse_rate": {"median": 0.03, "sigma": 0.5},
        "lapse_duration": {"median": 0.8, "sigma": 0.3},
        "wrong_key": {"median": 0.02, "sigma": 0.5},
        "max_keys": {"values": [1, 2, 3], "p": [0.4, 0.4, 0.2]},
    }
)


def drive(participant, reference, pull=None, limit=60.0, tick=0.05):
    """Integrate the participant's keys kinematically; ``pull`` adds a robot velocity."""
    state, t, presses, previous = reference[0, 1:].copy(), 0.0, 0, frozenset()
    while t < limit and not participant.done:
        keys = participant.keys(t, state)
        presses += len(keys - previous)
        previous = keys
        velocity = keys_to_action(keys)
        if pull is not None:
            velocity = 0.5 * velocity + 0.5 * pull
        state = state + velocity * tick
        t += tick
    return state, t, presses


@pytest.mark.parametrize("task", ["known_goal", "unknown_goal", "unknown_skill"])
def test_expert_reaches_the_end_of_the_intended_trajectory(task):
    reference = intended_trajectory(task, SCENE)
    participant = SimulatedParticipant(EXPERT, reference, rng=np.random.default_rng(0))
    state, t, _ = drive(participant, reference)
    assert participant.done
    assert np.linalg.norm(state[:3] - reference[-1, 1:4]) < 0.02
    assert abs(state[3] - reference[-1, 4]) < 0.2
    # keys move one axis at 0.05 m/s, so the expert needs at least the reference's time
    assert t >= reference[-1, 0] * 0.5


def test_participants_are_drawn_deterministically_from_the_seed():
    first = draw_participants(5, POPULATION, np.random.default_rng(7))
    again = draw_participants(5, POPULATION, np.random.default_rng(7))
    assert first == again
    assert len({p.reaction_time for p in first}) == 5


def test_a_robot_pulling_off_course_costs_the_participant_effort():
    # The participant counteracts: a steady pull away from the path needs more key presses.
    reference = intended_trajectory("unknown_goal", SCENE)
    params = draw_participants(1, POPULATION, np.random.default_rng(3))[0]
    _, _, free = drive(
        SimulatedParticipant(params, reference, rng=np.random.default_rng(1)), reference
    )
    pull = np.array([0.05, 0.0, 0.0, 0.0])
    state, _, pulled = drive(
        SimulatedParticipant(params, reference, rng=np.random.default_rng(1)), reference, pull
    )
    assert pulled > free
    assert np.linalg.norm(state[:3] - reference[-1, 1:4]) < 0.1


def test_protocol_counterbalances_methods_and_follows_the_paper_order():
    orders = {protocol.method_order(i) for i in range(6)}
    assert len(orders) == 6  # every order of NA, PBA, CASA once in 6 participants
    trials = protocol.before_learning(0)
    assert [t.phase for t in trials] == ["familiarization"] + ["no_misspecification"] * 3 + [
        "before_learning"
    ] * 6
    assert [t.task for t in trials[4:]] == ["unknown_goal"] * 3 + ["unknown_skill"] * 3
    demos = protocol.demonstrations("unknown_goal")
    assert len({d.stem for d in demos}) == 5
    assert {t.stem for t in protocol.after_learning()} == {
        "unknown_goal_after_learning_CASA",
        "unknown_skill_after_learning_CASA",
    }


def test_fight_fraction_counts_ticks_moving_against_the_keys():
    # 4 ticks holding y+; the arm moves +y, +y, -x (90 deg off), -y (180 deg off)
    frame = pd.DataFrame(
        {
            "x": [0.0, 0.0, 0.0, -0.01, -0.01],
            "y": [0.0, 0.01, 0.02, 0.02, 0.01],
            "z": [0.0] * 5,
            "keys": ["y+"] * 5,
        }
    )
    assert likert.fight_fraction(frame) == pytest.approx(0.5)


def test_likert_scores_are_integers_on_the_scale_and_follow_the_experience():
    rng = np.random.default_rng(0)
    good = likert.latent_impressions(help_=0.8, fight=0.0, effort_gain=0.6, error_gain=0.3)
    bad = likert.latent_impressions(help_=0.6, fight=0.5, effort_gain=-0.5, error_gain=-0.5)
    good_scores = [likert.answer(good, 0.0, rng) for _ in range(200)]
    bad_scores = [likert.answer(bad, 0.0, rng) for _ in range(200)]
    for scores in (good_scores, bad_scores):
        values = [v for s in scores for v in s.values()]
        assert all(isinstance(v, int) and 1 <= v <= 7 for v in values)
    for question in QUESTIONS:
        assert np.mean([s[question] for s in good_scores]) > np.mean(
            [s[question] for s in bad_scores]
        )


def test_arbitration_comparison_belief_goes_to_one_while_confidence_stays_low():
    # Paper Fig. alpha_methods on our scene with the paper's distance-sum cost (C3).
    intents = [
        GoalIntent(name, SCENE.goals[name], cost="distance_sum") for name in ("green", "purple")
    ]
    trajectory = GoalIntent("red", SCENE.goals["red"]).optimal_trajectory(SCENE.start_state, 15.0)
    table = compare_arbitrations(Assistant(intents), trajectory)
    assert list(table.columns) == [
        "t",
        "intent",
        "belief",
        "beta",
        "alpha_distance",
        "alpha_belief",
        "alpha_confidence",
    ]
    assert len(table) == 2 * 31
    last = table[table.t == table.t.max()].set_index("intent")
    assert last.loc["green", "belief"] > 0.99
    assert last["alpha_belief"].iloc[0] < 0.01
    assert (table["beta"] < 1.0).all()
    assert (table["alpha_confidence"] == 1.0).all()
