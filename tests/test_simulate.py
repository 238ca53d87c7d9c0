"""The study runner's own logic: seeding, misspecification detection, one real trial set."""

import numpy as np
import pandas as pd
import pytest

from casa_core.config import load_config
from casa_core.io import read_trial, validate_paths
from casa_core.scene import load_scene
from casa_core.study import protocol, simulate

CONFIG = load_config("config/config.yaml", "config/ci.yaml")
SCENE = load_scene()


def test_participant_parameters_depend_only_on_seed_and_index():
    simulation = CONFIG["simulation"]
    first = simulate.participant_params(4, simulation)
    assert first == simulate.participant_params(4, {**simulation, "participants": 50})
    assert first != simulate.participant_params(5, simulation)


def test_misspecification_needs_every_beta_below_epsilon_at_the_end():
    t = np.arange(0, 10, 0.5)
    low = pd.DataFrame({"t": t, "beta:green": 0.5, "beta:purple": 0.2})
    assert protocol.misspecification_detected(low, 1.0)
    # green explains the last seconds: not misspecified
    late = low.assign(**{"beta:green": np.where(t > 8, 2.0, 0.5)})
    assert not protocol.misspecification_detected(late, 1.0)
    # high early confidence that fell away is misspecification ("stays below" at the end)
    early = low.assign(**{"beta:green": np.where(t < 3, 2.0, 0.5)})
    assert protocol.misspecification_detected(early, 1.0)


def test_before_learning_writes_valid_logs_for_the_whole_protocol(tmp_path):
    settings = {**CONFIG["simulation"], "demonstrations": 1, "max_duration": 20.0}
    stems = simulate.simulate_before_learning(0, SCENE, simulation=settings, out_dir=tmp_path)
    assert len(stems) == 10 + 2  # familiarization, 3 + 3 + 3 conditions, 1 demo per task
    assert validate_paths([tmp_path]) == []
    meta, _ = read_trial(tmp_path / "unknown_goal_before_learning_CASA")
    assert meta["inference"] == {"preset": "casa", "evidence": "commanded"}
    assert meta["notes"].startswith("misspecification detected: ")
    again = tmp_path / "again"
    simulate.simulate_before_learning(0, SCENE, simulation=settings, out_dir=again)
    for stem in stems:  # the same seed gives the same logs, byte for byte
        for suffix in (".csv", ".json"):
            assert (again / stem.name).with_suffix(suffix).read_bytes() == stem.with_suffix(
                suffix
            ).read_bytes()


def test_a_participant_index_below_zero_is_refused_before_simulating(tmp_path):
    # Indices are 0-based (casa simulate's --participant is 1-based); -1 reached numpy's
    # seeding and failed there with "expected non-negative integer".
    for call in (
        lambda: simulate.participant_params(-1, CONFIG["simulation"]),
        lambda: simulate.participant_id(-1),
        lambda: simulate.simulate_before_learning(
            -1, SCENE, simulation=CONFIG["simulation"], out_dir=tmp_path
        ),
    ):
        with pytest.raises(ValueError, match="participant index must be an integer >= 0"):
            call()
    assert list(tmp_path.iterdir()) == []


def test_simulate_names_a_missing_scene_file(tmp_path, capsys):
    from casa_core.cli import main

    overlay = tmp_path / "overlay.yaml"
    overlay.write_text(f"scene: {tmp_path / 'none.yaml'}\n")
    code = main(
        ["simulate", "before", "--config", "config/config.yaml", "--config", str(overlay),
         "--out", str(tmp_path / "out")]
    )  # fmt: skip
    assert code == 2
    assert f"cannot read the scene {tmp_path / 'none.yaml'}" in capsys.readouterr().err


def test_measured_training_times_go_to_their_own_timing_table(tmp_path):
    # Without demonstrations nothing is learned (fast): the learning row has no time,
    # the timing row holds it; learning-table gathers each kind into its own table.
    from casa_core.cli import main

    for pid, task in (("p02", "unknown_goal"), ("p01", "unknown_skill")):
        row, timing = simulate.learn_from_demonstrations(
            tmp_path, task, scene=SCENE, seed=1, library=tmp_path / "lib", pid=pid
        )
        assert "train_seconds" not in row and set(timing) == {
            "participant",
            "task",
            "intent",
            "train_seconds",
        }
        pd.DataFrame([row]).to_csv(tmp_path / f"{pid}_{task}.csv", index=False)
        pd.DataFrame([timing]).to_csv(tmp_path / f"{pid}_{task}_timing.csv", index=False)
    args = ["simulate", "learning-table", "--out", str(tmp_path / "learning.csv")]
    learned = [p for p in sorted(tmp_path.glob("p0?_*.csv")) if not p.stem.endswith("_timing")]
    args += ["--rows", *map(str, learned)]
    args += ["--timing", str(tmp_path / "learning_timing.csv")]
    args += ["--timing-rows", *map(str, sorted(tmp_path.glob("*_timing.csv")))]
    assert main(args) == 0
    learning = pd.read_csv(tmp_path / "learning.csv")
    timing = pd.read_csv(tmp_path / "learning_timing.csv")
    assert list(learning["participant"]) == ["p01", "p02"]  # sorted
    assert "train_seconds" not in learning and "train_seconds" in timing
    assert len(timing) == 2
