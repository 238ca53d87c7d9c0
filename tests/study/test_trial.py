"""The trial runner: scripted trials of every task under every method, headless.

Expected numbers come from the key map (0.05 m/s), the control tick (0.05 s), the
inference period (0.5 s) and PBA's arbitration alpha = min(1, d / D) with D = 0.55 m
(the original implementation's, docs/paper-to-code.md); logs are checked by the
casa-trial/1 reader itself.
"""

import dataclasses

import numpy as np
import pytest

from casa_core.assist.tasks import intended_trajectory, task_waypoints
from casa_core.io import read_trial, validate_paths
from casa_core.study.closed_loop import default_phase, known_goal_intents, run_trial
from casa_core.study.key_sources import ScriptedKeys, WaypointKeys
from casa_core.study.participants import ParticipantParams, SimulatedParticipant


def _expert(task, scene):
    return WaypointKeys(task_waypoints(task, scene)[1:])


CASES = [("familiarization", "NA")] + [
    (task, method)
    for task in ("known_goal", "unknown_goal", "unknown_skill")
    for method in ("NA", "PBA", "CASA")
]


@pytest.mark.parametrize(("task", "method"), CASES)
def test_scripted_trial_writes_a_valid_log(task, method, scene, tmp_path):
    result = run_trial(
        scene, task, method, _expert(task, scene), participant="s1", max_duration=20, seed=3
    )
    stem = tmp_path / "s1" / f"{task}_{method}"
    result.write(stem)
    assert validate_paths([tmp_path]) == []
    meta, frame = read_trial(stem)
    assert meta["task"] == task and meta["method"] == method
    assert meta["phase"] == default_phase(task)
    assert meta["intents"] == ["green", "purple"] and meta["seed"] == 3
    assert meta["max_duration"] == 20.0  # the limit, so trials.csv can tell who ran out
    expected = ["t", "x", "y", "z", "rot", "keys", "alpha"] + [f"q{i}" for i in range(1, 8)]
    expected += ["beta:green", "beta:purple", "belief:green", "belief:purple"]
    assert list(frame.columns) == expected
    np.testing.assert_allclose(np.diff(frame["t"]), 0.05, atol=1e-9)
    assert frame["alpha"].between(0, 1).all()
    if method == "NA":
        assert (frame["alpha"] == 1).all()
        # Direct teleoperation of the scripted expert ends at the task's last waypoint.
        final = task_waypoints(task, scene)[-1]
        last = frame.iloc[-1]
        np.testing.assert_allclose(last[["x", "y", "z"]].to_numpy(float), final[:3], atol=6e-3)
        assert last["rot"] == pytest.approx(final[3], abs=0.06)


def test_held_key_for_one_second_moves_five_centimetres(scene):
    source = ScriptedKeys([(1.0, ["x+"]), (0.5, [])])
    frame = run_trial(scene, "known_goal", "NA", source, participant="s").frame
    assert source.done
    assert (frame["keys"][:20] == "x+").all() and (frame["keys"][20:] == "").all()
    # 20 ticks of 0.05 s at 0.05 m/s = 0.05 m along x.
    moved = frame.iloc[-1][["x", "y", "z"]].to_numpy(float) - scene.start_state[:3]
    np.testing.assert_allclose(moved, [0.05, 0, 0], atol=2e-3)


def test_inference_runs_twice_per_second(scene):
    frame = run_trial(
        scene, "known_goal", "CASA", _expert("known_goal", scene), participant="s"
    ).frame
    early = frame[frame["t"] < 0.5 - 1e-9]
    assert (early["beta:green"] == 0).all() and (early["belief:green"] == 0.5).all()
    changed = frame["t"][frame["belief:green"].diff().fillna(0) != 0]
    assert len(changed) > 2
    np.testing.assert_allclose(np.mod(changed * 2, 1.0), 0.0, atol=1e-9)


def test_pba_arbitrates_by_the_distance_to_the_predicted_goal(scene):
    frame = run_trial(
        scene, "known_goal", "PBA", _expert("known_goal", scene), participant="s"
    ).frame
    green = scene.goal("green")
    # At an inference tick the alpha logged is min(1, d / 0.55) for the state of that row.
    inference = frame[np.isclose(np.mod(frame["t"] * 2, 1.0), 0) & (frame["t"] > 0)]
    late = inference.iloc[-1]
    assert late["belief:green"] > late["belief:purple"]
    distance = np.linalg.norm(late[["x", "y", "z"]].to_numpy(float) - green)
    assert late["alpha"] == pytest.approx(min(1.0, distance / 0.55), abs=1e-9)
    assert late["alpha"] < 0.5


