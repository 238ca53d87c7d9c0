"""``casa validate``: every problem printed with file, where and rule; the exit code."""

from __future__ import annotations

import json

import pandas as pd

from casa_core.analysis import datasets
from casa_core.cli import main
from casa_core.io import read_table
from casa_core.scene import DEFAULT_SCENE
from tests.io.test_logs_synthetic import write_dataset


def test_valid_folder_exits_0(tmp_path, capsys):
    write_dataset(
        tmp_path / "ds",
        participants=("p01",),
        conditions=[("known_goal", "NA", "no_misspecification")],
    )
    assert main(["validate", str(tmp_path / "ds")]) == 0
    err = capsys.readouterr().err
    assert "1 trial(s) and 1 survey file(s) checked, 0 invalid, 0 problem(s)" in err


def test_bad_files_are_all_listed_and_exit_1(tmp_path, capsys):
    stems = write_dataset(tmp_path / "ds", participants=("p01", "p02"), surveys=False)
    meta_path = stems[0].with_name(stems[0].name + ".json")
    meta_path.write_text(json.dumps({**json.loads(meta_path.read_text()), "source": "lab"}))
    lone = tmp_path / "ds" / "p02" / "lone.json"
    lone.write_text("{}")
    assert main(["validate", str(tmp_path / "ds"), str(tmp_path / "missing")]) == 1
    # The problems on standard output (`> problems.txt` keeps them), the counts on error.
    out, err = capsys.readouterr()
    assert f"{meta_path}: key 'source': [enum] is 'lab'" in out
    assert f"{tmp_path / 'ds' / 'p02' / 'lone.csv'}: [pair]" in out
    assert f"{lone}: key 'participant': [required-key] missing" in out
    assert f"{tmp_path / 'missing'}: [exists]" in out
    assert f"casa validate: {tmp_path / 'missing'} does not exist" in out
    # 2 x 11 trials and the lone one, 2 of them bad; the missing path is a problem, not a file.
    assert err == "casa validate: 23 trial(s) checked, 2 invalid, 9 problem(s)\n"


def test_a_path_that_does_not_exist_is_named_and_not_counted_as_a_file(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "nope")]) == 1
    out, err = capsys.readouterr()
    assert f"casa validate: {tmp_path / 'nope'} does not exist" in out
    assert "0 trial(s) checked, 0 invalid, 1 problem(s)" in err


def test_report_and_allow_invalid(tmp_path, capsys):
    stems = write_dataset(tmp_path / "ds", participants=("p01",), surveys=False)
    csv_path = stems[1].with_name(stems[1].name + ".csv")
    csv_path.write_text(csv_path.read_text().replace(",", ";", 1))
    report = tmp_path / "out" / "validation.csv"
    assert main(["validate", str(tmp_path / "ds"), "--report", str(report)]) == 1
    table = read_table(report)
    assert table.columns.tolist() == list(datasets.VALIDATION_COLUMNS)
    assert (table["status"] == "invalid").sum() >= 1 and (table["status"] == "ok").sum() == 10
    assert main(["validate", str(tmp_path / "ds"), "--report", str(report), "--allow-invalid"]) == 0
    table = read_table(report)
    bad = table[table["status"] == "excluded"]
    assert set(bad["file"]) == {csv_path.relative_to(tmp_path / "ds").as_posix()}
    assert "excluded" in capsys.readouterr().err


def test_process_command_writes_the_tables(tmp_path, capsys):
    write_dataset(tmp_path / "ds", participants=("p01",))
    scene = str(DEFAULT_SCENE)
    out = tmp_path / "processed"
    assert main(["process", str(tmp_path / "ds"), "--out", str(out), "--scene", scene]) == 0
    trials = read_table(out / "trials.csv")
    # "NA" stays a method, not a missing value.
    assert sorted(trials["method"].unique()) == ["CASA", "NA", "PBA"]
    assert "11 trial(s)" in capsys.readouterr().out
    (tmp_path / "ds" / "p01" / "known_goal_NA_no_misspecification.json").write_text("[]")
    assert main(["process", str(tmp_path / "ds"), "--out", str(out), "--scene", scene]) == 1
    assert "[json-object]" in capsys.readouterr().err
    pd.testing.assert_frame_equal(read_table(out / "trials.csv"), trials)  # untouched


def test_process_names_the_bad_scene_key_without_a_traceback(tmp_path, capsys):
    write_dataset(tmp_path / "ds", participants=("p01",), surveys=False)
    scene = tmp_path / "scene.yaml"
    scene.write_text(DEFAULT_SCENE.read_text().replace("dt:", "tick:"))
    assert (
        main(
            ["process", str(tmp_path / "ds"), "--out", str(tmp_path / "out")]
            + ["--scene", str(scene)]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert err.startswith(f"casa process: {scene}: teleop.") and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def help_examples(parser):
    """The ``casa ...`` command lines of a parser's epilog (continuations joined)."""
    text = (parser.epilog or "").replace("\\\n", " ")
    lines = [line.strip() for line in text.splitlines()]
    return [line.split("|")[0].split()[1:] for line in lines if line.startswith("casa ")]


def test_every_command_and_subcommand_help_ends_with_an_example_that_parses():
    from casa_core.cli import all_parsers, build_parser

    parsers = all_parsers(build_parser())
    # casa, its 11 commands and the subcommands of figure (5), library (1) and report (3).
    assert len(parsers) >= 21
    for parser in parsers:
        assert "example" in parser.format_help().lower(), parser.prog
        examples = help_examples(parser)
        assert examples, parser.prog
        for argv in examples:
            if "--help" not in argv:
                build_parser().parse_args(argv)  # argparse exits on a bad example


def test_warnings_are_printed_and_exit_0(tmp_path, capsys):
    (stem,) = write_dataset(
        tmp_path / "ds",
        participants=("p01",),
        conditions=[("known_goal", "NA", "no_misspecification")],
        surveys=False,
    )
    csv_path = stem.with_name(stem.name + ".csv")
    table = pd.read_csv(csv_path, keep_default_na=False)
    table.loc[len(table) // 2 :, "t"] += 0.05  # a dropped tick
    csv_path.write_text(table.to_csv(index=False))
    report = tmp_path / "validation.csv"
    assert main(["validate", str(tmp_path / "ds"), "--report", str(report)]) == 0
    out, err = capsys.readouterr()
    assert f"{csv_path}: column 't', line {len(table) // 2 + 2}: warning [tick-irregular]" in out
    assert "1 trial(s) checked, 0 invalid, 1 problem(s) (1 warning(s))" in err
    rows = read_table(report)
    assert rows[["status", "rule"]].values.tolist() == [["warning", "tick-irregular"]]


def test_latin1_files_are_a_message_not_a_traceback(tmp_path, capsys):
    (stem,) = write_dataset(
        tmp_path / "ds",
        participants=("p01",),
        conditions=[("known_goal", "NA", "no_misspecification")],
        surveys=False,
    )
    csv_path = stem.with_name(stem.name + ".csv")
    csv_path.write_bytes(csv_path.read_bytes() + "0.0,0,0,0,0,é\n".encode("latin-1"))
    assert main(["validate", str(tmp_path / "ds")]) == 1
    assert f"{csv_path}: line " in capsys.readouterr().out
