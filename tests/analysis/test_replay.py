"""``casa replay``: a replay with a trial's own settings reproduces its log; counterfactuals.

The trials are short simulated known_goal runs (pybullet headless, a scripted expert
driving to the green goal for at most 8 s), written and read back as casa-trial/1.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from casa_core.analysis.replay import COLUMNS, replay_differences, replay_trial
from casa_core.cli import main
from casa_core.cli.replay import SUMMARY_COLUMNS
from casa_core.io import read_trial
from casa_core.scene import load_scene

SCENE = load_scene()
DURATION = 8.0
#: Control ticks per inference step: 0.5 s / 0.05 s.
PER_STEP = 10


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    """A dataset folder ``ds/p01/known_goal_<METHOD>`` with one trial per method."""
    from casa_core.study.closed_loop import run_trial
    from casa_core.study.key_sources import WaypointKeys

    folder = tmp_path_factory.mktemp("replay") / "ds"
    green = SCENE.goals["green"]
    for method in ("NA", "PBA", "CASA"):
        expert = WaypointKeys([[*green, 0.0]])
        result = run_trial(
            SCENE, "known_goal", method, expert, participant="p01", max_duration=DURATION
        )
        result.write(folder / "p01" / f"known_goal_{method}")
    return folder


def trial(dataset, method):
    return read_trial(dataset / "p01" / f"known_goal_{method}")


@pytest.mark.parametrize("method", ["CASA", "PBA"])
def test_own_settings_reproduce_the_log_exactly(dataset, method):
    # The log holds shortest round-trip floats (read back bit for bit) and the replay
    # does the closed loop's float operations in its order: nothing may differ.
    meta, frame = trial(dataset, method)
    replayed = replay_trial(meta, frame, SCENE)
    assert replay_differences(frame, replayed) == {"beta": 0.0, "belief": 0.0, "alpha": 0.0}
    # The assistance was real: alpha fell below 1, so the robot's share was removed.
    assert frame["alpha"].min() < 0.9


def test_a_replay_has_one_row_per_step_and_intent(dataset):
    meta, frame = trial(dataset, "CASA")
    replayed = replay_trial(meta, frame, SCENE)
    assert list(replayed.columns) == list(COLUMNS)
    # Rows are ticks 0..n-1; inference runs at every 10th tick after the first.
    steps = (len(frame) - 1) // PER_STEP
    assert len(replayed) == steps * len(meta["intents"])
    assert replayed["intent"].tolist() == meta["intents"] * steps
    assert replayed["t"].tolist() == [0.5 * (1 + i // 2) for i in range(len(replayed))]
    per_step = replayed.groupby("t")[["alpha", "theta_star", "misspecified"]].nunique()
    assert (per_step == 1).all().all()


def test_na_replayed_under_confidence_arbitration_is_the_counterfactual(dataset):
    meta, frame = trial(dataset, "NA")
    assert (frame["alpha"] == 1.0).all()
    replayed = replay_trial(meta, frame, SCENE, arbitration="confidence")
    # The arm applied alpha = 1 throughout (the logged alpha), so no robot share is
    # removed from the evidence: beta and belief are the log's own ...
    differences = replay_differences(frame, replayed)
    assert differences["beta"] == 0.0 and differences["belief"] == 0.0
    # ... and alpha is CASA's min(1, 1 / beta_hat(theta*)), below 1 at the end.
    last = replayed[replayed["t"] == replayed["t"].max()]
    star = last[last["intent"] == last["theta_star"]].iloc[0]
    assert star["alpha"] == min(1.0, 1.0 / star["beta"])
    assert star["alpha"] < 1.0
    assert differences["alpha"] > 0.0


def test_cli_on_a_dataset_folder(dataset, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["replay", str(dataset), "--out", str(out)]) == 0
    summary = pd.read_csv(out / "replay.csv", keep_default_na=False)
    assert list(summary.columns) == SUMMARY_COLUMNS
    rows = summary.set_index("method")
    # NA trials found in a folder are not replayed by default.
    assert rows.loc["NA", "status"] == "skipped" and "--methods" in rows.loc["NA", "reason"]
    for method in ("PBA", "CASA"):
        assert rows.loc[method, "status"] == "replayed"
        for column in ("max_diff_beta", "max_diff_belief", "max_diff_alpha"):
            assert float(rows.loc[method, column]) == 0.0
        table = pd.read_csv(out / "p01" / f"known_goal_{method}.replay.csv")
        assert list(table.columns) == list(COLUMNS)
        _, frame = trial(dataset, method)
        assert len(table) == (len(frame) - 1) // PER_STEP * 2  # steps x (green, purple)
        assert int(rows.loc[method, "steps"]) == (len(frame) - 1) // PER_STEP
        for figure in ("replay", "path"):
            png = out / "p01" / f"known_goal_{method}.{figure}.png"
            assert png.read_bytes().startswith(b"\x89PNG")
    said = capsys.readouterr().out
    assert "2 trial(s) replayed, 1 skipped" in said
    assert "(0 where the trials' own settings are reproduced)" in said


def test_a_named_file_is_replayed_whatever_its_method(dataset, tmp_path, capsys):
    out = tmp_path / "out"
    stem = dataset / "p01" / "known_goal_NA"  # a stem names its trial
    assert main(["replay", str(stem), "--arbitration", "confidence", "--out", str(out)]) == 0
    # A counterfactual's differences from the log are its effect, and the summary says so.
    assert "(expected: --arbitration changed the settings" in capsys.readouterr().out
    summary = pd.read_csv(out / "replay.csv", keep_default_na=False)
    assert summary["status"].tolist() == ["replayed"]
    assert summary["arbitration"].tolist() == ["confidence"]
    assert (out / "known_goal_NA.replay.csv").is_file()


def test_an_unknown_intent_is_skipped_with_its_reason(dataset, tmp_path, capsys):
    folder = tmp_path / "ds"
    shutil.copytree(dataset, folder)
    meta_path = folder / "p01" / "known_goal_CASA.json"
    meta = json.loads(meta_path.read_text())
    meta_path.write_text(json.dumps({**meta, "intents": [*meta["intents"], "blue"]}))
    out = tmp_path / "out"
    assert main(["replay", str(folder), "--out", str(out)]) == 0
    summary = pd.read_csv(out / "replay.csv", keep_default_na=False).set_index("method")
    assert summary.loc["CASA", "status"] == "skipped"
    assert "intent 'blue' is not a goal of the scene" in summary.loc["CASA", "reason"]
    assert summary.loc["PBA", "status"] == "replayed"
    assert "known_goal_CASA skipped" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (["--preset", "nope"], "invalid choice: 'nope'"),
        (["--arbitration", "nope"], "--arbitration 'nope'"),
        (["--lam", "-1"], "must be a finite number >= 0"),
        (["--intents", "nowhere"], "--intents nowhere: no such file or folder"),
    ],
)
def test_bad_arguments_exit_2_with_a_message(dataset, tmp_path, capsys, options, said):
    assert status(["replay", str(dataset), "--out", str(tmp_path), *options]) == 2
    assert said in capsys.readouterr().err


def test_a_missing_path_exits_2(tmp_path, capsys):
    assert status(["replay", str(tmp_path / "none"), "--out", str(tmp_path / "out")]) == 2
    assert "no such trial, file or folder" in capsys.readouterr().err


def status(argv) -> int:
    """The exit status of ``casa ARGV``: returned, or argparse's on a bad option."""
    try:
        return main(argv)
    except SystemExit as error:
        return error.code


