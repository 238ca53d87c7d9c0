"""The operator models in closed loop with pybullet: who lets go, who pushes back.

Participants are the study's own draws (config/config.yaml: its 11 participants, seed
2021), each trial with the same random stream under every method, so that only the method
differs, and with the study's time limit.
"""

import numpy as np
import pytest

from casa_core.analysis import metrics
from casa_core.assist.tasks import intended_trajectory
from casa_core.config import load_config
from casa_core.scene import load_scene
from casa_core.study import simulate
from casa_core.study.closed_loop import run_trial
from casa_core.study.participants import (
    ParticipantParams,
    PredictiveParticipant,
    SimulatedParticipant,
    make_participant,
)
from casa_core.study.settings import StudySettings
from casa_core.vocabulary import TASKS

CONFIG = load_config("config/config.yaml")
SETTINGS = StudySettings.from_config(CONFIG)
SCENE = load_scene()
EXPERT = ParticipantParams(0.25, 0.003, 0.008, 0.0, 0.5, 0.0, 3)
PARTICIPANTS = range(CONFIG["simulation"]["participants"])


def trial(sim, task, method, index, *, operator="predictive", params=None):
    """One trial of participant ``index``: keys pressed, key ticks, success, the frame."""
    params = params or simulate.participant_params(index, SETTINGS.seed, SETTINGS.population)
    reference = intended_trajectory(task, SCENE)
    source = make_participant(
        params, reference, rng=np.random.default_rng([2021, index, 1]), operator=operator
    )
    frame = run_trial(
        SCENE,
        task,
        method,
        source,
        participant="p",
        sim=sim,
        max_duration=SETTINGS.max_duration,
    ).frame
    keys = frame["keys"].fillna("").tolist()
    executed = frame[["t", "x", "y", "z", "rot"]].to_numpy()
    success = metrics.task_success(executed, reference)
    return metrics.key_presses(keys), metrics.key_ticks(keys), success, frame


@pytest.mark.parametrize("method", ["CASA", "PBA"])
def test_assistance_toward_the_intended_goal_lets_the_operator_press_less(sim, method):
    # Known Goal: both methods assist green, the participant's goal. The predictive
    # operator lets go while the robot carries the arm, so every participant holds keys
    # for fewer ticks, and the six together press fewer keys, by at least 10% (a clear
    # effect, not a tick or two), than under direct teleoperation.
    totals = {"NA": np.zeros(2), method: np.zeros(2)}
    for index in PARTICIPANTS:
        na = trial(sim, "known_goal", "NA", index)
        assisted = trial(sim, "known_goal", method, index)
        assert na[2] and assisted[2]
        assert assisted[1] < na[1], f"participant {index}: key ticks {assisted[1]} >= {na[1]}"
        totals["NA"] += na[:2]
        totals[method] += assisted[:2]
    assert (totals[method] < 0.9 * totals["NA"]).all(), totals


def test_assistance_toward_a_wrong_goal_makes_the_operator_push_back_and_still_arrive(sim):
    # Unknown Goal before learning: PBA assists the known green goal, 16 cm off the
    # participant's red path. Every participant holds its keys for more ticks than
    # without assistance, the participants together press more keys, and every one still
    # ends within the success radius of red before the study's time limit.
    presses = {"NA": 0, "PBA": 0}
    for index in PARTICIPANTS:
        na = trial(sim, "unknown_goal", "NA", index)
        pulled = trial(sim, "unknown_goal", "PBA", index)
        assert pulled[2], f"participant {index} did not end at red under PBA"
        assert pulled[1] > na[1], f"participant {index}: key ticks {pulled[1]} <= {na[1]}"
        presses["NA"] += na[0]
        presses["PBA"] += pulled[0]
    assert presses["PBA"] > presses["NA"], presses


@pytest.mark.parametrize("task", TASKS)
def test_the_predictive_operator_completes_every_task_on_its_own(sim, task):
    # Under NA nothing but the keys moves the arm: the operator must drive it all the way,
    # the pour's turn included, and say it is done before the trial's time limit.
    for index in (0, 1, 2):
        _, _, success, frame = trial(sim, task, "NA", index)
        assert success, f"participant {index} did not complete {task}"
        assert frame["t"].iloc[-1] < SETTINGS.max_duration
    assert trial(sim, task, "NA", 0, params=EXPERT)[2]


def test_the_lookahead_model_stays_selectable_and_unchanged(sim):
    # The factory's "lookahead" is the lookahead class itself, so the same draws give the
    # same trial as constructing it directly.
    reference = intended_trajectory("known_goal", SCENE)
    params = simulate.participant_params(0, SETTINGS.seed, SETTINGS.population)
    direct = SimulatedParticipant(params, reference, rng=np.random.default_rng([2021, 0, 1]))
    frame = run_trial(SCENE, "known_goal", "CASA", direct, participant="p", sim=sim).frame
    assert frame.equals(trial(sim, "known_goal", "CASA", 0, operator="lookahead")[3])
    rng = np.random.default_rng(0)
    assert type(make_participant(params, reference, rng=rng, operator="lookahead")) is (
        SimulatedParticipant
    )
    assert isinstance(
        make_participant(params, reference, rng=rng, operator="predictive"),
        PredictiveParticipant,
    )


def test_the_predictive_operator_lets_go_when_the_arm_moves_along_its_path():
    # Kinematic check without pybullet: an arm seen moving along the path at the
    # reference's speed, exactly on it and on schedule, needs no key; the same arm
    # standing still at the start falls behind by the reference's speed times the
    # horizon (0.05 m/s * 0.75 s = 3.75 cm > the 0.8 cm deadband) and gets one.
    reference = intended_trajectory("known_goal", SCENE)
    moving = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0))
    standing = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0))
    moving_keys = standing_keys = frozenset()
    for row in reference[:60]:
        moving_keys = moving.keys(row[0], row[1:])
        standing_keys = standing.keys(row[0], reference[0, 1:])
    assert moving_keys == frozenset()
    assert standing_keys != frozenset()