def test_casa_before_learning_leaves_the_user_in_control_of_the_unknown_goal(scene):
    """The paper's Fig. 3 (middle): neither known goal explains the motion, alpha stays 1."""
    frame = run_trial(
        scene, "unknown_goal", "CASA", _expert("unknown_goal", scene), participant="s"
    ).frame
    assert (frame["alpha"] == 1).all()
    red = scene.goal("red")
    np.testing.assert_allclose(frame.iloc[-1][["x", "y", "z"]].to_numpy(float), red, atol=6e-3)


def test_belief_method_runs_but_is_not_a_log_method(scene, tmp_path):
    result = run_trial(
        scene,
        "unknown_goal",
        "BELIEF",
        _expert("unknown_goal", scene),
        participant="s",
        max_duration=3,
    )
    assert len(result.frame) == 61
    with pytest.raises(ValueError, match="casa-trial/1"):
        result.write(tmp_path / "belief")
    assert not list(tmp_path.iterdir())


def test_simulated_participant_is_a_key_source(scene):
    params = ParticipantParams(
        reaction_time=0.2,
        perception_noise=0.002,
        deadband=0.01,
        lapse_rate=0.0,
        lapse_duration=0.5,
        wrong_key=0.0,
        max_keys=3,
    )
    reference = intended_trajectory("known_goal", scene)
    participant = SimulatedParticipant(params, reference, rng=np.random.default_rng(5))
    frame = run_trial(scene, "known_goal", "CASA", participant, participant="p1").frame
    assert participant.done
    green = scene.goal("green")
    assert np.linalg.norm(frame.iloc[-1][["x", "y", "z"]].to_numpy(float) - green) < 0.03


def test_bad_inputs_are_named(scene):
    with pytest.raises(ValueError, match="method 'XX'"):
        run_trial(scene, "known_goal", "XX", ScriptedKeys([]), participant="s")
    with pytest.raises(ValueError, match="task 'flying'"):
        default_phase("flying")
    with pytest.raises(ValueError, match="'jump'"):
        ScriptedKeys([(1.0, ["jump"])])
    with pytest.raises(ValueError, match="entry 0"):
        ScriptedKeys([(-1.0, ["x+"])])
    with pytest.raises(ValueError, match="goals has no orange"):
        known_goal_intents(scene, ["green", "orange"])
    odd_tick = dataclasses.replace(scene, teleop=dataclasses.replace(scene.teleop, dt=0.3))
    with pytest.raises(ValueError, match="teleop.dt"):
        run_trial(odd_tick, "known_goal", "NA", ScriptedKeys([]), participant="s")


def test_a_trial_ended_at_once_still_writes_a_valid_log(scene, tmp_path):
    # A participant who ends the trial on its first tick: the log keeps the start and one
    # tick, which the contract requires (rule two-rows), so the session goes on.
    result = run_trial(scene, "known_goal", "CASA", ScriptedKeys([]), participant="s1")
    stem = tmp_path / "s1" / "known_goal_CASA"
    result.write(stem)
    assert validate_paths([tmp_path]) == []
    assert read_trial(stem)[1]["t"].tolist() == [0.0, 0.05]


def test_a_trial_of_fixed_length_runs_its_length_whatever_the_source_says(scene):
    # The original's protocol (a scene's trial_length): a source done after 1 s, or never,
    # gives a trial of exactly 3 s (61 ticks of 0.05 s); max_duration gives way to it.
    fixed = dataclasses.replace(scene, trial_length=3.0)
    frames = []
    for script in ([(1.0, ["x+"])], []):
        result = run_trial(fixed, "known_goal", "NA", ScriptedKeys(script), participant="s")
        t = result.frame["t"]
        assert len(t) == 61 and t.iloc[-1] == 3.0 and result.meta["max_duration"] == 3.0
        frames.append(result.frame)
    # The arm moved 5 cm in the second of keys and stood still after it.
    frame = frames[0]
    assert frame["x"].iloc[-1] - frame["x"].iloc[0] == pytest.approx(0.05, abs=0.002)
    # Settled within 0.1 mm a quarter second after the keys.
    assert frame["x"].iloc[-1] == pytest.approx(frame["x"].iloc[25], abs=1e-4)
    # Without it, the same source ends the trial when done: at 1 s, 21 rows.
    ended = run_trial(scene, "known_goal", "NA", ScriptedKeys([(1.0, ["x+"])]), participant="s")
    assert len(ended.frame) == 21


def test_a_pause_still_ends_a_trial_of_fixed_length(scene):
    class Paused(ScriptedKeys):
        def keys(self, t, state):
            self.paused = self.done = t >= 0.5
            return frozenset()

    fixed = dataclasses.replace(scene, trial_length=3.0)
    result = run_trial(fixed, "known_goal", "NA", Paused([]), participant="s")
    assert result.frame["t"].iloc[-1] == 0.5
