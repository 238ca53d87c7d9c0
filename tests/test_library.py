"""The intent library (casa_core.library) and the `casa learn` / `casa library list` commands."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import torch

from casa_core import library
from casa_core.io import write_trial
from casa_core.learning import IRLConfig, NeuralIntent, cost_network, feature_names
from casa_core.scene import load_scene
from casa_core.study.learn_from_logs import read_demonstrations
from casa_core.study.learning_evidence import scene_objects

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


def damage(path, how):
    text = path.read_text()
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
    """Demonstration logs in the casa-trial/1 contract, written by the one writer."""
    rng = np.random.default_rng(7)
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
        write_trial(folder / f"{stem}{i}", meta, frame)


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
