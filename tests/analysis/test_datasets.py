"""A raw dataset folder into its processed tables: contract columns, determinism, bad input."""

from __future__ import annotations

import hashlib
import json

import pandas as pd
import pytest

from casa_core.analysis import datasets, metrics
from casa_core.assist import tasks
from casa_core.io import check_meta, find_files, read_table, read_trial
from tests.io.test_logs_synthetic import SCENE, write_dataset

# The column contract with users (docs/data-contracts.md); extra columns may follow.
TRIALS = [
    "dataset",
    "participant",
    "task",
    "method",
    "phase",
    "source",
    "error",
    "efficiency",
    "effort",
    "effort_ticks",
    "relative_effort",
    "duration",
]
STEPS = ["participant", "task", "method", "phase", "t", "alpha", "intent", "beta", "belief"]
LIKERT = ["participant", "task", "method", "phase", "question", "score"]


@pytest.fixture(scope="module")
def raw(tmp_path_factory):
    folder = tmp_path_factory.mktemp("raw") / "pilot"
    write_dataset(folder, participants=("p01", "p02"), seed=1)
    return folder


def process(raw, out, scene, **options) -> datasets.DatasetTables:
    """What ``casa process`` does: a dataset's tables built and written."""
    tables = datasets.build_tables(raw, scene, **options)
    datasets.write_tables(tables, out)
    return tables


def test_tables_follow_the_column_contract(raw, tmp_path):
    tables = process(raw, tmp_path, SCENE)
    trials = pd.read_csv(tmp_path / "trials.csv")
    steps = pd.read_csv(tmp_path / "steps.csv")
    likert = pd.read_csv(tmp_path / "likert.csv")
    assert list(trials.columns[: len(TRIALS)]) == TRIALS
    assert list(steps.columns[: len(STEPS)]) == STEPS
    assert set(LIKERT + ["dataset", "source"]) <= set(likert.columns)
    assert len(trials) == 2 * 11 and (trials["dataset"] == "pilot").all()
    assert len(likert) == 2 * 11 * 3
    assert set(likert["source"]) == {"simulated"}  # from the trials: no source column
    assert len(tables.validation) == 2 * 11 + 1 and set(tables.validation["status"]) == {"ok"}


def test_trials_rows_are_the_metrics_of_each_log(raw, tmp_path):
    trials = datasets.build_tables(raw, SCENE).trials.set_index("trial")
    meta, frame = read_trial(raw / "p02" / "unknown_skill_PBA_before_learning")
    expected = metrics.trial_metrics(
        frame, tasks.intended_trajectory("unknown_skill", SCENE), dt=0.05
    )
    row = trials.loc["p02/unknown_skill_PBA_before_learning"]
    flags = {"timed_out", "success"}
    for key, value in expected.items():
        if key in flags:
            continue
        if key == "input":
            assert row[key] == value == "keyboard"
            continue
        if value is None:  # arrival, of a trial that does not succeed
            assert pd.isna(row[key]), key
        else:
            assert row[key] == pytest.approx(value, rel=1e-12), key
    # The synthetic logs do not say their time limit: timed_out stays empty.
    assert expected["timed_out"] is None and pd.isna(row["timed_out"])
    assert row["success"] == expected["success"]
    reference = trials.loc["p02/unknown_skill_NA_before_learning", "effort"]
    assert row["relative_effort"] == pytest.approx(expected["effort"] / reference)


def test_steps_are_long_one_row_per_tick_and_intent(raw):
    steps = datasets.build_tables(raw, SCENE).steps
    trial = steps[steps["trial"] == "p01/known_goal_CASA_no_misspecification"]
    _, frame = read_trial(raw / "p01" / "known_goal_CASA_no_misspecification")
    assert len(trial) == 2 * len(frame)  # intents green and purple
    green = trial[trial["intent"] == "green"].reset_index(drop=True)
    pd.testing.assert_series_equal(green["beta"], frame["beta:green"], check_names=False)
    pd.testing.assert_series_equal(green["alpha"], frame["alpha"], check_names=False)
    # NA trials logged neither alpha nor intents: they have no steps.
    assert not steps["method"].eq("NA").any()


