"""Replaying imported sessions where the original measured them, with and without its defects.

The sessions are synthetic, in the original's format and laid out as it logs (NOTES
section 4): joint angles along a bent path, sampled 13 ms after each control tick; the
waypoints ``traj_hist`` recorded at the first sample at or after each 0.5 s; each timed
inference step starting 2 ms after its waypoint, over the waypoints recorded by then (one
step late, so one waypoint starts none); then the final step after the trial. The histories
are written by the test's own re-implementation of the original's numerics
(``tests/io/original_reference.py``, written from their specification, not from the
package), at link 7 of the waypoints, toward the link-7 goals of the original's layout.
Expected values are that re-implementation's; the tolerance 1e-9 leaves room only for
rounding.
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
#: Samples 13 ms after every tick of 0.05 s for 6 s, and one at the start.
TIMES = np.r_[0.0, np.round(np.arange(1, 121) * 0.05 + 0.013, 6)]
#: The waypoints 0..12 and the timed steps: at waypoints 1..11 but 4, which started while
#: the step of waypoint 3 was still running.
WAYPOINTS = 13
AT = [w for w in range(1, WAYPOINTS - 1) if w != 4]
STARTS = np.round(0.5 * np.array(AT) + 0.015, 6)
METHODS = {"task1c": "CASA", "task1b": "PBA"}


def joint_angles(t):
    """From the start toward goal 1, bent on joints 2 and 4 so the path is no straight line."""
    s = np.asarray(t)[:, None] / TIMES[-1]
    start, goal = reference_q("start"), reference_q("goal 1")
    bend = np.zeros(7)
    bend[[1, 3]] = 0.3
    return start + s * (goal - start) + np.sin(np.pi * s) * bend


def recorded(q):
    """traj_hist: the sample at or after each 0.5 s."""
    return q[[int(np.searchsorted(TIMES, 0.5 * j - 1e-9)) for j in range(WAYPOINTS)]]


def resampled(q):
    """The joint angles every 0.5 s, linearly interpolated between samples, as an import
    resamples them."""
    ticks = 0.5 * np.arange(WAYPOINTS)
    return np.column_stack([np.interp(ticks, TIMES, q[:, j]) for j in range(7)])


def write_sessions(folder, *, defects=True, waypoints=True):
    """One CASA and one PBA session whose histories are the reference's over the recorded
    waypoints (``waypoints``; else over the path resampled every 0.5 s, with no traj_hist
    in the file), and the reference's step results by stem."""
    folder.mkdir(parents=True)
    q = joint_angles(TIMES)
    command = np.array([np.linalg.pinv(kin.jacobian(row)[:3]) @ [0.0, 0.05, 0.0] for row in q])
    path = recorded(q) if waypoints else resampled(q)
    points = reference.link7_waypoints(path)
    expected = {}
    for stem, method in METHODS.items():
        logged = reference.histories(points, GOALS, defects=defects, method=method, at=AT)
        arrays = dict(
            cmdpos_time=TIMES,
            curr_pos=q,
            joy_cmd=command,
            ctl_cmd=np.zeros_like(q),
            cmd=command,
            inf_start_time=STARTS,
            sub_hist=logged["sub"],
            # NA and PBA sessions log no betas and the prior as their beliefs.
            belief_hist=logged["belief"] if method == "CASA" else np.full((len(AT) + 1, 2), 0.5),
            beta_hist=logged["beta"] if method == "CASA" else np.zeros(0),
            start_T=np.array(1.6e9),
        )
        if waypoints:
            arrays["traj_hist"] = path
        np.savez(folder / f"{stem}_data.npz", **arrays)
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
    # The trial's own settings: the original's numerics, defects included, at link 7, over
    # the recorded waypoints, each step at its own start.
    replayed = replay_trial(meta, frame, SCENE)
    logged = expected[stem]
    assert list(replayed["t"].unique()) == STARTS.tolist()
    timed = slice(0, len(AT))  # the final step is no step of the trial
    assert np.abs(by_intent(replayed, "belief") - logged["belief"][timed]).max() < 1e-9
    assert np.abs(by_intent(replayed, "suboptimality") - logged["sub"][timed]).max() < 1e-9
    alpha = replayed.drop_duplicates("t")["alpha"].to_numpy()
    assert np.abs(alpha - logged["alpha"]).max() < 1e-9
    gaps = replay_differences(frame, replayed)
    if METHODS[stem] == "CASA":
        assert np.abs(by_intent(replayed, "beta") - logged["beta"][timed]).max() < 1e-9
        # And so the replay is within rounding of the imported log itself, each step read
        # at the first tick at or after its start.
        assert gaps["belief"] < 1e-9 and gaps["beta"] < 1e-9 and gaps["alpha"] < 1e-9
    else:  # PBA logged no beliefs; its alpha, recomputed at import, is the replay's
        assert np.isnan(gaps["belief"]) and np.isnan(gaps["beta"]) and gaps["alpha"] < 1e-9


def test_the_replay_reads_the_path_its_log_was_computed_on(tmp_path):
    sessions = tmp_path / "sessions"
    write_sessions(sessions / "recorded" / "P01")
    write_sessions(sessions / "resampled" / "P01", waypoints=False)
    for name in ("recorded", "resampled"):
        raw = tmp_path / "raw" / name
        assert main(["import", "original", str(sessions / name / "P01"), "--out", str(raw)]) == 0
    summaries = {}
    for name, extra in (("recorded", []), ("resampled", []), ("recorded", ["--path", "ticks"])):
        out = tmp_path / "replay" / f"{name}{len(extra)}"
        argv = ["replay", str(tmp_path / "raw" / name), "--out", str(out), *extra]
        argv += ["--preset", "original_defects"]
        assert main(argv) == 0
        table = pd.read_csv(out / "replay.csv", keep_default_na=False).set_index("trial")
        summaries[name, bool(extra)] = table
    # Each log is reproduced on the path it was written from, and replay.csv says which.
    for key, path in ((("recorded", False), "waypoints"), (("resampled", False), "ticks")):
        casa = summaries[key].loc["P01/task1c"]
        assert casa["path"] == path and float(casa["max_diff_belief"]) < 1e-9, key
        assert float(casa["max_diff_beta"]) < 1e-9, key
    # The recorded waypoints are 13 ms after their ticks: read from the ticks, they differ.
    ticks = summaries["recorded", True].loc["P01/task1c"]
    assert ticks["path"] == "ticks" and float(ticks["max_diff_beta"]) > 1e-4
    # PBA logged no inference: nothing is compared, and the reason says so.
    pba = summaries["recorded", False].loc["P01/task1b"]
    assert pba["status"] == "replayed" and pba["max_diff_belief"] == ""
    assert pba["max_diff_alpha"] == "" and "flagged no-logged-inference" in pba["reason"]


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
    assert summary.loc[f"P01/{stem}", "path"] == "waypoints"
    replayed = pd.read_csv(out / "P01" / f"{stem}.replay.csv")
    logged = expected[stem]
    timed = slice(0, len(AT))
    assert np.abs(by_intent(replayed, "beta") - logged["beta"][timed]).max() < 1e-9
    assert np.abs(by_intent(replayed, "belief") - logged["belief"][timed]).max() < 1e-9
    alpha = replayed.drop_duplicates("t")["alpha"].to_numpy()
    assert np.abs(alpha - logged["alpha"]).max() < 1e-9


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
