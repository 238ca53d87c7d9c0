"""`casa calibrate` on datasets: what it writes, and what it refuses.

The recorded dataset is written as `casa teleop` records a person (``source`` human),
with scripted keys standing in for the person; the session dataset is what `casa session`
records (its loop, with tests/study/test_session.py's headless window and scripted keys).
Two datasets are imported by `casa import original`: the synthetic original-format
sessions of tests/io/test_import_original.py (faster than keys allow, so refused), and
original-format sessions written from simulated operators' trials on the authors' layout,
driven the original's way (tests/io/original_reference.py's ``session_of_trial``). Sizes
are the smallest that train (30 simulations).
"""

from __future__ import annotations

import json

import pandas as pd
import pytest

from casa_core.calibration.summaries import SUMMARIES
from casa_core.cli import main
from casa_core.config import load_config
from casa_core.io import read_trial
from casa_core.io.population import PopulationFileError, read_population
from casa_core.scene import load_scene
from casa_core.study.settings import StudySettings
from tests.io.test_import_original import write_session

SMALL = ["--simulations", "30", "--predictive", "4", "--cores", "2", "--seed", "3"]


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    root = tmp_path_factory.mktemp("original")
    folder = root / "sessions" / "P03"
    write_session(folder, "task1a_data.npz", build={"beta": False})
    write_session(folder, "task1b_data.npz")
    write_session(folder, "task1c_data.npz")
    write_session(folder, "task2c_learned_data.npz", build={"n_goals": 3})
    out = root / "raw" / "original"
    assert main(["import", "original", str(folder), "--out", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def imported_operators(tmp_path_factory):
    """Known Goal under NA, PBA and CASA by a simulated operator on the authors' layout
    (measured at link 7, the original's teleoperation), written as the original's session
    files task1a, task1b and task1c, then imported."""
    import numpy as np

    from casa_core.assist.tasks import intended_trajectory
    from casa_core.io.original.importer import ORIGINAL_SCENE
    from casa_core.study.closed_loop import run_trial
    from casa_core.study.participants import ParticipantParams, make_participant
    from tests.io.original_reference import session_of_trial

    root = tmp_path_factory.mktemp("operators")
    scene = load_scene(ORIGINAL_SCENE)
    params = ParticipantParams(0.35, 0.01, 0.015, 0.03, 0.8, 0.02, 2)
    reference = intended_trajectory("known_goal", scene)
    folder = root / "sessions" / "P07"
    folder.mkdir(parents=True)
    for letter, method in zip("abc", ("NA", "PBA", "CASA"), strict=True):
        rng = np.random.default_rng([7, ord(letter)])
        source = make_participant(params, reference, rng=rng, operator="predictive")
        result = run_trial(
            scene, "known_goal", method, source, participant="P07", max_duration=15.0, seed=7
        )
        arrays = session_of_trial(result.frame, ["green", "purple"], logged=method == "CASA")
        np.savez(folder / f"task1{letter}_data.npz", **arrays)
        if method == "NA":  # the same path with no user command: a session the robot drove
            drove = arrays | {"joy_cmd": np.zeros_like(arrays["joy_cmd"])}
            np.savez(folder / "task4a_data.npz", **drove)
    out = root / "raw" / "authors"
    assert main(["import", "original", str(folder), "--out", str(out)]) == 0
    return out, result.frame


def test_an_imported_dataset_of_the_authors_setup_gives_a_population(
    imported_operators, tmp_path, capsys
):
    raw, casa_trial = imported_operators
    meta, frame = read_trial(raw / "P07" / "task1c")
    # The import gives back what the operator did: its keys and its link-7 path.
    assert frame["keys"].tolist() == casa_trial["keys"].tolist()
    path = ["x", "y", "z"]
    assert abs(frame[path].to_numpy() - casa_trial[path].to_numpy()).max() < 1e-6
    assert meta["inference"]["point"] == "link7"
    out = tmp_path / "authors.json"
    capsys.readouterr()
    assert main(["calibrate", str(raw), "--out", str(out), *SMALL]) == 0
    # The session the robot drove is imported flagged, and calibration leaves it out, naming it.
    assert "no-user-command" in json.loads((raw / "P07" / "task4a.json").read_text())["flags"]
    assert f"{raw / 'P07' / 'task4a.csv'}: left out, flagged no-user-command" in (
        capsys.readouterr().err
    )
    assert read_population(out)["dataset"] == "authors"
    table = pd.read_csv(out.with_name("authors_predictive.csv"), keep_default_na=False)
    assert sorted(set(table["method"])) == ["CASA", "NA", "PBA"]
    assert set(table["task"]) == {"known_goal"} and (table["people_trials"] == 1).all()
    assert out.with_name("authors_predictive.png").stat().st_size > 10_000


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    from casa_core.scene import load_scene
    from casa_core.study.closed_loop import run_trial
    from casa_core.study.key_sources import ScriptedKeys

    raw = tmp_path_factory.mktemp("recorded") / "mylab"
    scene = load_scene()
    plan = [("known_goal", method, None) for method in ("NA", "PBA", "CASA")]
    plan.append(("unknown_goal", "CASA", "after_learning"))
    for task, method, phase in plan:
        # A first press after 1 s, as people make it (no operator presses at once).
        keys = ScriptedKeys([(1.0, []), (0.4, ["x+"]), (3.0, ["x+", "y+"]), (1.6, [])])
        result = run_trial(
            scene,
            task,
            method,
            keys,
            participant="P01",
            phase=phase,
            source_kind="human",
            max_duration=6.0,
        )
        result.write(raw / "P01" / f"{task}_{result.meta['phase']}_{method}")
    return raw


@pytest.fixture(scope="module")
def calibrated(recorded, tmp_path_factory):
    out = tmp_path_factory.mktemp("fit") / "population.json"
    assert main(["calibrate", str(recorded), "--out", str(out), *SMALL]) == 0
    return out


def test_a_recorded_dataset_gives_a_population_a_predictive_table_and_a_figure(calibrated):
    document = read_population(calibrated)
    assert document["format"] == "casa-operator-population" and document["version"] == 1
    assert document["dataset"] == "mylab" and document["usable_simulations"] >= 10
    samples = document["posterior"]["log_median_samples"]
    # Nine medians: the six lognormal parameters and the predictive operator's bout,
    # pause and planning (the config's operator).
    assert len(samples) == 1000 and len(samples[0]) == 9
    assert document["posterior"]["parameters"][-3:] == ["bout", "pause", "planning"]
    table = pd.read_csv(calibrated.with_name("population_predictive.csv"), keep_default_na=False)
    # The three known-goal trials (NA, PBA, CASA) are fitted; the learned one is left out.
    assert sorted(set(table["method"])) == ["CASA", "NA", "PBA"]
    assert set(table["task"]) == {"known_goal"} and len(table) == 3 * len(SUMMARIES)
    assert (table["simulated_low"] <= table["simulated_high"]).all()
    assert calibrated.with_name("population_predictive.png").stat().st_size > 10_000


def test_a_dataset_recorded_by_casa_session_gives_a_population(tmp_path):
    from casa_core.scene import DEFAULT_SCENE
    from casa_core.study.session_run import STOPPED, run_session
    from tests.study.test_session import FakeWindow, settings

    def window(scene, *, notify=None):
        # Practice and four trials, then a stop from the pause screen: all kept.
        return FakeWindow(scene, script=["start"] * 5 + ["pause", "abort"])

    dataset = tmp_path / "lab"
    outcome = run_session(
        load_scene(),
        "P05",
        dataset,
        settings=settings(),
        scene_source=DEFAULT_SCENE,
        window_factory=window,
    )
    assert outcome == STOPPED and len(list((dataset / "P05").glob("*.json"))) == 5
    out = tmp_path / "session.json"
    assert main(["calibrate", str(dataset), "--out", str(out), *SMALL]) == 0
    assert read_population(out)["dataset"] == "lab"
    table = pd.read_csv(out.with_name("session_predictive.csv"), keep_default_na=False)
    assert len(table) > 0 and (table["people_trials"] >= 1).all()
    assert out.with_name("session_predictive.png").stat().st_size > 10_000


def test_the_trial_after_learning_is_left_out_with_a_warning(recorded, tmp_path, capsys):
    out = tmp_path / "p.json"
    assert main(["calibrate", str(recorded), "--out", str(out), *SMALL]) == 0
    assert "unknown_goal_after_learning_CASA.csv: left out" in capsys.readouterr().err


def test_an_imported_dataset_is_simulated_on_the_authors_layout_and_a_failed_fit_is_named(
    imported, tmp_path, capsys, monkeypatch
):
    # `casa import original` gives the dataset the authors' layout, whose teleop.mode is
    # the original's (link 7's target by position-only IK), so its trials are simulated
    # there. A fit whose posterior has no draw inside the prior (here made to fail: whether
    # a small network learns an out-of-reach dataset is chance) names the dataset and the
    # scene and writes nothing.
    import casa_core.calibration.calibrate as calibration
    import casa_core.calibration.simulator as simulator

    assert load_scene(imported / "scene.yaml").teleop.mode == "original"
    scenes = []
    built = simulator.Simulator.__init__

    def recording(self, scene, *args, **kwargs):
        scenes.append(scene)
        built(self, scene, *args, **kwargs)

    def failing(*args, **kwargs):
        raise ValueError("only 0.0% of the posterior's draws lie inside the prior")

    monkeypatch.setattr(simulator.Simulator, "__init__", recording)
    monkeypatch.setattr(calibration, "calibrate", failing)
    out = tmp_path / "p.json"
    assert main(["calibrate", str(imported), "--out", str(out), *SMALL]) == 2
    err = capsys.readouterr().err
    assert [scene.teleop.mode for scene in scenes] == ["original"]
    assert f"dataset {imported} in scene {imported / 'scene.yaml'}: only 0.0%" in err
    assert not out.exists() and not out.with_name("p_predictive.csv").exists()


def test_the_same_seed_gives_the_same_population(recorded, calibrated, tmp_path):
    again = tmp_path / "again.json"
    assert main(["calibrate", str(recorded), "--out", str(again), *SMALL]) == 0
    assert again.read_bytes() == calibrated.read_bytes()


def test_the_study_draws_its_participants_from_a_population_file(calibrated, tmp_path):
    overlay = tmp_path / "overlay.yaml"
    overlay.write_text(f"simulation:\n  operator_population: {calibrated}\n", encoding="utf-8")
    settings = StudySettings.from_config(load_config("config/config.yaml", overlay))
    fitted = read_population(calibrated)["population"]
    assert settings.population.deadband.median == fitted["deadband"]["median"]
    assert settings.population.deadband.sigma == 0.25  # the study's spread
    # Intermittent control was fitted with the rest, and the file's values win over the
    # config's; a file without them (a fit of the lookahead operator) takes the config's.
    assert settings.population.pause.median == fitted["pause"]["median"]
    assert settings.population.pause.sigma == 0.3  # INTERMITTENT_SIGMA: the config sets none
    overlay.write_text(
        f"simulation:\n  operator_population: {calibrated}\n"
        "  population:\n    pause: {median: 0.5, sigma: 0.3}\n",
        encoding="utf-8",
    )
    settings = StudySettings.from_config(load_config("config/config.yaml", overlay))
    assert settings.population.pause.median == fitted["pause"]["median"]
    document = json.loads(calibrated.read_text())
    for name in ("bout", "pause", "planning"):
        del document["population"][name]
    lookahead = tmp_path / "lookahead.json"
    lookahead.write_text(json.dumps(document | {"operator": "lookahead"}))
    overlay.write_text(
        f"simulation:\n  operator_population: {lookahead}\n"
        "  population:\n    pause: {median: 0.5, sigma: 0.3}\n",
        encoding="utf-8",
    )
    settings = StudySettings.from_config(load_config("config/config.yaml", overlay))
    assert settings.population.pause.median == 0.5 and settings.population.bout is None
    assert settings.population.deadband.median == fitted["deadband"]["median"]


def test_a_population_file_that_breaks_the_format_is_refused_naming_the_key(calibrated, tmp_path):
    document = json.loads(calibrated.read_text())
    document["population"]["deadband"]["median"] = -1
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document))
    with pytest.raises(PopulationFileError, match="key population/deadband/median"):
        read_population(bad)
    with pytest.raises(PopulationFileError, match="no such population file"):
        read_population(tmp_path / "missing.json")


