"""The casa-trial/1 contract (docs/data-contracts.md): round trips and every rule's error."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pandas as pd
import pytest
from test_logs_synthetic import trial_frame, write_dataset

from casa_core.io import (
    SCHEMA,
    SURVEY_COLUMNS,
    LogError,
    check_meta,
    check_paths,
    find_files,
    parse_trial_csv,
    read_surveys,
    read_trial,
    validate_paths,
    write_surveys,
    write_trial,
)
from casa_core.vocabulary import QUESTIONS

META = {
    "participant": "p01",
    "task": "known_goal",
    "method": "CASA",
    "phase": "no_misspecification",
    "source": "human",
    "intents": ["green", "purple"],
}


def small_frame() -> pd.DataFrame:
    return pd.DataFrame(
        {
            "t": [0.0, 0.05, 0.1],
            "x": [0.45, 0.4525, 0.455],
            "y": [-0.22, -0.22, -0.22],
            "z": [0.38, 0.38, 0.38],
            "rot": [0.0, 0.0, 0.0],
            "keys": ["x+", "x+ rot-", ""],
            "alpha": [1.0, 0.5, 0.25],
            "beta:green": [0.0, 1.5, 2.0],
            "belief:green": [0.5, 0.75, 0.9],
        }
    )


def test_round_trip_keeps_every_value(tmp_path):
    frame = small_frame()
    write_trial(tmp_path / "p01" / "trial.1", META, frame)
    meta, read = read_trial(tmp_path / "p01" / "trial.1")
    assert meta == {"schema": SCHEMA, **META}
    pd.testing.assert_frame_equal(read, frame)
    # A dotted stem stays one stem: no "trial.csv" next to "trial.1.csv".
    assert sorted(p.name for p in (tmp_path / "p01").iterdir()) == ["trial.1.csv", "trial.1.json"]


def test_written_files_are_deterministic_bytes(tmp_path):
    frame = trial_frame("unknown_skill", intents=("green",), rng=np.random.default_rng(3))
    for folder in ("a", "b"):
        write_trial(tmp_path / folder / "trial", META, frame)
    for suffix in (".csv", ".json"):
        a = (tmp_path / "a" / f"trial{suffix}").read_bytes()
        assert a == (tmp_path / "b" / f"trial{suffix}").read_bytes()


# Each case breaks exactly one rule of the contract; the problem must name the
# file, where in it, and that rule.
META_CASES = [
    ({"schema": "casa-trial/2"}, "key 'schema'", "schema"),
    ({"participant": " "}, "key 'participant'", "non-empty-string"),
    ({"task": "pouring"}, "key 'task'", "enum"),
    ({"method": "na"}, "key 'method'", "enum"),
    ({"source": "robot"}, "key 'source'", "enum"),
    ({"phase": "after_learning"}, "key 'phase'", "task-phase"),
    ({"mood": "good"}, "key 'mood'", "unknown-key"),
    ({"intents": ["green", "green"]}, "key 'intents'", "intent-names"),
    ({"intents": "green"}, "key 'intents'", "intent-names"),
]


@pytest.mark.parametrize("change, where, rule", META_CASES)
def test_each_metadata_rule_is_reported(tmp_path, change, where, rule):
    with pytest.raises(LogError) as raised:
        write_trial(tmp_path / "t", {**META, **change}, small_frame())
    assert [(p.file, p.where, p.rule) for p in raised.value.problems] == [
        (str(tmp_path / "t.json"), where, rule)
    ]
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_missing_key_and_method_of_a_phase(tmp_path):
    meta = {k: v for k, v in META.items() if k != "source"}
    meta.update(task="unknown_goal", phase="demonstration", method="CASA")
    problems = check_meta({"schema": SCHEMA, **meta}, "m.json")
    assert {(p.where, p.rule) for p in problems} == {
        ("key 'source'", "required-key"),
        ("key 'method'", "phase-method"),
    }


def _with(frame: pd.DataFrame, column: str, row: int, value) -> pd.DataFrame:
    frame = frame.copy()
    frame[column] = frame[column].astype(object)
    frame.loc[row, column] = value
    return frame


# Line numbers count the header as line 1, so data row i is on line i + 2.
FRAME_CASES = [
    (lambda f: _with(f, "x", 1, "far"), "column 'x', line 3", "finite-number"),
    (lambda f: _with(f, "y", 2, float("inf")), "column 'y', line 4", "finite-number"),
    (lambda f: _with(f, "t", 2, 0.05), "column 't', line 4", "t-increasing"),
    (lambda f: _with(f, "t", 0, -1.0), "column 't', line 2", "range"),
    (lambda f: _with(f, "keys", 0, "x+ up"), "column 'keys', line 2", "keys"),
    (lambda f: _with(f, "keys", 1, "x+ x+"), "column 'keys', line 3", "keys"),
    (lambda f: _with(f, "alpha", 2, 1.5), "column 'alpha', line 4", "range"),
    (lambda f: _with(f, "belief:green", 0, -0.1), "column 'belief:green', line 2", "range"),
    (lambda f: _with(f, "beta:green", 0, -0.1), "column 'beta:green', line 2", "range"),
    (lambda f: f.drop(columns="rot"), "column 'rot'", "required-column"),
    (lambda f: f.assign(speed=1.0), "column 'speed'", "unknown-column"),
    (lambda f: f.assign(**{"beta:red": 1.0}), "column 'beta:red'", "intent-name"),
    (lambda f: f.iloc[:0], "", "non-empty"),
]


@pytest.mark.parametrize("change, where, rule", FRAME_CASES)
def test_each_frame_rule_is_reported(tmp_path, change, where, rule):
    with pytest.raises(LogError) as raised:
        write_trial(tmp_path / "t", META, change(small_frame()))
    assert [(p.file, p.where, p.rule) for p in raised.value.problems] == [
        (str(tmp_path / "t.csv"), where, rule)
    ]
    assert list(tmp_path.iterdir()) == []


def test_every_problem_of_a_file_is_listed_at_once(tmp_path):
    write_trial(tmp_path / "t", META, small_frame())
    csv = tmp_path / "t.csv"
    lines = csv.read_text().splitlines()
    lines[1] = lines[1].replace("x+", "jump")  # keys, line 2
    lines[3] = "abc" + lines[3][lines[3].index(",") :]  # t, line 4
    csv.write_text("\n".join(lines) + "\n")
    (tmp_path / "t.json").write_text(json.dumps({**META, "task": "nope"}))
    with pytest.raises(LogError) as raised:
        read_trial(tmp_path / "t")
    rules = sorted(p.rule for p in raised.value.problems)
    assert rules == ["enum", "finite-number", "keys", "required-key"]  # schema key missing too
    assert "line 4" in str(raised.value) and "line 2" in str(raised.value)


def test_long_runs_of_bad_lines_are_counted_not_spelled_out():
    header = "t,x,y,z,rot,keys\n"
    body = "".join(f"{i},nan,0,0,0,\n" for i in range(25))
    _, problems = parse_trial_csv(header + body, "f.csv")
    (problem,) = problems
    assert problem.where.startswith("column 'x', lines 2, 3, 4")
    assert problem.where.endswith("(and 15 more)")


def test_unreadable_files(tmp_path):
    (tmp_path / "a.json").write_text("{not json")
    (tmp_path / "a.csv").write_text("")
    (tmp_path / "b.csv").write_text("t,x,x,y,z,rot,keys\n")
    (tmp_path / "b.json").write_text(json.dumps({"schema": SCHEMA, **META}))
    (tmp_path / "c.json").write_text(json.dumps({"schema": SCHEMA, **META}))
    found = {(p.file, p.rule) for p in validate_paths([tmp_path])}
    assert found == {
        (str(tmp_path / "a.json"), "json"),
        (str(tmp_path / "a.csv"), "csv-format"),
        (str(tmp_path / "b.csv"), "unique-columns"),
        (str(tmp_path / "c.csv"), "pair"),
    }


def test_surveys_round_trip_and_rules(tmp_path):
    answers = pd.DataFrame(
        [
            ["p01", "known_goal", "CASA", "no_misspecification", q, s]
            for q, s in zip(QUESTIONS, (7, 1, 4), strict=True)
        ],
        columns=list(SURVEY_COLUMNS),
    )
    write_surveys(tmp_path / "surveys.csv", answers)
    read = read_surveys(tmp_path / "surveys.csv")
    pd.testing.assert_frame_equal(read, answers)
    bad = answers.astype({"score": object})
    bad.loc[0, "score"] = "8"
    bad.loc[1, "score"] = "2.5"
    bad.loc[2, "question"] = "fun"
    bad = pd.concat([bad, bad.iloc[[0]]])
    with pytest.raises(LogError) as raised:
        write_surveys(tmp_path / "x" / "surveys.csv", bad)
    assert {(p.where, p.rule) for p in raised.value.problems} == {
        ("column 'score', lines 2, 3, 5", "likert-score"),
        ("column 'question', line 4", "enum"),
        ("line 5", "unique-answer"),
    }


def test_folder_checks_pairs_duplicates_and_ignores_other_files(tmp_path):
    write_dataset(tmp_path, participants=("p01",), surveys=True)
    (tmp_path / "README.md").write_text("notes")
    (tmp_path / ".hidden.csv").write_text("garbage")
    # The same condition twice would be counted twice by the statistics.
    copy = tmp_path / "p01" / "again"
    meta, frame = read_trial(tmp_path / "p01" / "known_goal_NA_no_misspecification")
    write_trial(copy, meta, frame)
    checks = {c.file.relative_to(tmp_path).as_posix(): c for c in check_paths([tmp_path])}
    assert checks["README.md"].kind == "other" and checks["README.md"].ok
    assert ".hidden.csv" not in checks
    assert checks["surveys.csv"].kind == "surveys" and checks["surveys.csv"].ok
    bad = sorted(name for name, c in checks.items() if not c.ok)
    assert bad == ["p01/again.csv", "p01/known_goal_NA_no_misspecification.csv"]
    assert {p.rule for n in bad for p in checks[n].problems} == {"unique-condition"}


def test_validate_paths_on_files_and_missing_paths(tmp_path):
    write_trial(tmp_path / "t", META, small_frame())
    assert validate_paths([tmp_path / "t.json"]) == []
    assert validate_paths([tmp_path / "t.csv"]) == []
    (problem,) = validate_paths([tmp_path / "nowhere"])
    assert problem.rule == "exists"
    (tmp_path / "empty").mkdir()
    (problem,) = validate_paths([tmp_path / "empty"])
    assert problem.rule == "non-empty"


def test_checking_never_modifies_raw_files(tmp_path):
    write_dataset(tmp_path, participants=("p01",))
    (tmp_path / "p01" / "broken.json").write_text("{")

    def digest():
        return {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in find_files(tmp_path)}

    before = digest()
    assert validate_paths([tmp_path])
    assert digest() == before


def test_ragged_rows_and_blank_lines():
    header = "t,x,y,z,rot,keys\n"
    # Rows with too few or too many fields are named by their line; blank lines are skipped
    # but still counted, so line numbers match the file as an editor shows it.
    text = header + "0,1,1,1,0,x+\n\n0.05,1,1\n0.1,1,1,1,0,x+,5\n0.15,1,1,1,0,\n"
    _, problems = parse_trial_csv(text, "f.csv")
    assert [(p.where, p.rule) for p in problems] == [("lines 4, 5", "csv-format")]
    frame, problems = parse_trial_csv(header + "\n0,1,1,1,0,x+\n\n0.05,1,1,1,0,x+\n", "f.csv")
    assert problems == [] and frame.index.tolist() == [0, 1]
    _, problems = parse_trial_csv(header + "\n0,1,1,1,0,x+\n\n0.05,1,nan,1,0,\n", "f.csv")
    assert [p.where for p in problems] == ["column 'y', line 5"]


def test_write_normalizes_no_keys_and_refuses_non_json_metadata(tmp_path):
    frame = small_frame()
    frame["keys"] = [None, "x+", float("nan")]
    write_trial(tmp_path / "t", META, frame)
    assert read_trial(tmp_path / "t")[1]["keys"].tolist() == ["", "x+", ""]
    with pytest.raises(LogError) as raised:
        write_trial(tmp_path / "u", {**META, "seed": np.int64(3)}, small_frame())
    assert [p.rule for p in raised.value.problems] == ["json-value"]
    assert not (tmp_path / "u.json").exists()


def test_metadata_values_of_the_wrong_type_are_problems_not_crashes():
    meta = {"schema": SCHEMA, **META, "phase": ["demonstration"], "method": ["NA"]}
    problems = check_meta(meta, "m.json")
    assert [(p.where, p.rule) for p in problems] == [
        ("key 'method'", "enum"),
        ("key 'phase'", "enum"),
    ]


def test_written_logs_are_readable_by_everyone(tmp_path):
    write_trial(tmp_path / "t", META, small_frame())
    for suffix in (".json", ".csv"):
        assert (tmp_path / f"t{suffix}").stat().st_mode & 0o777 == 0o644
