"""The operator models in closed loop with pybullet: who lets go, who pushes back.

Participants are the study's own draws (config/config.yaml: its 11 participants, seed
2021), each trial with the same random stream under every method, so that only the method
differs, and with the study's time limit.
"""

import dataclasses

import numpy as np
import pytest

from casa_core.analysis import effort, metrics
from casa_core.assist.tasks import intended_trajectory
from casa_core.config import load_config
from casa_core.robot.sim import ArmSimulation
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
    return effort.key_presses(keys), effort.key_ticks(keys), success, frame


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


def test_assistance_toward_a_wrong_goal_makes_the_operator_push_back(sim):
    # Unknown Goal before learning: PBA assists the known green goal, 16 cm off the
    # participant's red path. Every participant holds its keys for more ticks than
    # without assistance, the participants together press more keys, and every one who
    # holds two keys at once still ends within the success radius of red before the
    # study's time limit. One key at a time gives a third to half of its speed under the
    # blend, which the pull toward green can match: of the study's one-key participants
    # 2 of 4 stay short (measured), as the one person the authors recorded stayed 0.61 m
    # short of the unknown goal under PBA.
    presses = {"NA": 0, "PBA": 0}
    for index in PARTICIPANTS:
        params = simulate.participant_params(index, SETTINGS.seed, SETTINGS.population)
        na = trial(sim, "unknown_goal", "NA", index)
        pulled = trial(sim, "unknown_goal", "PBA", index)
        if params.max_keys > 1:
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


def _held_ticks(operator, reference, carried: bool) -> np.ndarray:
    """Per tick, whether ``operator`` holds a key while the arm is carried along the
    reference whatever the keys (``carried``) or stands at its start."""
    held = []
    for row in reference:
        state = row[1:] if carried else reference[0, 1:]
        held.append(bool(operator.keys(row[0], state)))
    return np.array(held)


def test_the_predictive_operator_lets_go_once_it_has_seen_the_arm_carried():
    # Kinematic check without pybullet: an arm carried along the path at the reference's
    # speed, whatever the keys. While the operator holds a key it cannot tell the keys'
    # share from the robot's; its bouts end in a look (its reaction time without keys),
    # which shows the drift, and it lets go. An arm standing still at the start falls
    # behind and gets keys bout after bout. In the last third of the path, after three
    # bouts and their looks, the carried arm's operator holds keys on at most half as many
    # ticks (measured 10 against 26), and its drift is the arm's velocity within 20%.
    reference = intended_trajectory("known_goal", SCENE)
    carried = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0))
    standing = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0))
    third = len(reference) - len(reference) // 3
    carried_held = _held_ticks(carried, reference, carried=True)[third:].sum()
    standing_held = _held_ticks(standing, reference, carried=False)[third:].sum()
    assert carried_held <= standing_held / 2, (carried_held, standing_held)
    velocity = (reference[1, 1:4] - reference[0, 1:4]) / (reference[1, 0] - reference[0, 0])
    error = np.linalg.norm(carried._estimate.drift[:3] - velocity) / np.linalg.norm(velocity)
    assert error < 0.2, (carried._estimate.drift, velocity)


def test_continuous_control_is_the_special_case_of_no_bout_limit():
    # bout = inf: no look, so an operator whose arm stands still holds keys on every tick
    # from its first press on; with the default bout it lets go once a bout.
    reference = intended_trajectory("known_goal", SCENE)
    continuous = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0), bout=np.inf)
    held = _held_ticks(continuous, reference, carried=False)
    assert held[held.argmax() :].all()
    intermittent = _held_ticks(
        PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0)),
        reference,
        carried=False,
    )
    first = intermittent.argmax()
    assert not intermittent[first:].all()
    with pytest.raises(ValueError, match="bout = 0"):
        PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0), bout=0)