def test_steps_give_the_distance_to_each_intents_goal(raw):
    steps = datasets.build_tables(raw, SCENE).steps
    trial = steps[steps["trial"] == "p01/known_goal_CASA_no_misspecification"]
    _, frame = read_trial(raw / "p01" / "known_goal_CASA_no_misspecification")
    for name in ("green", "purple"):
        mine = trial[trial["intent"] == name].reset_index(drop=True)
        # Euclid written out: the logged point against the scene's goal.
        goal = SCENE.goals[name]
        expected = sum((frame[axis] - goal[i]) ** 2 for i, axis in enumerate("xyz")) ** 0.5
        pd.testing.assert_series_equal(mine["distance"], expected, check_names=False)
    # An intent the scene has no goal for (a learned one) has no distance.
    learned = frame.assign(**{"beta:learned_pour": 1.0})
    rows = datasets._steps(learned, {}, "pilot", "t", goals=SCENE.goals)
    assert rows.loc[rows["intent"] == "learned_pour", "distance"].isna().all()
    assert rows.loc[rows["intent"] == "green", "distance"].notna().all()


def test_same_raw_files_give_the_same_bytes(raw, tmp_path):
    for out in ("a", "b"):
        process(raw, tmp_path / out, SCENE)
        datasets.write_validation([raw], tmp_path / out / "validation.csv")
    for name in ("trials", "steps", "likert", "validation"):
        a = (tmp_path / "a" / f"{name}.csv").read_bytes()
        assert a == (tmp_path / "b" / f"{name}.csv").read_bytes(), name


def _digests(folder):
    return {p: hashlib.sha256(p.read_bytes()).digest() for p in find_files(folder)}


def _break(folder):
    """Two bad trials with three problems, and a bad surveys.csv."""
    json_path = folder / "p01" / "known_goal_PBA_no_misspecification.json"
    meta = json.loads(json_path.read_text())
    json_path.write_text(json.dumps({**meta, "method": "XX", "source": "robot"}))
    csv_path = folder / "p02" / "unknown_goal_CASA_after_learning.csv"
    csv_path.write_text(csv_path.read_text().replace("y+", "left", 1))
    surveys = folder / "surveys.csv"
    surveys.write_text(surveys.read_text() + "p09,known_goal,NA,no_misspecification,useful,9\n")


def test_bad_files_stop_the_dataset_listing_every_problem(tmp_path):
    write_dataset(tmp_path / "ds", participants=("p01", "p02"))
    _break(tmp_path / "ds")
    with pytest.raises(datasets.DatasetInvalid) as raised:
        process(tmp_path / "ds", tmp_path / "out", SCENE)
    rules = sorted(p.rule for p in raised.value.problems)
    assert rules == ["enum", "enum", "keys", "likert-score"]
    assert "3 file(s)" in str(raised.value) and "allow_invalid" in str(raised.value)
    assert not (tmp_path / "out").exists()


def test_allow_invalid_excludes_bad_files_and_lists_them(tmp_path):
    write_dataset(tmp_path / "ds", participants=("p01", "p02"))
    _break(tmp_path / "ds")
    before = _digests(tmp_path / "ds")
    tables = process(tmp_path / "ds", tmp_path / "out", SCENE, allow_invalid=True)
    assert len(tables.trials) == 2 * 11 - 2
    # Only the bad answer is left out: 2 participants x 11 conditions x 3 questions remain.
    assert len(tables.likert) == 2 * 11 * 3
    assert pd.read_csv(tmp_path / "out" / "likert.csv").columns.tolist() == list(
        datasets.LIKERT_COLUMNS
    )
    excluded = tables.validation[tables.validation["status"] == "excluded"]
    assert sorted(set(excluded["file"])) == [
        "p01/known_goal_PBA_no_misspecification.csv",
        "p02/unknown_goal_CASA_after_learning.csv",
        "surveys.csv",
    ]
    assert len(excluded) == 4  # one row per problem
    assert _digests(tmp_path / "ds") == before  # raw files are never modified


