"""The Done-when test of issue 29: sim, assistant and operator as three processes over DDS.

A Known Goal trial under CASA: ``casa ros2 sim``, ``casa ros2 assist`` and a scripted
operator (``teleop_script.py``, the keys a :class:`WaypointKeys` expert holds, as a
Twist) talk over Fast DDS on a domain of their own. The arm must reach the green goal,
alpha must fall as in the in-process closed loop (:func:`run_trial` with the same
expert) within :data:`ALPHA_TOLERANCE` at every inference step of the approach, and the
recorded log must validate and build its tables.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.cli import main
from casa_core.defaults import DT, SUCCESS_RADIUS
from casa_core.io import read_trial
from casa_core.study.closed_loop import run_trial
from casa_core.study.key_sources import WaypointKeys
from tests.ros2.ros_processes import casa, ros_env, script, stop

pytest.importorskip("rclpy", reason="the ros2 extra is not installed")

#: How far (in alpha) the trial over DDS may be from the in-process one, beyond a shift of
#: one inference step in time. The arm's state arrives up to a tick old and the operator's
#: command up to a tick late, so near the goal the live operator corrects a little more
#: (more evidence): measured gaps were up to 0.065, at the last steps of the approach.
ALPHA_TOLERANCE = 0.1
#: Seconds the assistant records; the expert reaches the goal in about 6.
DURATION = 14.0


def test_a_known_goal_trial_under_casa_over_dds(tmp_path, scene, capsys):
    goal = np.array(scene.goals["green"])
    env = ros_env()
    out = tmp_path / "raw" / "P01"
    processes = []
    try:
        processes.append(casa(["ros2", "sim", "--duration", "60"], env, tmp_path / "sim.log"))
        assist = casa(
            ["ros2", "assist", "--task", "known_goal", "--method", "CASA"]
            + ["--participant", "P01", "--out", str(out), "--duration", str(DURATION)],
            env,
            tmp_path / "assist.log",
        )
        processes.append(assist)
        processes.append(
            script("teleop_script.py", [*map(str, goal[:3]), "60"], env, tmp_path / "op.log")
        )
        assist.wait(timeout=DURATION + 60)
    finally:
        stop(processes)
    log = (tmp_path / "assist.log").read_text()
    assert assist.returncode == 0, log
    stem = out / "known_goal_no_misspecification_CASA"
    meta, frame = read_trial(stem)
    assert meta["method"] == "CASA" and meta["source"] == "human"

    # The arm reached the goal.
    end = frame[["x", "y", "z"]].to_numpy()[-1]
    assert np.linalg.norm(end - goal[:3]) < SUCCESS_RADIUS, end

    # Alpha fell as in the in-process closed loop: the same expert, the same assistant.
    expert = WaypointKeys([[*goal[:3], 0.0]], rot_tolerance=1e9)
    reference = run_trial(scene, "known_goal", "CASA", expert, participant="P01").frame
    # From the operator's first command on (the assistant may start a few ticks earlier,
    # so its inference steps fall anywhere within a step of the reference's): at each
    # inference step of the approach, the live alpha is within ALPHA_TOLERANCE of the
    # reference's alphas within one inference step (DT) of the same time.
    first = frame.index[frame["keys"] != ""][0]
    live = frame.iloc[first:].reset_index(drop=True)
    window = int(round(DT / scene.teleop.dt))
    steps = np.arange(window, min(len(live), len(reference)), window)
    ref = reference["alpha"].to_numpy()
    low = np.array([ref[max(i - window, 0) : i + window + 1].min() for i in steps])
    high = np.array([ref[max(i - window, 0) : i + window + 1].max() for i in steps])
    alpha = live["alpha"].to_numpy()[steps]
    gap = np.maximum(low - alpha, alpha - high).clip(0)
    compared = {"t": live["t"][steps], "dds": alpha, "low": low, "high": high}
    assert gap.max() <= ALPHA_TOLERANCE, pd.DataFrame(compared)
    assert live["alpha"].iloc[steps[-1]] < 0.6  # and it did fall: CASA took a share

    # The log validates and builds its tables.
    capsys.readouterr()
    assert main(["validate", str(out.parent)]) == 0
    tables = tmp_path / "processed"
    assert main(["process", str(out.parent), "--out", str(tables)]) == 0
    trials = pd.read_csv(tables / "trials.csv")
    assert trials["method"].tolist() == ["CASA"] and bool(trials["success"].iloc[0])

    # The node held its rate; its numbers are in its output (docs/ros2.md quotes them).
    line = next(line for line in log.splitlines() if "Hz" in line)
    rate = float(line.split(" Hz")[0].split()[-1])
    assert 19.0 < rate < 21.0, line
    print(line)
