"""The study runner's own logic: seeding, misspecification detection, one real trial set."""

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from casa_core.config import load_config
from casa_core.io import read_trial, validate_paths
from casa_core.scene import load_scene
from casa_core.study import protocol, simulate
from casa_core.study.settings import StudySettings
from casa_core.vocabulary import LEARNED_NAMES, UNKNOWN_TASKS

CONFIG = load_config("config/config.yaml", "config/ci.yaml")
SETTINGS = StudySettings.from_config(CONFIG)
SCENE = load_scene()


def test_participant_parameters_depend_only_on_seed_and_index():
    many = load_config("config/config.yaml", overrides={"simulation": {"participants": 50}})
    first = simulate.participant_params(4, SETTINGS.seed, SETTINGS.population)
    assert StudySettings.from_config(many) == SETTINGS  # the number is no setting of a trial
    assert first != simulate.participant_params(5, SETTINGS.seed, SETTINGS.population)


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
    settings = replace(SETTINGS, demonstrations=1, max_duration=20.0)
    stems = simulate.simulate_before_learning(0, SCENE, settings=settings, out_dir=tmp_path)
    assert len(stems) == 10 + 2  # familiarization, 3 + 3 + 3 conditions, 1 demo per task
    assert validate_paths([tmp_path]) == []
    meta, _ = read_trial(tmp_path / "unknown_goal_before_learning_CASA")
    assert meta["inference"] == {"preset": "casa", "evidence": "commanded"}
    assert meta["notes"].startswith("misspecification detected: ")
    again = tmp_path / "again"
    simulate.simulate_before_learning(0, SCENE, settings=settings, out_dir=again)
    for stem in stems:  # the same seed gives the same logs, byte for byte
        for suffix in (".csv", ".json"):
            assert (again / stem.name).with_suffix(suffix).read_bytes() == stem.with_suffix(
                suffix
            ).read_bytes()


