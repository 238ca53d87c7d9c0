"""The casa-trial/1 contract (docs/data-contracts.md): round trips and every rule's error."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from casa_core.io import (
    SCHEMA,
    SURVEY_COLUMNS,
    LogError,
    check_meta,
    check_paths,
    find_files,
    parse_surveys_csv,
    parse_trial_csv,
    read_surveys,
    read_trial,
    validate_paths,
    write_surveys,
    write_trial,
)
from casa_core.vocabulary import QUESTIONS
from tests.io.test_logs_synthetic import trial_frame, write_dataset

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
            "belief:purple": [0.5, 0.25, 0.1],
        }
    )


def test_write_trial_returns_the_trial_as_read_back(tmp_path):
    # A caller keeps write_trial's return instead of reading the files again, so it must
    # be read_trial's answer: the same metadata and the same table, bit for bit, also for
    # floats that the CSV text writes as their shortest repr (1/3, subnormal, near the bound).
    rng = np.random.default_rng(0)
    frame = trial_frame("known_goal", intents=("green", "purple"), rng=rng)
    frame.loc[:3, "x"] = [1 / 3, 5e-324, 1.9999999999999998, -0.0]
    frame["y"] += rng.normal(0.0, 1e-3, size=len(frame))
    kept = write_trial(tmp_path / "trial", META, frame)
    meta, read = read_trial(tmp_path / "trial")
    assert kept[0] == meta
    pd.testing.assert_frame_equal(kept[1], read, check_exact=True)
    assert all(np.array_equal(kept[1][c], read[c]) for c in read.columns if c != "keys")


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
    (lambda f: f.assign(t=f["t"] - 0.01), "column 't', line 2", "range"),
    (lambda f: _with(f, "keys", 0, "x+ up"), "column 'keys', line 2", "keys"),
    (lambda f: _with(f, "keys", 1, "x+ x+"), "column 'keys', line 3", "keys"),
    (lambda f: _with(f, "alpha", 2, 1.5), "column 'alpha', line 4", "range"),
    (lambda f: _with(f, "beta:green", 0, -0.1), "column 'beta:green', line 2", "range"),
    (lambda f: f.drop(columns="rot"), "column 'rot'", "required-column"),
    (lambda f: f.assign(speed=1.0), "column 'speed'", "unknown-column"),
    (lambda f: f.assign(**{"beta:red": 1.0}), "column 'beta:red'", "intent-name"),
    (lambda f: f.iloc[:0], "", "non-empty"),
    # One tick: no duration, no motion (every metric undefined).
    (lambda f: f.iloc[:1], "", "two-rows"),
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
    body = "".join(f"{i * 0.05},nan,0,0,0,\n" for i in range(25))
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
        ("lines 2, 5", "unique-answer"),  # both answers: which one is right is unknown
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


# --------------------------------------------------------------------------- hostile input
# Each case is a file a lab's script might produce; the expected outcome (rule and
# severity) is the one docs/data-contracts.md gives for it.


def _trial(folder, name="t", meta=None, frame=None):
    write_trial(folder / name, {**META, **(meta or {})}, small_frame() if frame is None else frame)
    return folder / f"{name}.csv", folder / f"{name}.json"


def _found(folder):
    """(file name, where, rule, severity) of every problem below ``folder``."""
    return {(Path(p.file).name, p.where, p.rule, p.severity) for p in validate_paths([folder])}


def test_bytes_that_are_not_utf8_name_file_line_and_byte(tmp_path):
    csv_path, json_path = _trial(tmp_path)
    text = csv_path.read_bytes()
    csv_path.write_bytes(text.replace(b"x+ rot-", "x+ rot- é".encode("latin-1")))
    json_path.write_bytes(json_path.read_bytes().replace(b'"human"', '"humän"'.encode("latin-1")))
    header = ",".join(SURVEY_COLUMNS).encode()
    row = "Jürgen,known_goal,CASA,no_misspecification,useful,5".encode("latin-1")
    (tmp_path / "surveys.csv").write_bytes(header + b"\n" + row + b"\n")
    found = {(name, rule) for name, _, rule, _ in _found(tmp_path)}
    assert found == {("t.csv", "utf-8"), ("t.json", "utf-8"), ("surveys.csv", "utf-8")}
    where = {name: w for name, w, _, _ in _found(tmp_path)}
    # Byte offsets counted by hand: the header, then "0.05,...,x+ rot- " on line 3.
    offset = text.index(b"x+ rot-") + len("x+ rot- ")
    assert where["t.csv"] == f"line 3, byte {offset}"
    assert where["surveys.csv"] == f"line 2, byte {len(header) + 1 + 1}"  # 'J', then 'ü'


@pytest.mark.parametrize("key", ["participant", "task", "method", "phase", "source"])
@pytest.mark.parametrize("value", [["a", "b"], {"a": 1}])
def test_unhashable_metadata_values_are_problems(tmp_path, key, value):
    _, json_path = _trial(tmp_path)
    _trial(tmp_path, "u")  # a second trial: the rules across files see both
    meta = json.loads(json_path.read_text())
    json_path.write_text(json.dumps({**meta, key: value}))
    rules = {rule for name, where, rule, _ in _found(tmp_path) if name == "t.json"}
    assert rules == {"non-empty-string" if key == "participant" else "enum"}


@pytest.mark.parametrize(
    "seed, ok", [(7, True), (-1, True), ("7", False), (True, False), (1.5, False)]
)
def test_seed_must_be_an_integer(seed, ok):
    problems = check_meta({"schema": SCHEMA, **META, "seed": seed}, "m.json")
    assert [(p.where, p.rule) for p in problems] == ([] if ok else [("key 'seed'", "integer")])


def _ticks(t) -> pd.DataFrame:
    n = len(t)
    frame = small_frame().iloc[[0] * n].reset_index(drop=True)
    return frame.assign(t=np.asarray(t, dtype=float), keys="")


# The outcome of each time column, from the time rule of docs/data-contracts.md.
TIME_CASES = [
    ("20 Hz", np.arange(40) * 0.05, set()),
    ("rounded", np.round(np.arange(40) * 0.05, 2), set()),
    ("starts within a tick", 0.04 + np.arange(40) * 0.05, set()),
    ("milliseconds", np.arange(40) * 50.0, {("tick-rate", "error")}),
    ("10 Hz", np.arange(40) * 0.1, {("tick-rate", "error")}),
    ("100 Hz", np.arange(40) * 0.01, {("tick-rate", "error")}),
    (
        "one dropped tick",
        np.r_[np.arange(20) * 0.05, 1.05 + np.arange(20) * 0.05],
        {("tick-irregular", "warning")},
    ),
    ("jitter within 10%", np.arange(40) * 0.05 + np.tile([0.0, 0.004], 20), set()),
    ("epoch seconds", 1.7e9 + np.arange(40) * 0.05, {("t-start", "error"), ("range", "error")}),
    ("late start", 2.0 + np.arange(40) * 0.05, {("t-start", "error")}),
    (
        "huge last value",
        np.r_[np.arange(39) * 0.05, 1e12],
        {("range", "error"), ("tick-irregular", "warning")},
    ),
]


@pytest.mark.parametrize("label, t, expected", TIME_CASES, ids=[c[0] for c in TIME_CASES])
def test_time_rule(label, t, expected):
    text = _ticks(t).to_csv(index=False)
    _, problems = parse_trial_csv(text, "t.csv")
    assert {(p.rule, p.severity) for p in problems} == expected


@pytest.mark.parametrize(
    "column, value",
    [("x", 1e308), ("y", -2.5), ("z", 3.0), ("rot", 1e3), ("rot", -101.0)],
)
def test_poses_out_of_the_arms_reach_are_range_problems(column, value):
    _, problems = parse_trial_csv(
        _with(small_frame(), column, 1, value).to_csv(index=False), "t.csv"
    )
    assert [(p.where, p.rule) for p in problems] == [(f"column {column!r}, line 3", "range")]


def test_beliefs_must_sum_to_one():
    frame = small_frame()
    frame.loc[1, "belief:purple"] = 0.2  # 0.75 + 0.2
    _, problems = parse_trial_csv(frame.to_csv(index=False), "t.csv")
    assert [(p.where, p.rule) for p in problems] == [
        ("columns belief:green, belief:purple, line 3", "belief-sum")
    ]
    frame.loc[1, "belief:purple"] = 0.25 + 5e-7  # within the tolerance
    assert parse_trial_csv(frame.to_csv(index=False), "t.csv")[1] == []


@pytest.mark.parametrize("participant", ["../x", "a/b", "a\\b", "..", " p01", "p01 ", "p\x01"])
def test_participant_ids_that_cannot_be_names(tmp_path, participant):
    problems = check_meta({"schema": SCHEMA, **META, "participant": participant}, "m.json")
    assert [(p.where, p.rule) for p in problems] == [("key 'participant'", "participant-id")]
    header = ",".join(SURVEY_COLUMNS)
    text = f"{header}\n{participant},known_goal,CASA,no_misspecification,useful,5\n"
    frame, problems = parse_surveys_csv(text, "surveys.csv")
    assert [(p.where, p.rule) for p in problems] == [
        ("column 'participant', line 2", "participant-id")
    ]
    assert len(frame) == 0


def test_participants_differing_only_by_case_are_a_warning(tmp_path):
    _trial(tmp_path, "a", {"participant": "P01"})
    _trial(tmp_path, "b", {"participant": "p01"})
    found = _found(tmp_path)
    assert found == {
        ("a.json", "key 'participant'", "participant-case", "warning"),
        ("b.json", "key 'participant'", "participant-case", "warning"),
    }
    assert all(check.ok for check in check_paths([tmp_path]))  # kept


def test_surveys_rows_are_checked_one_by_one():
    header = ",".join(SURVEY_COLUMNS)
    rows = [
        "p01,known_goal,CASA,no_misspecification,useful,5",
        "p01,known_goal,CASA,no_misspecification,understood,9",
        "p02,known_goal,CASA,no_misspecification,useful,3",
    ]
    frame, problems = parse_surveys_csv("\n".join([header, *rows]) + "\n", "surveys.csv")
    assert frame["participant"].tolist() == ["p01", "p02"]
    assert [(p.where, p.rule) for p in problems] == [("column 'score', line 3", "likert-score")]
    assert frame.attrs["lines"] == [2, 4]


@pytest.mark.parametrize("mark", [";", "\t"])
def test_a_file_separated_by_another_delimiter_says_so(mark):
    # As a spreadsheet set to a decimal comma saves it: ';' between fields, ',' in numbers.
    rows = [SURVEY_COLUMNS, ["p01", "known_goal", "CASA", "no_misspecification", "useful", "5"]]
    text = "".join(mark.join(row) + "\n" for row in rows)
    trial = "t;x;y;z;rot;keys\n0;0,45;-0,22;0,38;0;x+\n".replace(";", mark)
    for parse, name in ((parse_surveys_csv, "surveys.csv"), (parse_trial_csv, "t.csv")):
        frame, problems = parse(text if name == "surveys.csv" else trial, name)
        assert frame is None and [(p.where, p.rule) for p in problems] == [("line 1", "csv-format")]
        assert f"the file looks separated by {mark!r}" in problems[0].message, problems
        assert "comma-separated" in problems[0].message


def test_an_empty_participant_folder_is_a_warning(tmp_path):
    _trial(tmp_path / "p01")
    (tmp_path / "p02" / "session").mkdir(parents=True)  # named once, at its outermost
    (tmp_path / "p03" / ".session").mkdir(parents=True)  # hidden files are not read
    (tmp_path / "p03" / ".session" / "notes").write_text("")
    assert _found(tmp_path) == {
        ("p02", "", "empty-folder", "warning"),
        ("p03", "", "empty-folder", "warning"),
    }
    # The folder given itself, without logs, stays an error.
    assert ("p02", "", "non-empty", "error") in _found(tmp_path / "p02")


def test_header_only_surveys_is_a_warning(tmp_path):
    _trial(tmp_path)
    (tmp_path / "surveys.csv").write_text(",".join(SURVEY_COLUMNS) + "\n")
    assert _found(tmp_path) == {("surveys.csv", "", "no-answers", "warning")}


def test_answers_without_a_trial_are_a_warning(tmp_path):
    _trial(tmp_path)  # p01, known_goal, CASA, no_misspecification
    header = ",".join(SURVEY_COLUMNS)
    rows = [
        "p01,known_goal,CASA,no_misspecification,useful,5",
        "p01,known_goal,PBA,no_misspecification,useful,5",
        "p09,known_goal,CASA,no_misspecification,useful,5",
    ]
    (tmp_path / "surveys.csv").write_text("\n".join([header, *rows]) + "\n")
    assert _found(tmp_path) == {
        ("surveys.csv", "line 3", "survey-trial", "warning"),
        ("surveys.csv", "line 4", "survey-trial", "warning"),
    }


@pytest.mark.parametrize(
    "name, rule",
    [
        ("T.CSV", "suffix"),
        ("t.Json", "suffix"),
        ("SURVEYS.CSV", "surveys-name"),
        ("Surveys.csv", "surveys-name"),
    ],
)
def test_upper_case_log_names_are_refused(tmp_path, name, rule):
    _trial(tmp_path, "ok")
    (tmp_path / name).write_text("whatever")
    assert _found(tmp_path) == {(name, "", rule, "error")}


def test_symlinks_out_of_the_dataset_are_refused_and_never_read(tmp_path, monkeypatch):
    outside = tmp_path / "outside"
    csv_path, json_path = _trial(outside)
    (outside / "surveys.csv").write_text(",".join(SURVEY_COLUMNS) + "\n")
    ds = tmp_path / "ds"
    _trial(ds, "real")
    (ds / "t.csv").symlink_to(csv_path)
    (ds / "t.json").symlink_to(json_path)
    (ds / "surveys.csv").symlink_to(outside / "surveys.csv")
    (ds / "notes.md").symlink_to(outside / "t.json")
    (ds / "linked").symlink_to(outside, target_is_directory=True)
    (ds / "inner").mkdir()
    (ds / "again").symlink_to(ds / "inner", target_is_directory=True)
    (ds / "gone.csv").symlink_to(tmp_path / "nothing.csv")
    read = []
    real_read_bytes = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda self: read.append(self) or real_read_bytes(self))
    found = _found(ds)
    assert {(name, rule, severity) for name, _, rule, severity in found} == {
        ("t.json", "symlink", "error"),
        ("t.csv", "symlink", "error"),
        ("surveys.csv", "symlink", "error"),
        ("notes.md", "symlink", "error"),
        ("linked", "symlink", "error"),
        ("again", "symlink", "warning"),
        ("inner", "empty-folder", "warning"),  # it holds no file
        ("gone.json", "pair", "error"),
        ("gone.csv", "symlink", "error"),
    }
    assert {p.name for p in read} == {"real.json", "real.csv"}  # nothing outside was opened


def test_warnings_keep_the_file_and_are_listed_in_validation_csv(tmp_path):
    from casa_core.analysis import datasets
    from casa_core.scene import load_scene

    stems = write_dataset(tmp_path / "ds", participants=("p01",), surveys=False)
    meta, frame = read_trial(stems[0])
    frame.loc[len(frame) // 2 :, "t"] += 0.05  # one dropped tick
    write_trial(stems[0], meta, frame)
    tables = datasets.build_tables(tmp_path / "ds", load_scene())
    assert len(tables.trials) == 11
    rows = tables.validation[tables.validation["rule"] != ""]
    assert rows[["status", "rule"]].values.tolist() == [["warning", "tick-irregular"]]


def test_a_fifo_named_like_a_log_is_not_opened(tmp_path):
    _trial(tmp_path)
    os.mkfifo(tmp_path / "surveys.csv")  # opening it for reading would block forever
    assert _found(tmp_path) == {("surveys.csv", "", "readable", "error")}


#: The metadata of a human's Known Goal trial under CASA.
KNOWN_GOAL_META = {
    "schema": "casa-trial/1",
    "participant": "p01",
    "task": "known_goal",
    "method": "CASA",
    "phase": "no_misspecification",
    "source": "human",
}


@pytest.mark.parametrize(
    ("inference", "message"),
    [
        ({"preset": "orignal", "evidence": "commanded"}, "preset is 'orignal', expected one of"),
        ({"preset": "casa", "evidence": "robot"}, "evidence is 'robot', expected one of"),
        ({"preset": "casa"}, "expected an object with the keys preset, evidence"),
        ("casa", "expected an object with the keys preset, evidence"),
    ],
)
def test_the_inference_settings_of_a_trial_are_checked(inference, message):
    meta = KNOWN_GOAL_META
    assert check_meta({**meta, "inference": {"preset": "paper", "evidence": "executed"}}, "t") == []
    [problem] = check_meta({**meta, "inference": inference}, "t.json")
    assert (problem.where, problem.rule) == ("key 'inference'", "inference-settings")
    assert message in problem.message


#: A valid ``inference_steps``: two steps, the second late, over three waypoints.
STEPS = {
    "started": [0.51, 1.52],
    "waypoint": [1, 3],
    "waypoints": [[0.0] * 7, [0.1] * 7, [0.2] * 7, [0.3] * 7],
    "after_trial": {"waypoint": 3, "beta": {"green": -0.5, "purple": None}, "belief": {}},
}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"started": [0.51]}, "waypoint has 2 entries, started 1: one per step"),
        ({"started": [1.52, 0.51]}, "started and waypoint must strictly increase"),
        ({"waypoint": [1, 1]}, "started and waypoint must strictly increase"),
        ({"waypoint": [0, 3]}, "waypoint: expected a list of waypoint indices, each >= 1"),
        ({"started": [0.51, "1.5"]}, "started: expected a list of times in seconds"),
        ({"waypoints": [[0.0] * 6] * 4}, "waypoints: expected 2 or more lists of 7 joint angles"),
        ({"waypoints": [[0.0] * 7] * 3}, "waypoint 3 of the last step is not among the 3"),
        ({"after_trial": {"beta": {"blue": 1.0}}}, "beta names 'blue', which is not in intents"),
        ({"after_trial": {"belief": {"green": "x"}}}, "belief must map intent names to numbers"),
        ({"after_trial": {"alpha": 1.0}}, "after_trial: expected an object with the keys"),
        ({"after_trial": {"waypoint": 4}}, "after_trial: waypoint 4 is not among the 4"),
        ({"steps": []}, "'steps' is not a key of it; allowed: started, waypoint"),
    ],
)
def test_the_logged_inference_steps_of_a_trial_are_checked(change, message):
    meta = {**KNOWN_GOAL_META, "intents": ["green", "purple"]}
    assert check_meta({**meta, "inference_steps": STEPS}, "t.json") == []
    [problem] = check_meta({**meta, "inference_steps": {**STEPS, **change}}, "t.json")
    assert (problem.where, problem.rule) == ("key 'inference_steps'", "inference-steps")
    assert message in problem.message