def test_the_predictive_operator_times_its_presses_by_the_tick_it_is_given():
    # The refractory rule on the time passed in, nothing else: a press at 0 s, a second
    # key wanted 0.1 s later is held back (REFRACTORY = 0.25 s after the last change),
    # and pressed at 0.3 s. EXPERT presses no wrong keys, so no draw decides a key.
    reference = intended_trajectory("known_goal", SCENE)
    operator = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0))
    along_x, along_x_and_y = np.array([0.1, 0.0, 0.0, 0.0]), np.array([0.1, 0.1, 0.0, 0.0])
    operator._held = operator._choose_keys(along_x, 0.0)
    assert operator._held == {"x+"}
    assert operator._choose_keys(along_x_and_y, 0.1) == {"x+"}
    assert operator._choose_keys(along_x_and_y, 0.3) == {"x+", "y+"}


def _keyboard_floor(displacement: np.ndarray, max_keys: int) -> float:
    """The shortest path from 0 to ``displacement`` with at most ``max_keys`` keys held,
    each moving one axis at the same speed: steps along one axis (1 key), face diagonals
    (2) or the cube's diagonal (3), each used as far as it goes."""
    a, b, c = sorted(np.abs(displacement), reverse=True)
    if max_keys == 1:
        return a + b + c
    if max_keys == 2:
        if a >= b + c:
            return np.sqrt(2) * (b + c) + (a - b - c)
        return np.sqrt(2) * (a + b + c) / 2
    return np.sqrt(3) * c + np.sqrt(2) * (b - c) + (a - b)


def _study_participant(index, reference):
    """Participant ``index`` of the study's population, predictive, on its own stream."""
    params = simulate.participant_params(index, SETTINGS.seed, SETTINGS.population)
    rng = np.random.default_rng([2021, index, 1])
    return params, make_participant(params, reference, rng=rng, operator="predictive")


OPPOSITE = {"x+": "x-", "x-": "x+", "y+": "y-", "y-": "y+", "z+": "z-", "z-": "z+"}
OPPOSITE.update({"rot+": "rot-", "rot-": "rot+"})


@pytest.mark.parametrize("scene_file", ["config/scene.yaml", "config/scene-original.yaml"])
def test_without_assistance_the_operator_drives_near_the_shortest_path_its_keys_allow(scene_file):
    # Known Goal under NA, the study's 11 participants, each on its own layout. A path
    # can be no shorter than the keyboard allows (_keyboard_floor: one key at a time
    # drives the L1 distance). The participants' median path is within 15% of it, and a
    # held key is replaced by its opposite on the next tick fewer than twice a trial on
    # average. Before the operator knew its own keys (it extrapolated the arm's velocity,
    # its held keys included, and answered the prediction's error with the opposite
    # key) the median was 1.81 (authors' layout) and 1.52 (ours) times the floor, with
    # 69 and 38 such reversals; now 1.08 and 1.00, 11 and 12 (docs/departures.md).
    # The path's shape, not the protocol's: trials run until the operator is done.
    scene = dataclasses.replace(load_scene(scene_file), trial_length=None)
    reference = intended_trajectory("known_goal", scene)
    displacement = reference[-1, 1:4] - reference[0, 1:4]
    ratios, reversals = [], 0
    with ArmSimulation(scene) as arm:
        for index in PARTICIPANTS:
            params, source = _study_participant(index, reference)
            frame = run_trial(
                scene,
                "known_goal",
                "NA",
                source,
                participant="p",
                sim=arm,
                max_duration=SETTINGS.max_duration,
            ).frame
            positions = frame[["x", "y", "z"]].to_numpy()
            path = np.linalg.norm(np.diff(positions, axis=0), axis=1).sum()
            ratios.append(path / _keyboard_floor(displacement, params.max_keys))
            held = [set(k.split()) for k in frame["keys"].fillna("")]
            reversals += sum(
                OPPOSITE[key] in after
                for before, after in zip(held[:-1], held[1:], strict=True)
                for key in before
            )
    assert np.median(ratios) <= 1.15, ratios
    assert reversals < 2 * len(PARTICIPANTS), reversals