def test_another_preset_reaches_the_assistant(dataset, tmp_path):
    # "original" takes the arm's executed motion as evidence and counts idle steps:
    # on an assisted trial its beta cannot be the logged (commanded-evidence) one.
    out = tmp_path / "out"
    assert main(["replay", str(dataset), "--preset", "original", "--out", str(out)]) == 0
    summary = pd.read_csv(out / "replay.csv", keep_default_na=False).set_index("method")
    assert summary.loc["CASA", "preset"] == "original"
    assert summary.loc["CASA", "evidence"] == "executed"
    assert float(summary.loc["CASA", "max_diff_beta"]) > 1e-3


def test_differences_are_nan_where_the_log_has_no_column(dataset):
    meta, frame = trial(dataset, "CASA")
    replayed = replay_trial(meta, frame, SCENE)
    bare = frame[["t", "x", "y", "z", "rot", "keys"]]
    assert all(np.isnan(value) for value in replay_differences(bare, replayed).values())


def test_a_dataset_replays_each_trial_with_the_intents_its_participant_folder_keeps(tmp_path):
    # As `casa session` keeps them: p01/.session/library/learned_red.intent.json. p02 ran
    # the same trial but keeps no intent: p01's must not serve it.
    from casa_core.learning.library import load_intent
    from casa_core.study.closed_loop import known_goal_intents, run_trial
    from casa_core.study.key_sources import WaypointKeys
    from tests.learning.test_library import make_intent, save

    folder = tmp_path / "ds"
    path = save(folder / "p01" / ".session" / "library", make_intent("learned_red"))
    for participant in ("p01", "p02"):
        intents = [*known_goal_intents(SCENE), load_intent(path).intent]
        result = run_trial(
            SCENE,
            "unknown_goal",
            "CASA",
            WaypointKeys([[*SCENE.goals["red"], 0.0]]),
            participant=participant,
            intents=intents,
            phase="after_learning",
            max_duration=3.0,
        )
        result.write(folder / participant / "unknown_goal_CASA_after")
    out = tmp_path / "out"
    assert main(["replay", str(folder), "--out", str(out)]) == 0
    rows = pd.read_csv(out / "replay.csv", keep_default_na=False).set_index("participant")
    assert rows.loc["p01", "status"] == "replayed"
    for column in ("max_diff_beta", "max_diff_belief", "max_diff_alpha"):
        assert float(rows.loc["p01", column]) == 0.0
    assert rows.loc["p02", "status"] == "skipped"
    assert "'learned_red' is not a goal of the scene" in rows.loc["p02", "reason"]
    # --intents replaces what the dataset keeps.
    other = tmp_path / "other"
    assert main(["replay", str(folder), "--out", str(other), "--intents", str(path)]) == 0
    rows = pd.read_csv(other / "replay.csv", keep_default_na=False)
    assert rows["status"].tolist() == ["replayed", "replayed"]