def test_a_participant_index_below_zero_is_refused_before_simulating(tmp_path):
    # Indices are 0-based (casa simulate's --participant is 1-based); -1 reached numpy's
    # seeding and failed there with "expected non-negative integer".
    for call in (
        lambda: simulate.participant_params(-1, SETTINGS.seed, SETTINGS.population),
        lambda: simulate.participant_id(-1),
        lambda: simulate.simulate_before_learning(-1, SCENE, settings=SETTINGS, out_dir=tmp_path),
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


# --- the whole protocol in one call --------------------------------------------------

STAGE_OPTIONS = ["--config", "config/config.yaml", "--config", "config/ci.yaml"]


def _files(root) -> dict:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def _protocol_args(root, participant: int = 2) -> list[str]:
    rows = [str(root / "learning" / f"{task}.csv") for task in UNKNOWN_TASKS]
    timings = [str(root / "learning" / f"{task}_timing.csv") for task in UNKNOWN_TASKS]
    return [
        "simulate", "protocol", *STAGE_OPTIONS, "--participant", str(participant),
        "--before", str(root / "raw" / "before"), "--library", str(root / "intents"),
        "--rows", *rows, "--timing-rows", *timings, "--out", str(root / "raw" / "after"),
    ]  # fmt: skip


def test_the_protocol_writes_the_bytes_of_the_three_stages(tmp_path):
    # Participant 2 of the CI config through `casa simulate before`, `learn` of each
    # unknown task and `after` (the robustness target's jobs), and through `casa simulate
    # protocol` (the power target's one job): the same files, the same bytes, but for the
    # measured training times.
    from casa_core.cli import main

    staged, whole = tmp_path / "stages", tmp_path / "protocol"
    stage = [*STAGE_OPTIONS, "--participant", "2"]
    before = str(staged / "raw" / "before")
    assert main(["simulate", "before", *stage, "--out", before]) == 0
    for task in UNKNOWN_TASKS:
        learning = staged / "learning"
        assert main(["simulate", "learn", *stage, "--task", task, "--before", before,
                     "--library", str(staged / "intents" / task),
                     "--out", str(learning / f"{task}.csv"),
                     "--timing", str(learning / f"{task}_timing.csv")]) == 0  # fmt: skip
    assert main(["simulate", "after", *stage, "--before", before,
                 "--library", str(staged / "intents"),
                 "--out", str(staged / "raw" / "after")]) == 0  # fmt: skip
    assert main(_protocol_args(whole)) == 0
    stages, protocol_files = _files(staged), _files(whole)
    assert sorted(stages) == sorted(protocol_files)
    # ci.yaml's config: 10 trials and 5 demonstrations of each unknown task before
    # learning, each a .json and a .csv; CASA after learning of each unknown task and
    # the surveys; an intent, a learning row and a timing row per unknown task.
    demonstrations = SETTINGS.demonstrations
    assert len([n for n in stages if n.startswith("raw/before/")]) == 2 * (10 + 2 * demonstrations)
    assert len([n for n in stages if n.startswith("raw/after/")]) == 2 * 2 + 1
    intents = {f"intents/{task}/{LEARNED_NAMES[task]}.intent.json" for task in UNKNOWN_TASKS}
    assert intents <= set(stages)
    timings = {name for name in stages if name.endswith("_timing.csv")}
    assert len(timings) == len(UNKNOWN_TASKS)
    for name in set(stages) - timings:
        assert stages[name] == protocol_files[name], name
    for name in timings:
        one, other = (pd.read_csv(root / name) for root in (staged, whole))
        assert (one["train_seconds"] > 0).all() and (other["train_seconds"] > 0).all()
        pd.testing.assert_frame_equal(one.drop(columns="train_seconds"),
                                      other.drop(columns="train_seconds"))  # fmt: skip


def _protocols_args(root, participants: list[int]) -> list[str]:
    """Several participants' protocols in one call, each path with {p}."""
    rows = [str(root / "learning" / f"p{{p}}_{task}.csv") for task in UNKNOWN_TASKS]
    timings = [str(root / "learning" / f"p{{p}}_{task}_timing.csv") for task in UNKNOWN_TASKS]
    return [
        "simulate", "protocol", *STAGE_OPTIONS, "--participant", *map(str, participants),
        "--before", str(root / "raw" / "p{p}" / "before"),
        "--library", str(root / "intents" / "p{p}"), "--rows", *rows,
        "--timing-rows", *timings, "--out", str(root / "raw" / "p{p}" / "after"),
    ]  # fmt: skip


def test_several_protocols_in_one_call_write_the_bytes_of_one_call_each(tmp_path, capsys):
    # The power target's job: a replicate's participants in one process, in turn. Each
    # participant's files are those of its own call, whatever ran before it in the
    # process (here participant 3 first), but for the measured training times.
    from casa_core.cli import main

    together = tmp_path / "together"
    assert main(_protocols_args(together, [3, 2])) == 0
    out = capsys.readouterr().out
    assert out.startswith("casa simulate protocol: participants p03, p02, "), out
    trials = 2 * (10 + 2 * SETTINGS.demonstrations + 2)  # before and after learning
    assert f" {trials} trial(s), 4 learned intent(s), 2 surveys.csv and 8 table(s)" in out, out
    for p in (2, 3):
        alone = tmp_path / f"alone{p}"
        assert main(_protocol_args(alone, participant=p)) == 0
        mine = {
            name: content
            for name, content in _files(together).items()
            if f"/p{p}/" in f"/{name}" or f"/p{p}_" in name
        }
        theirs = {
            name.replace("raw/", f"raw/p{p}/").replace("intents/", f"intents/p{p}/")
            .replace("learning/", f"learning/p{p}_"): content
            for name, content in _files(alone).items()
        }  # fmt: skip
        assert sorted(mine) == sorted(theirs) and len(mine) > 20
        for name, content in theirs.items():
            if not name.endswith("_timing.csv"):
                assert mine[name] == content, name


def test_several_protocols_need_a_participant_field_in_every_path(tmp_path, capsys):
    from casa_core.cli import main

    args = _protocols_args(tmp_path, [1, 2])
    fixed = args.index("--out") + 1
    assert main([*args[:fixed], str(tmp_path / "after")]) == 2
    err = capsys.readouterr().err
    assert f"--out {tmp_path / 'after'}: with several participants every path holds {{p}}" in err
    assert main(_protocols_args(tmp_path, [1, 1])) == 2
    assert "--participant names a participant twice: [1, 1]" in capsys.readouterr().err
    before = ["simulate", "before", *STAGE_OPTIONS, "--participant", "1", "2", "--out", "x"]
    assert main(before) == 2
    assert "casa simulate before: takes one --participant" in capsys.readouterr().err
    assert not tmp_path.exists() or not any(tmp_path.iterdir())


def test_the_protocol_refuses_missing_or_miscounted_outputs(tmp_path, capsys):
    from casa_core.cli import main

    args = _protocol_args(tmp_path)
    rows, timings = args.index("--rows"), args.index("--timing-rows")
    assert main(args[:rows] + args[timings:]) == 2
    assert "casa simulate protocol: needs --rows" in capsys.readouterr().err
    assert main(args[: rows + 2] + args[timings:]) == 2  # one CSV for two tasks
    message = "--rows needs one CSV per unknown task (unknown_goal, unknown_skill), got 1"
    assert message in capsys.readouterr().err
    assert not tmp_path.exists() or not any(tmp_path.iterdir())


def test_a_failed_protocol_leaves_no_folder_half_written(tmp_path, capsys, monkeypatch):
    # The trials before learning fail after writing a log (a full disk): the command
    # says so and exits 2, and no output folder, temporary or not, is left.
    from casa_core.cli import main

    def fail(index, scene, *, out_dir, **options):
        (out_dir / "familiarization_NA.json").write_text("{}")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(simulate, "simulate_before_learning", fail)
    assert main(_protocol_args(tmp_path)) == 2
    assert "casa simulate protocol: [Errno 28] No space left on device" in capsys.readouterr().err
    assert [p for p in tmp_path.rglob("*") if p.is_file()] == []
    assert not (tmp_path / "raw" / "before").exists() and not list(tmp_path.rglob(".*"))
