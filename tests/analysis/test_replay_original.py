"""Replaying imported sessions where the original measured them, with and without its defects.

The sessions are synthetic, in the original's format: joint angles along a bent path, and
histories (belief, beta, suboptimality) written by the test's own re-implementation of
the original's numerics (``tests/io/original_reference.py``, written from their
specification, not from the package), at link 7 of the logged joint angles, toward the
link-7 goals of the original's layout. Expected values are that re-implementation's;
the tolerance 1e-9 leaves room only for rounding.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.analysis.replay import ReplayError, replay_differences, replay_trial
from casa_core.cli import main
from casa_core.io import read_trial
from casa_core.io.original.importer import ORIGINAL_SCENE
from casa_core.io.original.sessions import reference_q
from casa_core.robot import kinematics as kin
from casa_core.scene import KNOWN_GOALS, load_scene
from tests.io import original_reference as reference

SCENE = load_scene(ORIGINAL_SCENE)
GOALS = np.array([SCENE.goal(name, "link7") for name in KNOWN_GOALS])
#: Samples every 0.05 s for 6 s, so that the inference ticks (every 0.5 s) are samples.
TIMES = np.round(np.arange(121) * 0.05, 6)
STEPS = TIMES[::10]  # t = 0, 0.5, ..., 6.0: the waypoints of steps 0..12
METHODS = {"task1c": "CASA", "task1b": "PBA"}


def joint_angles(t):
    """From the start toward goal 1, bent on joints 2 and 4 so the path is no straight line."""
    s = np.asarray(t)[:, None] / TIMES[-1]
    start, goal = reference_q("start"), reference_q("goal 1")
    bend = np.zeros(7)
    bend[[1, 3]] = 0.3
    return start + s * (goal - start) + np.sin(np.pi * s) * bend


def write_sessions(folder, *, defects=True):
    """One CASA and one PBA session whose histories are the reference's, and the
    reference's step results by stem."""
    folder.mkdir(parents=True)
    q = joint_angles(TIMES)
    command = np.array([np.linalg.pinv(kin.jacobian(row)[:3]) @ [0.0, 0.05, 0.0] for row in q])
    waypoints = reference.link7_waypoints(joint_angles(STEPS))
    expected = {}
    for stem, method in METHODS.items():
        logged = reference.histories(waypoints, GOALS, defects=defects, method=method)
        np.savez(
            folder / f"{stem}_data.npz",
            cmdpos_time=TIMES,
            curr_pos=q,
            joy_cmd=command,
            ctl_cmd=np.zeros_like(q),
            cmd=command,
            traj_hist=np.zeros((31, 7)),
            inf_start_time=STEPS[1:],
            sub_hist=logged["sub"],
            belief_hist=logged["belief"],
            beta_hist=logged["beta"] if method == "CASA" else np.zeros(0),
            start_T=np.array(1.6e9),
        )
        expected[stem] = logged
    return expected


@pytest.fixture
def imported(tmp_path):
    expected = write_sessions(tmp_path / "sessions" / "P01")
    out = tmp_path / "raw"
    assert main(["import", "original", str(tmp_path / "sessions" / "P01"), "--out", str(out)]) == 0
    return out, expected


def by_intent(replayed, column):
    """``column`` of a replay as (steps, goals), goals in KNOWN_GOALS order."""
    table = replayed.pivot(index="t", columns="intent", values=column)
    return table[list(KNOWN_GOALS)].to_numpy(dtype=float)


@pytest.mark.parametrize("stem", METHODS)
def test_the_defects_preset_replays_an_import_to_its_logged_beliefs(imported, stem):
    out, expected = imported
    meta, frame = read_trial(out / "P01" / stem)
    # The trial's own settings: the original's numerics, defects included, at link 7.
    replayed = replay_trial(meta, frame, SCENE)
    logged = expected[stem]
    assert list(replayed["t"].unique()) == list(STEPS[1:])
    assert np.abs(by_intent(replayed, "belief") - logged["belief"][1:]).max() < 1e-9
    assert np.abs(by_intent(replayed, "suboptimality") - logged["sub"][1:]).max() < 1e-9
    alpha = replayed.drop_duplicates("t")["alpha"].to_numpy()
    assert np.abs(alpha - logged["alpha"][1:]).max() < 1e-9
    if METHODS[stem] == "CASA":
        assert np.abs(by_intent(replayed, "beta") - logged["beta"][1:]).max() < 1e-9
    # And so the replay is within rounding of the imported log itself.
    gaps = replay_differences(frame, replayed)
    assert gaps["belief"] < 1e-9 and gaps["alpha"] < 1e-9
    assert gaps["beta"] < 1e-9 if METHODS[stem] == "CASA" else np.isnan(gaps["beta"])


def test_the_defects_differ_from_the_faithful_numerics_on_the_same_path(imported):
    out, expected = imported
    meta, frame = read_trial(out / "P01" / "task1c")
    own = replay_trial(meta, frame, SCENE)
    faithful = replay_trial(meta, frame, SCENE, preset="original")
    # The penalty toward goal 0 alone makes them differ by far more than rounding.
    assert np.abs(by_intent(own, "suboptimality") - by_intent(faithful, "suboptimality")).min() > 1


@pytest.mark.parametrize("stem", METHODS)
def test_casa_replay_preset_original_follows_the_original_at_link7(tmp_path, stem):
    expected = write_sessions(tmp_path / "sessions" / "P01", defects=False)
    raw = tmp_path / "raw"
    assert main(["import", "original", str(tmp_path / "sessions" / "P01"), "--out", str(raw)]) == 0
    out = tmp_path / "replay"
    assert main(["replay", str(raw), "--out", str(out), "--preset", "original"]) == 0
    summary = pd.read_csv(out / "replay.csv").set_index("trial")
    assert summary.loc[f"P01/{stem}", ["preset", "point"]].tolist() == ["original", "link7"]
    replayed = pd.read_csv(out / "P01" / f"{stem}.replay.csv")
    logged = expected[stem]
    assert np.abs(by_intent(replayed, "beta") - logged["beta"][1:]).max() < 1e-9
    assert np.abs(by_intent(replayed, "belief") - logged["belief"][1:]).max() < 1e-9
    alpha = replayed.drop_duplicates("t")["alpha"].to_numpy()
    assert np.abs(alpha - logged["alpha"][1:]).max() < 1e-9


def test_at_the_tool_point_the_same_replay_differs(imported):
    out, expected = imported
    meta, frame = read_trial(out / "P01" / "task1c")
    at_tool = replay_trial(meta, frame, SCENE, preset="original", point="tool")
    at_link7 = replay_trial(meta, frame, SCENE, preset="original")
    assert np.abs(by_intent(at_tool, "beta") - by_intent(at_link7, "beta")).max() > 0.01


def test_link7_needs_joint_angles_and_link7_goals(imported):
    out, _ = imported
    meta, frame = read_trial(out / "P01" / "task1c")
    with pytest.raises(ReplayError, match=r"measured at tool: the log has no joint angles \(q1\)"):
        replay_trial(meta, frame.drop(columns=["q1"]), SCENE, point="tool")
    with pytest.raises(ReplayError, match="measured at link7: scene: link7 has no 'green'"):
        replay_trial(meta, frame, load_scene(), preset="original")
    with pytest.raises(ReplayError, match="preset original_defects redoes goals only"):
        replay_trial(meta, frame, SCENE, intents=["green", "learned_red"])
