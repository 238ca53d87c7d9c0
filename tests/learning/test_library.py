"""The intent library (casa_core.learning.library), `casa learn` and `casa library list`."""

from __future__ import annotations

import base64
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

from casa_core.io import write_trial
from casa_core.learning import IRLConfig, NeuralIntent, cost_network, feature_names, library
from casa_core.scene import load_scene
from casa_core.study.learn_from_logs import read_demonstrations
from casa_core.study.learning_evidence import scene_objects

ROOT = Path(__file__).resolve().parents[2]
OBJECTS = scene_objects(load_scene())
DEMOS = [np.column_stack([np.arange(4) * 0.5, np.full((4, 3), 0.4), np.zeros(4)])]
HISTORY = [{"iteration": 1, "loss": 1.5, "end_moved_m": None, "converged": False}]


def make_intent(name="red_p01", seed=0):
    """An untrained neural intent: weights are what the library must keep, trained or not."""
    config = IRLConfig()
    network = cost_network(
        len(feature_names(OBJECTS)),
        hidden=config.hidden,
        negative_slope=config.negative_slope,
        seed=seed,
    )
    guide = np.linspace([0.45, -0.22, 0.38, 0.0], [0.40, 0.22, 0.12, 0.0], 31)
    return NeuralIntent(
        name,
        network,
        objects=OBJECTS,
        cost_scale=config.cost_scale,
        length_scale=config.length_scale,
        guides=[guide],
        cost_offset=1.25,
    )


def save(folder, intent=None, **overrides):
    intent = make_intent() if intent is None else intent
    fields = dict(task="unknown_goal", participant="p01", seed=0, demos=DEMOS, history=HISTORY)
    fields.update(overrides)
    return library.save_intent(folder, intent, config=IRLConfig(), **fields)


def test_round_trip_keeps_the_cost_and_the_metadata(tmp_path):
    intent = make_intent()
    path = save(tmp_path, intent)
    assert path == tmp_path / "red_p01.intent.json"
    entry = library.load_intent(path)
    states = np.random.default_rng(0).uniform([0.2, -0.4, 0.1, -1], [0.7, 0.3, 0.5, 2], (50, 4))
    np.testing.assert_array_equal(entry.intent.costs_of(states), intent.costs_of(states))
    assert entry.intent.cost_offset == 1.25
    meta = entry.metadata
    assert (meta["name"], meta["task"], meta["participant"], meta["seed"]) == (
        "red_p01",
        "unknown_goal",
        "p01",
        0,
    )
    assert meta["features"] == intent.features
    assert meta["demo_hashes"] == [library.demo_hash(DEMOS[0])]
    assert meta["history"] == HISTORY
    assert meta["format"] == "casa-intent" and meta["version"] == library.VERSION
    np.testing.assert_array_equal(entry.intent.guides[0], intent.guides[0])
    np.testing.assert_array_equal(entry.intent.objects, intent.objects)
    assert entry.intent.object_names == intent.object_names == list(OBJECTS)
    # The atomic write left no temporary file, and the lab can read the file.
    assert [p.name for p in tmp_path.iterdir()] == ["red_p01.intent.json"]
    assert path.stat().st_mode & 0o777 == 0o644


def test_demo_hash_changes_with_the_demo():
    changed = DEMOS[0].copy()
    changed[2, 1] += 1e-9
    assert library.demo_hash(changed) != library.demo_hash(DEMOS[0])
    assert library.demo_hash(DEMOS[0]) == library.demo_hash(DEMOS[0].copy())


def resealed(payload):
    """``payload`` with a checksum that matches it: damage the checksum cannot see."""
    payload.pop("checksum", None)
    payload["checksum"] = library.hashlib.sha256(library._canonical(payload)).hexdigest()
    return json.dumps(payload)


#: Damage that passes the checksum (the file was written so) but makes the intent unusable.
RESEALED = {
    "nan-weights": lambda p: p["weights"]["0.bias"].update(
        data=base64.b64encode(np.full(p["network"]["hidden"], np.nan, "<f4").tobytes()).decode()
    ),
    # length_scale divides the features: 0 loaded before and gave NaN costs-to-go later.
    "length-scale-0": lambda p: p.update(length_scale=0.0),
    "tiny-length-scale": lambda p: p.update(length_scale=1e-300),
    "cost-scale-negative": lambda p: p.update(cost_scale=-1.0),
    "inner-key": lambda p: p["network"].pop("inputs"),
    "seed-bool": lambda p: p.update(seed=True),
    "huge-hidden": lambda p: p["network"].update(hidden=10**9),  # refused, not allocated
    "planner": lambda p: p["planner"].update(dt=-0.5),
}