def test_an_operator_that_has_arrived_waits_and_steers_back_when_the_arm_is_moved_away():
    # Kinematic check without pybullet: the arm carried along the reference to its end and
    # held there for 6 s (the drift estimate settles: no key in the last 2 s), then moved
    # along y. Arrival is judged within the deadband; a
    # waiting operator steers again only beyond HYSTERESIS (3) deadbands: at 1.5 it keeps
    # waiting for 4 s with no key, at 5 it presses toward the end (y-) within half a second
    # (its reaction time, 0.25 s, and the estimate's lag: measured 0.3 s).
    reference = intended_trajectory("known_goal", SCENE)
    end = reference[-1, 1:]
    for moved, expect_keys in ((1.5, False), (5.0, True)):
        operator = PredictiveParticipant(EXPERT, reference, rng=np.random.default_rng(0))
        _held_ticks(operator, reference, carried=True)
        t = reference[-1, 0] + 0.05 * np.arange(1, 121)
        waiting = [operator.keys(ti, end) for ti in t]
        assert not any(waiting[80:]) and operator.done  # no key in the last 2 s
        away = end + np.array([0.0, moved * EXPERT.deadband, 0.0, 0.0])
        held = [operator.keys(ti, away) for ti in t[-1] + 0.05 * np.arange(1, 81)]
        if not expect_keys:
            assert not any(held) and operator.done
            continue
        first = next(i for i, keys in enumerate(held) if keys)
        assert first * 0.05 <= 0.5 and "y-" in held[first] and not operator.done


class _Watched:
    """A key source that records, tick by tick, whether its operator judged itself done."""

    def __init__(self, source):
        self.source, self.dones = source, []

    def keys(self, t, state):
        held = self.source.keys(t, state)
        self.dones.append(self.source.done)
        return held

    @property
    def done(self):
        return self.source.done


def test_in_a_trial_of_fixed_length_the_operators_wait_once_arrived():
    # The authors' setup runs the original's 15 s trials. Known Goal under CASA, the
    # study's 11 participants: every trial lasts 15 s, at least 9 operators arrive
    # (measured 11), and after its first arrival an operator holds keys on at most 5% of
    # the ticks left (measured 2.6%: steering back when its estimate, not the arm, strays).
    scene = load_scene("config/scene-original.yaml")
    reference = intended_trajectory("known_goal", scene)
    arrived, after, with_keys = 0, 0, 0
    with ArmSimulation(scene) as arm:
        for index in PARTICIPANTS:
            watched = _Watched(_study_participant(index, reference)[1])
            frame = run_trial(
                scene, "known_goal", "CASA", watched, participant="p", sim=arm, max_duration=40
            ).frame
            assert frame["t"].iloc[-1] == 15.0
            if any(watched.dones):
                first = watched.dones.index(True)
                keys = frame["keys"].fillna("").iloc[first:]
                arrived, after, with_keys = (
                    arrived + 1,
                    after + len(keys),
                    with_keys + (keys != "").sum(),
                )
    assert arrived >= 9, arrived
    assert with_keys <= 0.05 * after, (with_keys, after)


@pytest.mark.parametrize("operator", ["lookahead", "predictive"])
def test_a_reference_that_never_moves_is_a_point_the_operator_steers_to(operator):
    # A reference path of one repeated pose (path length 0) is a target, not a direction:
    # the operator presses toward it (here x+, 10 cm) and lets go once there, with no NaN.
    reference = np.zeros((20, 5))
    reference[:, 0] = 0.05 * np.arange(20)
    reference[:, 1:] = [0.5, 0.0, 0.2, 0.0]
    source = make_participant(EXPERT, reference, rng=np.random.default_rng(0), operator=operator)
    start = np.array([0.4, 0.0, 0.2, 0.0])
    held = [source.keys(0.05 * i, start) for i in range(40)]
    assert any("x+" in keys for keys in held) and not source.done
    there = reference[0, 1:]
    for i in range(40, 200):
        source.keys(0.05 * i, there)
    assert source.done