def test_a_dataset_without_na_or_surveys_still_builds(tmp_path):
    conditions = [("unknown_goal", "CASA", "before_learning")]
    write_dataset(tmp_path / "ds", participants=("p01",), surveys=False, conditions=conditions)
    tables = datasets.build_tables(tmp_path / "ds", SCENE, dataset="lab")
    assert tables.trials["relative_effort"].isna().all()  # no NA reference
    assert tables.trials["dataset"].tolist() == ["lab"]
    assert tables.likert.empty


def test_trials_end_with_timed_out_success_and_arrival(raw, tmp_path):
    process(raw, tmp_path, SCENE)
    header = (tmp_path / "trials.csv").read_text().splitlines()[0].split(",")
    assert header[-3:] == ["timed_out", "success", "arrival"]
    trials = read_table(tmp_path / "trials.csv")
    assert trials["timed_out"].isna().all()  # no log says its limit
    # Each row's success is task_success of its log against its task's intended end.
    for row in trials.itertuples():
        _, frame = read_trial(raw / row.trial)
        executed = frame[["t", "x", "y", "z", "rot"]].to_numpy()
        intended = tasks.intended_trajectory(row.task, SCENE)
        assert row.success == metrics.task_success(executed, intended), row.trial
        # Arrival: empty exactly when the trial fails, else a tick's t no later than the end.
        if row.success:
            assert row.arrival == metrics.arrival_time(executed, intended), row.trial
            assert row.arrival in set(frame["t"]) and row.arrival <= row.duration
        else:
            assert pd.isna(row.arrival), row.trial


def test_timed_out_comes_from_the_logged_limit(tmp_path):
    methods = ("NA", "PBA", "CASA")
    conditions = [("known_goal", method, "no_misspecification") for method in methods]
    write_dataset(tmp_path / "ds", participants=("p01",), surveys=False, conditions=conditions)
    # NA: a limit at its last tick (it ran out); PBA: a limit 10 s later (it did not);
    # CASA: no limit logged (unknown, an empty cell).
    for method, extra in (("NA", 0.0), ("PBA", 10.0)):
        stem = tmp_path / "ds" / "p01" / f"known_goal_{method}_no_misspecification"
        _, frame = read_trial(stem)
        path = stem.with_suffix(".json")
        meta = json.loads(path.read_text())
        path.write_text(json.dumps({**meta, "max_duration": frame["t"].iloc[-1] + extra}))
    process(tmp_path / "ds", tmp_path / "out", SCENE)
    trials = read_table(tmp_path / "out" / "trials.csv").set_index("method")
    assert trials.loc["NA", "timed_out"] is True and trials.loc["PBA", "timed_out"] is False
    assert pd.isna(trials.loc["CASA", "timed_out"])


META = {
    "schema": "casa-trial/1",
    "participant": "p01",
    "task": "known_goal",
    "method": "NA",
    "phase": "no_misspecification",
    "source": "human",
}


@pytest.mark.parametrize("value", [40, 40.0, 0.5])
def test_max_duration_is_an_optional_positive_number(value):
    assert check_meta(META, "t.json") == []
    assert check_meta({**META, "max_duration": value}, "t.json") == []


@pytest.mark.parametrize("value", [0, -5.0, "40", True, None, float("inf"), float("nan")])
def test_max_duration_must_be_a_positive_finite_number(value):
    problems = check_meta({**META, "max_duration": value}, "t.json")
    assert [(p.where, p.rule) for p in problems] == [("key 'max_duration'", "positive-number")]
    assert "positive number of seconds" in problems[0].message


def test_learned_intents_kept_with_the_logs_are_listed_not_read_as_trials(tmp_path):
    # The simulated study keeps p<N>/intents/<task>/NAME.intent.json beside the logs.
    from casa_core.io import check_paths

    write_dataset(tmp_path, participants=("p01",))
    kept = tmp_path / "p01" / "intents" / "unknown_goal" / "learned_red.intent.json"
    kept.parent.mkdir(parents=True)
    kept.write_text("{}")
    checks = check_paths([tmp_path])
    assert [p for c in checks for p in c.problems] == []
    assert [c.file for c in checks if c.kind == "intent"] == [kept]
    table = datasets.validation_table(checks, tmp_path)
    row = table[table["file"] == "p01/intents/unknown_goal/learned_red.intent.json"]
    assert row[["kind", "status"]].values.tolist() == [["intent", "ignored"]]