def damage(path, how):
    text = path.read_text()
    if how in RESEALED:
        payload = json.loads(text)
        RESEALED[how](payload)
        path.write_text(resealed(payload))
        return
    if how == "nan":
        # A NaN written by a tool that allows it (json.dumps does): not JSON, not finite.
        payload = json.loads(text)
        payload["cost_scale"] = float("nan")
        path.write_text(json.dumps(payload))
    elif how == "overflow":
        path.write_text(text.replace('"cost_offset": 1.25', '"cost_offset": 1e999'))
    elif how == "flipped":
        # One flipped bit in the weights' base64, as a bad disk or copy would leave it.
        data = bytearray(path.read_bytes())
        at = data.index(b'"data": "') + 20
        data[at] ^= 0x01
        path.write_bytes(bytes(data))
    if how == "truncated":
        path.write_text(text[: len(text) // 2])
    elif how == "edited":
        payload = json.loads(text)
        payload["participant"] = "someone else"
        path.write_text(json.dumps(payload))
    elif how == "weights":
        payload = json.loads(text)
        entry = payload["weights"]["0.weight"]
        entry["shape"] = [entry["shape"][1], entry["shape"][0]]
        payload.pop("checksum")
        payload["checksum"] = library.hashlib.sha256(library._canonical(payload)).hexdigest()
        path.write_text(json.dumps(payload))
    elif how == "types":
        payload = json.loads(text)
        payload["history"] = "not a list"
        payload.pop("checksum")
        payload["checksum"] = library.hashlib.sha256(library._canonical(payload)).hexdigest()
        path.write_text(json.dumps(payload))
    elif how == "version":
        payload = json.loads(text)
        payload["version"] = library.VERSION + 1
        path.write_text(json.dumps(payload))
    elif how == "missing":
        payload = json.loads(text)
        del payload["demo_hashes"]
        path.write_text(json.dumps(payload))
    elif how == "binary":
        path.write_bytes(b"\x80\x81\x00garbage")


@pytest.mark.parametrize(
    "how, rule",
    [
        ("truncated", "json"),
        ("edited", "checksum"),
        ("weights", "content"),
        ("types", "content"),
        ("version", "version"),
        ("missing", "required-key"),
        ("binary", "readable"),
        ("nan", "finite"),
        ("overflow", "finite"),
        ("flipped", "checksum"),
        ("nan-weights", "finite"),
        ("length-scale-0", "content"),
        ("tiny-length-scale", "finite"),
        ("cost-scale-negative", "content"),
        ("inner-key", "required-key"),
        ("seed-bool", "content"),
        ("huge-hidden", "content"),
        ("planner", "content"),
    ],
)
def test_damaged_files_are_named_and_do_not_take_the_others_down(tmp_path, how, rule):
    good = save(tmp_path, make_intent("good"))
    bad = save(tmp_path, make_intent("bad"))
    damage(bad, how)
    with pytest.raises(library.LibraryError) as raised:
        library.load_intent(bad)
    assert raised.value.path == bad and raised.value.rule == rule
    assert str(bad) in str(raised.value)
    entries, problems = library.scan_library(tmp_path)
    assert [e.path for e in entries] == [good]
    assert [p.path for p in problems] == [bad]


def test_scan_reports_a_missing_folder_and_duplicate_names(tmp_path):
    entries, problems = library.scan_library(tmp_path / "nope")
    assert entries == [] and problems[0].rule == "folder"
    first = save(tmp_path, make_intent("same"))
    copy = tmp_path / "copy.intent.json"
    copy.write_text(first.read_text())
    entries, problems = library.scan_library(tmp_path)
    assert len(entries) == 1 and problems[0].rule == "unique-name"


def test_bad_intent_names_are_refused_before_writing(tmp_path):
    with pytest.raises(ValueError, match="cannot name a file"):
        library.intent_path(tmp_path, "../escape")


def write_demo_logs(folder, n=2, phase="demonstration", stem="demo"):
    """Demonstration logs in the casa-trial/1 contract, written by the one writer.

    Returns what the writer returned, by each log's ``.json`` path.
    """
    rng = np.random.default_rng(7)
    written = {}
    for i in range(n):
        t = np.arange(0.0, 3.0, 0.05)
        line = np.linspace([0.45, -0.22, 0.38], [0.45, -0.10, 0.38], len(t))
        line += rng.normal(0.0, 0.002, line.shape)
        frame = pd.DataFrame(
            {"t": t, "x": line[:, 0], "y": line[:, 1], "z": line[:, 2], "rot": 0.0, "keys": "y+"}
        )
        meta = {
            "participant": "p07",
            "task": "unknown_goal",
            "method": "NA",
            "phase": phase,
            "source": "simulated",
        }
        written[folder / f"{stem}{i}.json"] = write_trial(folder / f"{stem}{i}", meta, frame)
    return written


def run_casa(*args):
    return subprocess.run(
        [sys.executable, "-m", "casa_core.cli", *args], capture_output=True, text=True, check=False
    )


def test_cli_learn_then_list(tmp_path):
    demos, lib = tmp_path / "demos", tmp_path / "lib"
    write_demo_logs(demos)
    done = run_casa(
        "learn", "--demos", str(demos), "--name", "new", "--library", str(lib),
        "--max-iterations", "1",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    entry = library.load_intent(lib / "new.intent.json")
    assert entry.metadata["participant"] == "p07" and entry.metadata["task"] == "unknown_goal"
    assert len(entry.metadata["demo_hashes"]) == 2
    (lib / "broken.intent.json").write_text('{"format": "casa-intent", "vers')
    listed = run_casa("library", "list", str(lib))
    assert listed.returncode == 1
    assert listed.stdout.startswith("new\ttask=unknown_goal\tparticipant=p07")
    assert "broken.intent.json" in listed.stderr and "Traceback" not in listed.stderr


def test_cli_learn_reads_a_participant_folder_whose_kept_intents_are_not_logs(tmp_path):
    # A dataset keeps each participant's learned intents below its folder, as the
    # workflow does (intents/<participant>/*.intent.json); learning again from that
    # folder reads the logs and passes over the intents, as casa validate does.
    participant = tmp_path / "p07"
    write_demo_logs(participant)
    kept = participant / "intents" / "p07"
    for name in ("first", "again"):
        done = run_casa(
            "learn", "--demos", str(participant), "--name", name, "--library", str(kept),
            "--max-iterations", "1",
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
    again = library.load_intent(kept / "again.intent.json")
    assert len(again.metadata["demo_hashes"]) == 2  # the two logs, not the first intent


def test_cli_learn_reports_missing_demos_without_traceback(tmp_path):
    done = run_casa(
        "learn", "--demos", str(tmp_path / "none"), "--name", "x", "--library", str(tmp_path)
    )
    assert done.returncode == 1
    assert "none" in done.stderr and "Traceback" not in done.stderr


def test_only_demonstrations_are_read_from_a_participant_folder(tmp_path):
    # A participant's folder also holds assisted trials of the same task, where
    # the robot pulled the arm toward another intent: they are not demonstrations.
    write_demo_logs(tmp_path, n=2)
    write_demo_logs(tmp_path, n=3, phase="before_learning", stem="assisted")
    demos, metas = read_demonstrations(tmp_path, "unknown_goal")
    assert len(demos) == 2 and {m["phase"] for m in metas} == {"demonstration"}
    assert len(read_demonstrations(tmp_path, "unknown_goal", phase=None)[0]) == 5


def test_demonstrations_kept_in_memory_are_those_read_from_their_files(tmp_path):
    # The logs write_trial returned stand in for their files; a log not among them (the
    # assisted ones here) is read. Both ways give the same arrays, metadata and errors.
    kept = write_demo_logs(tmp_path, n=2)
    write_demo_logs(tmp_path, n=3, phase="before_learning", stem="assisted")
    kept.update(write_demo_logs(tmp_path, n=1, phase="before_learning", stem="late"))
    for task, phase in [("unknown_goal", "demonstration"), ("unknown_goal", None), (None, None)]:
        read = read_demonstrations(tmp_path, task, phase=phase)
        fast = read_demonstrations(tmp_path, task, phase=phase, logs=kept)
        assert fast[1] == read[1] and len(fast[0]) == len(read[0])
        assert all(np.array_equal(a, b) for a, b in zip(fast[0], read[0], strict=True))
    for logs in (None, kept):
        with pytest.raises(ValueError, match="found phases: before_learning, demonstration"):
            read_demonstrations(tmp_path, "unknown_goal", phase="after_learning", logs=logs)


def test_cli_learn_names_the_phases_it_found_when_none_is_a_demonstration(tmp_path):
    write_demo_logs(tmp_path, n=1, phase="before_learning")
    done = run_casa("learn", "--demos", str(tmp_path), "--name", "x", "--library", str(tmp_path))
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert "in phase 'demonstration'" in done.stderr and "before_learning" in done.stderr


def test_weights_survive_exactly(tmp_path):
    intent = make_intent(seed=5)
    entry = library.load_intent(save(tmp_path, intent))
    for a, b in zip(intent.network.parameters(), entry.intent.network.parameters(), strict=True):
        assert torch.equal(a, b)


def test_cli_list_searches_the_participant_folders_below(tmp_path):
    # The workflow's layout: intents/<participant>/<task>/<name>.intent.json, the same
    # intent name in every participant's library.
    for pid in ("p1", "p2"):
        save(tmp_path / pid / "unknown_goal", make_intent("learned_red"))
    listed = run_casa("library", "list", str(tmp_path))
    assert listed.returncode == 0, listed.stderr
    lines = listed.stdout.splitlines()
    assert [line.split("\t")[0] for line in lines] == ["learned_red", "learned_red"]
    assert [line.split("\t")[-1] for line in lines] == [
        "library=p1/unknown_goal",
        "library=p2/unknown_goal",
    ]
    # One library named directly lists as before, without the folder column.
    direct = run_casa("library", "list", str(tmp_path / "p1" / "unknown_goal"))
    assert direct.returncode == 0 and "library=" not in direct.stdout


def test_cli_list_says_when_nothing_is_found_and_exits_1(tmp_path):
    (tmp_path / "p1" / "unknown_goal").mkdir(parents=True)
    listed = run_casa("library", "list", str(tmp_path))
    assert listed.returncode == 1 and listed.stdout == ""
    assert f"no *.intent.json file in {tmp_path} or below" in listed.stderr
    missing = run_casa("library", "list", str(tmp_path / "nope"))
    assert missing.returncode == 1 and "is not a folder" in missing.stderr
    assert "Traceback" not in listed.stderr + missing.stderr


def test_cli_list_reports_a_nan_file_and_lists_the_good_ones(tmp_path):
    # "bad" sorts before "good": the damaged file must not hide what follows it.
    damage(save(tmp_path, make_intent("bad")), "nan")
    save(tmp_path, make_intent("good"))
    listed = run_casa("library", "list", str(tmp_path))
    assert listed.returncode == 1 and "Traceback" not in listed.stderr
    assert [line.split("\t")[0] for line in listed.stdout.splitlines()] == ["good"]
    assert f"{tmp_path / 'bad.intent.json'}: [finite] holds NaN" in listed.stderr


def damaged_library(folder, how="length-scale-0"):
    """A library of one good intent and one damaged one; returns the damaged file."""
    save(folder, make_intent("good"))
    bad = save(folder, make_intent("bad"))
    damage(bad, how)
    return bad


@pytest.mark.parametrize(("how", "rule"), [("length-scale-0", "content"), ("truncated", "json")])
def test_simulate_after_names_the_damaged_intent_file(tmp_path, capsys, how, rule):
    from casa_core.cli import main

    bad = damaged_library(tmp_path / "lib", how)
    code = main(
        ["simulate", "after", "--config", str(ROOT / "config" / "config.yaml"),
         "--participant", "1", "--out", str(tmp_path / "after"), "--before", str(tmp_path),
         "--library", str(tmp_path / "lib")]
    )  # fmt: skip
    assert code == 2
    assert f"casa simulate after: {bad}: [{rule}]" in capsys.readouterr().err
    assert not (tmp_path / "after").exists()  # nothing simulated with a damaged library


def test_simulate_stages_say_which_option_they_need(capsys):
    from casa_core.cli import main

    assert main(["simulate", "after", "--out", "x"]) == 2
    assert "casa simulate after: needs --before, --library" in capsys.readouterr().err


def test_teleop_names_a_damaged_intent_file_before_opening_a_window(tmp_path, capsys):
    from casa_core.cli import main

    bad = damaged_library(tmp_path, "flipped")
    code = main(
        ["teleop", "--task", "unknown_goal", "--method", "CASA", "--participant", "p01",
         "--out", str(tmp_path / "out"), "--intent", str(bad)]
    )  # fmt: skip
    assert code == 2
    assert f"casa teleop: {bad}: [checksum]" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_cli_learn_refuses_zero_iterations_and_a_negative_seed(tmp_path, capsys):
    from casa_core.cli import main

    common = ["learn", "--demos", str(tmp_path), "--name", "x", "--library", str(tmp_path)]
    for option, value, expected in (
        ("--max-iterations", "0", "argument --max-iterations: must be an integer >= 1, got '0'"),
        ("--seed", "-1", "argument --seed: must be an integer >= 0, got '-1'"),
    ):
        with pytest.raises(SystemExit) as done:  # argparse's usage error, exit status 2
            main([*common, option, value])
        assert done.value.code == 2 and expected in capsys.readouterr().err


def test_irl_config_refuses_settings_out_of_range():
    # max_iterations=0 ran no iteration and failed on an empty history.
    for settings, message in (
        ({"max_iterations": 0}, "IRLConfig.max_iterations must be an integer >= 1, got 0"),
        (
            {"min_iterations": 20, "max_iterations": 10},
            r"IRLConfig.min_iterations \(20\) must be at most max_iterations \(10\)",
        ),
        ({"min_iterations": -1}, "IRLConfig.min_iterations must be an integer >= 0"),
        ({"hidden": 0}, "hidden of IRLConfig must be a positive number, got 0"),
        ({"length_scale": 0.0}, "length_scale of IRLConfig must be a positive number"),
        ({"lr": float("nan")}, "lr of IRLConfig must be a positive number, got nan"),
        ({"weight_decay": -1e-3}, "IRLConfig.weight_decay must be a finite number >= 0"),
    ):
        with pytest.raises(ValueError, match=message):
            IRLConfig(**settings)


def test_cli_learn_names_a_latin1_demonstration_file(tmp_path, capsys):
    from casa_core.cli import main

    write_demo_logs(tmp_path, n=1)
    csv = tmp_path / "demo0.csv"
    csv.write_bytes(csv.read_bytes().replace(b"y+", "\u00e9".encode("latin-1"), 1))
    code = main(["learn", "--demos", str(tmp_path), "--name", "x", "--library", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 1 and f"casa learn: {csv}" in err and "utf-8" in err.lower()
    assert not (tmp_path / "x.intent.json").exists()


def test_no_flipped_bit_gives_a_traceback_or_another_intent(tmp_path):
    # 300 single-bit flips at random places (seeded): each is refused with a LibraryError,
    # or the file still means the same thing (e.g. 1e-05 read as 1E-05) and loads the same.
    original = save(tmp_path, make_intent("flip"))
    pristine = original.read_bytes()
    reference = library.load_intent(original)
    rng = np.random.default_rng(15)
    outcomes = {}
    places = rng.integers(len(pristine), size=300)
    for at, bit in zip(places, rng.integers(8, size=300), strict=True):
        data = bytearray(pristine)
        data[at] ^= 1 << bit
        original.write_bytes(bytes(data))
        try:
            entry = library.load_intent(original)
        except library.LibraryError as error:
            outcomes[error.rule] = outcomes.get(error.rule, 0) + 1
            continue
        assert entry.metadata == reference.metadata
        parameters = zip(
            entry.intent.network.parameters(), reference.intent.network.parameters(), strict=True
        )
        assert all(torch.equal(a, b) for a, b in parameters)
    assert set(outcomes) <= {"readable", "json", "checksum", "format", "version", "required-key"}
    assert sum(outcomes.values()) >= 290  # nearly every flip changes the meaning


def test_measured_times_are_not_stored_so_a_file_is_the_same_bytes_on_every_run(tmp_path):
    timed = [{**HISTORY[0], "seconds": 0.123}]
    first = save(tmp_path / "a", history=timed).read_bytes()
    second = save(tmp_path / "b", history=[{**HISTORY[0], "seconds": 9.87}]).read_bytes()
    assert first == second and b"seconds" not in first
    stored = library.load_intent(tmp_path / "a" / "red_p01.intent.json")
    assert stored.metadata["history"] == HISTORY


def test_the_listing_says_why_training_stopped_and_which_iteration_the_file_keeps(tmp_path):
    # IRL that ran out of iterations (the usual case) and kept an earlier iteration, and IRL
    # that met its criterion: the words say so, not a bare converged=no.
    ran_out = [
        {"iteration": 1, "converged": None},
        {"iteration": 2, "kept": True, "verified_match": 0.0123},
        {"iteration": 3, "converged": False},
    ]
    save(tmp_path / "lib", make_intent("ran_out"), history=ran_out)
    met = [{"iteration": 1}, {"iteration": 2, "converged": True, "kept": True}]
    save(tmp_path / "lib", make_intent("met"), history=met)
    listed = run_casa("library", "list", str(tmp_path / "lib"))
    assert listed.returncode == 0, listed.stderr
    lines = {line.split("\t")[0]: line.split("\t") for line in listed.stdout.splitlines()}
    most = IRLConfig().max_iterations
    assert lines["ran_out"][5:9] == [
        f"iterations=3/{most}",
        "stopped=budget",
        "kept=2",
        "end_match_m=0.0123",
    ]
    assert lines["met"][5:9] == [f"iterations=2/{most}", "stopped=converged", "kept=2"] + [
        "end_match_m=-"
    ]
    assert "converged=" not in listed.stdout
    # The help says what the words mean and what to read instead.
    help_text = " ".join(run_casa("library", "list", "--help").stdout.split())
    assert "budget: it ran all its iterations, as it usually does" in help_text
    assert "learning.csv: endpoint_error_m" in help_text


def test_the_stored_network_shape_is_the_networks_not_the_configs(tmp_path):
    # An intent whose network has 8 hidden units and slope 0.2, saved with the default
    # config (32 and 0.01): the file says the network's shape, and loads to the same cost.
    config = IRLConfig()
    network = cost_network(len(feature_names(OBJECTS)), hidden=8, negative_slope=0.2, seed=0)
    intent = make_intent()
    intent = NeuralIntent(
        intent.name,
        network,
        objects=OBJECTS,
        cost_scale=config.cost_scale,
        length_scale=config.length_scale,
        guides=intent.guides,
        cost_offset=1.25,
    )
    assert (config.hidden, config.negative_slope) != (8, 0.2)
    entry = library.load_intent(save(tmp_path, intent))
    assert entry.metadata["network"]["hidden"] == 8
    assert entry.metadata["network"]["negative_slope"] == 0.2
    states = np.random.default_rng(0).uniform([0.2, -0.4, 0.1, -1], [0.7, 0.3, 0.5, 2], (20, 4))
    np.testing.assert_array_equal(entry.intent.costs_of(states), intent.costs_of(states))


def test_the_learned_costs_bound_is_a_goals_cost_half_a_metre_away():
    # IRLConfig.cost_scale bounds the learned per-state cost at what a goal intent's
    # distance_sum cost charges for one state 0.5 m from its goal (GoalIntent's closed
    # form: COST_PER_METRE * dt * distance), with the cost per metre rounded to a whole
    # number (227 for 227.27): within that rounding, 0.12%, and derived from it.
    from casa_core.assist.intents import GoalIntent
    from casa_core.defaults import COST_PER_METRE, DT

    goal = GoalIntent("g", [0.5, 0.0, 0.0], cost="distance_sum", dt=DT)
    charged = goal.step_cost(np.zeros(4), np.zeros(4))
    assert charged == pytest.approx(COST_PER_METRE * DT * 0.5)
    assert IRLConfig().cost_scale == pytest.approx(charged, rel=0.5 / round(COST_PER_METRE))
