"""What the commands say: counts that name what they count, a misspelt option's hint, and
examples and docs that say what the code does (file names, the counterbalancing)."""

from __future__ import annotations

import re

import pytest
import yaml

from casa_core.cli import all_parsers, build_parser, main
from casa_core.config import DEFAULT_CONFIG
from casa_core.study import protocol
from casa_core.study.session import participant_index
from casa_core.vocabulary import TASKS, UNKNOWN_TASKS
from tests.io.test_logs_synthetic import ROOT, write_dataset

DOCS = ROOT / "docs"


def test_validate_counts_trials_and_survey_files_not_files(tmp_path, capsys):
    # 11 trials (22 files) per participant, the dataset's surveys.csv, and a learned intent
    # kept with the logs, which validation lists but does not read.
    write_dataset(tmp_path / "ds", participants=("p01", "p02"))
    (tmp_path / "ds" / "p01" / "learned_red.intent.json").write_text("{}")
    assert main(["validate", str(tmp_path / "ds")]) == 0
    err = capsys.readouterr().err
    assert (
        "casa validate: 22 trial(s) and 1 survey file(s) checked "
        "(1 learned intent file(s) not read), 0 invalid, 0 problem(s)"
    ) in err


def test_simulate_counts_the_trials_it_wrote(tmp_path, capsys):
    overlay = tmp_path / "quick.yaml"
    overlay.write_text(yaml.safe_dump({"simulation": {"max_duration": 0.5, "demonstrations": 0}}))
    out = tmp_path / "before"
    args = ["simulate", "before", "--config", str(DEFAULT_CONFIG), "--config", str(overlay)]
    args += ["--participant", "1"]
    assert main([*args, "--out", str(out)]) == 0
    trials = len(protocol.before_learning(0))
    assert f"casa simulate before: participant p01, {trials} trial(s) written" in (
        capsys.readouterr().out
    )
    assert len(list(out.iterdir())) == 2 * trials  # each trial a .json and a .csv


@pytest.mark.parametrize(
    "argv, usage, hint",
    [
        (["validate", "x", "--alow-invalid"], "casa validate", "--allow-invalid"),
        (["process", "x", "--out", "y", "--scnee=s.yaml"], "casa process", "--scene"),
        (["library", "list", "x", "--alow-invalid"], "casa library list", None),
    ],
)
def test_a_misspelt_option_names_the_commands_usage_and_the_closest_option(
    argv, usage, hint, capsys
):
    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"usage: {usage} [-h]")
    suggestion = f" (did you mean {hint}?)" if hint else ""
    assert err.endswith(f"{usage}: error: unrecognized arguments: {argv[-1]}{suggestion}\n")


#: A trial file named in a doc or an example: a path's last part that starts with a task.
TRIAL_NAME = re.compile(rf"/((?:{'|'.join(TASKS)})_\w+?)(?:\.replay)?(?:\.csv|\.json)?(?![\w.])")


def protocol_stems() -> set[str]:
    """Every trial stem the protocol writes (casa simulate and casa session)."""
    specs = [*protocol.before_learning(0), *protocol.after_learning()]
    specs += [spec for task in UNKNOWN_TASKS for spec in protocol.demonstrations(task)]
    return {spec.stem for spec in specs}


def test_the_trial_files_of_the_docs_and_examples_are_those_the_study_writes():
    texts = {str(path.relative_to(ROOT)): path.read_text() for path in DOCS.glob("*.md")}
    texts["README.md"] = (ROOT / "README.md").read_text()
    for parser in all_parsers(build_parser()):
        texts[parser.prog] = parser.format_help()
    named = {(where, name) for where, text in texts.items() for name in TRIAL_NAME.findall(text)}
    assert named, "the pattern finds the examples"
    wrong = sorted((where, name) for where, name in named if name not in protocol_stems())
    assert not wrong, f"trial files no study writes: {wrong}"
    assert TRIAL_NAME.findall("data/raw/mine/p01/known_goal_NA.csv") == ["known_goal_NA"]


def counterbalancing(page: str) -> str:
    """The sentence of a doc that says which method order a participant takes."""
    text = " ".join((DOCS / page).read_text().split())
    (sentence,) = re.findall(r"participant number i \(.*?mod 6.*?\)\.", text)
    return sentence


def test_the_docs_give_the_counterbalancing_of_the_code_in_the_same_words():
    sentence = counterbalancing("session.md")
    assert counterbalancing("power.md") == sentence
    assert "`(i - 1) mod 6`" in sentence and "counted from 0" in sentence
    # What the code does: participant number i (casa simulate --participant i, index
    # i - 1; a session id ending in i) takes METHOD_ORDERS[(i - 1) mod 6].
    for i in range(1, 14):
        assert participant_index(f"P{i:02d}") == i - 1
        order = protocol.METHOD_ORDERS[(i - 1) % 6]
        assert protocol.method_order(i - 1) == order
        known = [s.method for s in protocol.before_learning(i - 1) if s.task == "known_goal"]
        assert tuple(known) == order
    assert protocol.METHOD_ORDERS[0] == ("NA", "PBA", "CASA")