def test_a_dataset_without_people_is_refused_and_nothing_is_written(tmp_path, capsys):
    from casa_core.scene import load_scene
    from casa_core.study.closed_loop import run_trial
    from casa_core.study.key_sources import ScriptedKeys

    raw = tmp_path / "raw" / "sim"
    result = run_trial(
        load_scene(),
        "known_goal",
        "NA",
        ScriptedKeys([(0.5, ["x+"])]),
        participant="p01",
        max_duration=1.0,
    )
    result.write(raw / "p01" / "known_goal_no_misspecification_NA")
    out = tmp_path / "out" / "p.json"
    assert main(["calibrate", str(raw), "--out", str(out), *SMALL]) == 2
    assert "no trial with source 'human'" in capsys.readouterr().err
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_a_dataset_of_one_trial_is_refused_naming_the_rule(recorded, tmp_path, capsys):
    import shutil

    one = tmp_path / "one"
    (one / "P01").mkdir(parents=True)
    for suffix in (".csv", ".json"):
        name = f"known_goal_no_misspecification_NA{suffix}"
        shutil.copy(recorded / "P01" / name, one / "P01" / name)
    assert main(["calibrate", str(one), "--out", str(tmp_path / "p.json"), *SMALL]) == 2
    assert "1 human trial(s) the simulator can run" in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()


def test_a_population_file_holds_the_fitted_parameters_only():
    from dataclasses import replace

    import numpy as np

    from casa_core.calibration.calibrate import Calibration, population_document
    from casa_core.study.settings import LOGNORMAL_PARAMETERS, Lognormal

    config = StudySettings.from_config(load_config("config/config.yaml")).population
    # The population simulated with: a config's pause, and a bout and planning besides.
    simulated = replace(config, pause=Lognormal(0.5, 0.3), bout=Lognormal(1, 0.3))
    simulated = replace(simulated, planning=Lognormal(1, 0.3))
    for parameters in (LOGNORMAL_PARAMETERS, (*LOGNORMAL_PARAMETERS, "bout", "pause", "planning")):
        n = len(parameters)
        result = Calibration(
            "lab",
            parameters,
            np.zeros((n, 2)),
            np.zeros((1, n)),
            simulated,
            pd.DataFrame(),
            ("NA",),
            1,
            1,
        )
        block = population_document(result, operator="predictive", seed=1)["population"]
        # A lookahead fit (six parameters) writes no intermittent control: the config's.
        assert list(block) == [*parameters, "max_keys"]
