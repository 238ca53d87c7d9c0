"""``casa import original``: the original implementation's session files as a casa-trial/1 dataset.

Every session here is synthetic, built in ``tmp_path`` in the original's format
(docs/data-contracts.md, "Importing the original implementation's sessions"): joint
angles moving linearly from the original's start angles to its goal 0, a user command
built from a known key, and inference arrays chosen so that each rule (negative beta,
a 0/0 belief row, the alpha of each method) is exercised with a hand-computed answer.
"""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np
import pandas as pd
import pytest
import yaml

from casa_core.cli import main
from casa_core.io import read_trial
from casa_core.io.original.importer import ORIGINAL_SCENE
from casa_core.io.original.sessions import REFERENCE_ANGLES, reference_q
from casa_core.robot import kinematics as kin
from casa_core.scene import DEFAULT_SCENE, load_scene
from tests.io import original_reference as reference

#: Sample times: about 18 Hz, irregular (steps of 0.05 and 0.06 s), 3.0 s in all.
TIMES = np.cumsum(np.r_[0.0, np.tile([0.05, 0.06], 27), 0.03])
DURATION = TIMES[-1]  # 3.0 s: ticks 0, 0.05, ..., 3.0
#: The timed inference steps, as the original logs them (NOTES section 4): each starts just
#: after its waypoint (waypoint j at 0.5 j s) over waypoints 0..w; the step from 1.03 s ran
#: late, so waypoint 3 (1.5 s) started none.
STEPS = np.array([0.52, 1.03, 2.01, 2.5])
WAYPOINTS = [1, 2, 4, 5]
#: The histories: one row per timed step, then the final step after the trial, whose beta
#: can be negative (here -2.0 for green).
BELIEFS = np.array([[0.6, 0.4], [np.nan, np.nan], [0.7, 0.3], [0.2, 0.8], [0.3, 0.7]])
BETAS = np.array([[2.0, 1.0], [4.0, -1.0], [-0.5, 3.0], [1.0, 4.0], [-2.0, 0.5]])
#: CASA's alpha after each timed step, by hand: clip(1 / beta of the most likely goal, 0, 1),
#: the 0/0 row carrying [0.6, 0.4] (goal 0 likely, beta 4), beta -0.5 giving 0.
CASA_ALPHAS = [0.5, 0.25, 0.0, 0.25]


def joint_angles(t):
    """Linear in time from the original's start to its goal 0, reached at DURATION."""
    start, goal = reference_q("start"), reference_q("goal 0")
    return start + np.outer(np.asarray(t) / DURATION, goal - start)


def command_of(q, velocity, joint7=0.0):
    """The joint velocity giving the tool ``velocity``, plus ``joint7`` on the last joint."""
    command = np.linalg.pinv(kin.jacobian(q)[:3]) @ np.asarray(velocity, dtype=float)
    command[6] += joint7
    return command


def recorded_waypoints(time, q, count):
    """``traj_hist``: the samples the original records, the first at or after 0.5 j s."""
    return q[[int(np.searchsorted(time, 0.5 * j - 1e-9)) for j in range(count)]]


def session_arrays(n_goals=2, beta=True):
    """A session of TIMES; ``beta=False`` logs as NA and PBA do: no betas, the prior."""
    q = joint_angles(TIMES)
    # z+ for the first second, then x- with rot+ (joint 7 backwards) to 2 s, then no key.
    commands = np.zeros_like(q)
    for i, t in enumerate(TIMES):
        if t < 1.0:
            commands[i] = command_of(q[i], [0, 0, 0.05])
        elif t < 2.0:
            commands[i] = command_of(q[i], [-0.05, 0, 0], joint7=-0.5)
    beliefs = BELIEFS if n_goals == 2 else np.column_stack([BELIEFS * 0.5, np.full(5, 0.5)])
    betas = BETAS if n_goals == 2 else np.column_stack([BETAS, np.ones(5)])
    if not beta:
        beliefs = np.full((5, n_goals), 1.0 / n_goals)
    return {
        "cmdpos_time": TIMES,
        "curr_pos": q,
        "joy_cmd": commands,
        "ctl_cmd": np.zeros_like(q),
        "cmd": commands,
        "traj_hist": recorded_waypoints(TIMES, q, 7),
        "inf_start_time": STEPS,
        "sub_hist": np.ones((5, n_goals)),
        "belief_hist": beliefs,
        "beta_hist": betas if beta else np.zeros(0),
        "start_T": np.array(1.6e9),
    }


def write_session(folder, name, **changes):
    arrays = session_arrays(**changes.pop("build", {}))
    arrays.update(changes)
    arrays = {key: value for key, value in arrays.items() if value is not None}
    folder.mkdir(parents=True, exist_ok=True)
    np.savez(folder / name, **arrays)
    return folder / name


@pytest.fixture
def sessions(tmp_path):
    folder = tmp_path / "sessions" / "P03"
    write_session(folder, "task1c_data.npz")
    write_session(folder, "task1b_data.npz", build={"beta": False})
    write_session(folder, "task1a_data.npz", build={"beta": False})
    write_session(folder, "task2c_learned_data.npz", build={"n_goals": 3})
    write_session(folder, "task1ex_data.npz")
    np.savez(folder / "task2_demonstrations.npz", demos=np.zeros((5, 10, 7)))
    return folder


def digest(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def run_import(folder, out, *extra):
    return main(["import", "original", str(folder), "--out", str(out), *extra])


def held_at(times, values, t):
    """The value of the last of ``times`` at or before ``t`` (None before the first)."""
    before = [v for s, v in zip(times, values, strict=True) if s <= t + 1e-9]
    return before[-1] if before else None


def test_a_folder_of_sessions_becomes_a_valid_dataset(sessions, tmp_path, capsys):
    before = digest(sessions)
    out = tmp_path / "raw" / "original"
    assert run_import(sessions, out) == 0
    printed = capsys.readouterr().out
    assert "skipped task1ex_data.npz: a worked example" in printed
    assert "skipped task2_demonstrations.npz: demonstrations" in printed
    assert digest(sessions) == before  # the session folder is only read
    stems = sorted(p.stem for p in (out / "P03").glob("*.json"))
    assert stems == ["task1a", "task1b", "task1c", "task2c_learned"]
    assert (out / "scene.yaml").read_text() == ORIGINAL_SCENE.read_text()
    assert main(["validate", str(out)]) == 0


def test_metadata_from_the_file_name(sessions, tmp_path):
    out = tmp_path / "out"
    assert run_import(sessions, out, "--participant", "P3") == 0
    expected = {
        "task1a": ("known_goal", "NA", "no_misspecification", ["green", "purple"]),
        "task1b": ("known_goal", "PBA", "no_misspecification", ["green", "purple"]),
        "task1c": ("known_goal", "CASA", "no_misspecification", ["green", "purple"]),
        "task2c_learned": (
            "unknown_goal",
            "CASA",
            "after_learning",
            ["green", "purple", "learned_red"],
        ),
    }
    for stem, (task, method, phase, intents) in expected.items():
        meta = json.loads((out / "P3" / f"{stem}.json").read_text())
        assert (meta["task"], meta["method"], meta["phase"], meta["intents"]) == (
            task,
            method,
            phase,
            intents,
        )
        assert (meta["participant"], meta["source"], meta["max_duration"]) == ("P3", "human", 15.0)
        assert f"session file {stem}_data.npz" in meta["notes"]
        assert meta["started_at"] == "2020-09-13T12:26:40+00:00"  # start_T 1.6e9 s


@pytest.mark.parametrize(("scene", "point"), [(None, "link7"), (DEFAULT_SCENE, "tool")])
def test_positions_are_the_scenes_point_of_the_joint_angles(sessions, tmp_path, scene, point):
    out = tmp_path / "out"
    assert run_import(sessions, out, *([] if scene is None else ["--scene", str(scene)])) == 0
    _, frame = read_trial(out / "P03" / "task1c")
    # Ticks of 0.05 s from 0 to the last sample (3.0 s): 61 rows.
    assert np.allclose(frame["t"], np.arange(61) * 0.05)
    q = frame[[f"q{i}" for i in range(1, 8)]].to_numpy()
    # The angles are linear in time, so linear interpolation is exact at every tick.
    assert np.allclose(q, joint_angles(frame["t"]), atol=1e-12)
    # The authors' layout is measured at link 7 (its `point`), ours at the tool point.
    frames = [kin.link_frames(row) for row in q]
    expected = np.array([f[6 if point == "link7" else 7][:3, 3] for f in frames])
    assert np.allclose(frame[["x", "y", "z"]].to_numpy(), expected, atol=1e-12)
    rot = [kin.rot_of(kin.forward_kinematics(row)[:3, :3]) for row in q]
    assert np.allclose(frame["rot"], np.unwrap(rot), atol=1e-12)


def test_keys_come_from_the_users_command(sessions, tmp_path):
    out = tmp_path / "out"
    assert run_import(sessions, out) == 0
    _, frame = read_trial(out / "P03" / "task1c")
    for t, keys in zip(frame["t"], frame["keys"], strict=True):
        # The key of the last sample at or before the tick, as the session was built.
        sample = held_at(TIMES, TIMES, t)
        expected = "z+" if sample < 1.0 else "x- rot+" if sample < 2.0 else ""
        assert keys == expected, t


def test_casa_confidence_beliefs_and_alpha(sessions, tmp_path):
    out = tmp_path / "out"
    assert run_import(sessions, out) == 0
    meta, frame = read_trial(out / "P03" / "task1c")
    carried = BELIEFS.copy()
    carried[1] = BELIEFS[0]  # the 0/0 row carries the last good row
    for row in frame.itertuples():
        # Each timed step from the first tick at or after its start; the final row on none.
        step = held_at(STEPS, range(len(STEPS)), row.t)
        beliefs = frame.loc[row.Index, ["belief:green", "belief:purple"]].to_numpy()
        betas = frame.loc[row.Index, ["beta:green", "beta:purple"]].to_numpy()
        if step is None:  # before the first step (0.52 s): no evidence
            assert row.t < 0.52 and row.alpha == 1.0
            assert betas.tolist() == [0.0, 0.0] and beliefs.tolist() == [0.5, 0.5]
            continue
        assert row.alpha == pytest.approx(CASA_ALPHAS[step])
        assert np.allclose(betas, np.maximum(BETAS[step], 0.0))  # negative betas -> 0
        assert np.allclose(beliefs, carried[step])
    # The last tick (3.0 s) holds the last timed step, not the step after the trial.
    assert frame["belief:purple"].iloc[-1] == 0.8 and frame["beta:green"].iloc[-1] == 1.0
    assert not np.isclose(frame["belief:purple"], BELIEFS[-1, 1]).any()
    # Two negative betas of the timed steps (-1.0, -0.5) and one 0/0 belief row were built.
    assert "negative betas written as 0: 2" in meta["notes"]
    assert "belief rows carried from the last good row: 1" in meta["notes"]
    # The metadata keeps when each step started, its waypoint, the waypoints and the final
    # step as the original computed it (its beta negative).
    steps = meta["inference_steps"]
    assert steps["started"] == STEPS.tolist() and steps["waypoint"] == WAYPOINTS
    expected = recorded_waypoints(TIMES, joint_angles(TIMES), 7)
    assert np.array_equal(steps["waypoints"], expected)
    assert steps["after_trial"] == {
        "waypoint": 6,
        "beta": {"green": -2.0, "purple": 0.5},
        "belief": {"green": 0.3, "purple": 0.7},
    }
    assert "flags" not in meta


@pytest.mark.parametrize("logged", [False, True], ids=["prior-only", "logged-beliefs"])
def test_pba_alpha_is_link7_distance_to_the_predicted_goal(tmp_path, logged):
    folder = tmp_path / "sessions" / "P03"
    write_session(folder, "task1b_data.npz", build={"beta": logged})
    out = tmp_path / "out"
    assert run_import(folder, out) == 0
    meta, frame = read_trial(out / "P03" / "task1b")
    # The link-7 goals of the scene the import copies (rounded to 1 mm), where a replay
    # measures the same trial.
    scene = load_scene(ORIGINAL_SCENE)
    goals = np.array([scene.goal("green", "link7"), scene.goal("purple", "link7")])
    points = reference.link7_waypoints(recorded_waypoints(TIMES, joint_angles(TIMES), 7))
    carried = BELIEFS.copy()
    carried[1] = BELIEFS[0]
    for row in frame.itertuples():
        step = held_at(STEPS, range(len(STEPS)), row.t)
        if step is None:
            assert row.alpha == 1.0
            continue
        w = WAYPOINTS[step]
        if logged:
            likely = int(np.argmax(carried[step]))
        else:  # the tests' reference of the original's posterior at beta = 1
            sub = reference.suboptimality(points, goals, w, defects=True)
            likely = int(np.argmax(reference.belief(sub, 1.0, w, defects=True)))
        expected = min(1.0, np.linalg.norm(points[w] - goals[likely]) / 0.55)
        assert row.alpha == pytest.approx(expected, abs=1e-12)
    beliefs = [c for c in frame.columns if c.startswith(("belief:", "beta:"))]
    if logged:
        assert beliefs == ["beta:green", "belief:green", "beta:purple", "belief:purple"]
    else:  # the prior on every row is no belief: no columns, the reason said
        assert beliefs == [] and meta["flags"] == ["no-logged-inference"]
        assert "no beliefs or betas: the session logged no inference result" in meta["notes"]
        assert "after_trial" not in meta["inference_steps"]


def test_na_without_betas(sessions, tmp_path):
    out = tmp_path / "out"
    assert run_import(sessions, out) == 0
    meta, frame = read_trial(out / "P03" / "task1a")
    assert (frame["alpha"] == 1.0).all()
    assert not [c for c in frame.columns if c.startswith(("beta:", "belief:"))]
    assert meta["flags"] == ["no-logged-inference"]
    assert meta["inference_steps"]["waypoint"] == WAYPOINTS


def test_rerun_refuses_to_overwrite_unless_forced(sessions, tmp_path, capsys):
    out = tmp_path / "out"
    assert run_import(sessions, out) == 0
    written = digest(out / "P03")
    capsys.readouterr()
    assert run_import(sessions, out) == 2
    err = capsys.readouterr().err
    assert f"{out / 'P03' / 'task1a.json'}: [exists]" in err and "nothing written" in err
    assert digest(out / "P03") == written
    assert run_import(sessions, out, "--force") == 0


DAMAGED = [
    ("truncated", "task1c_data.npz", "", "npz"),
    ("not an archive", "task1c_data.npz", "", "npz"),
    ("no curr_pos", "task1c_data.npz", "key 'curr_pos'", "required-key"),
    ("wrong shape", "task1c_data.npz", "key 'curr_pos'", "shape"),
    ("decreasing time", "task1c_data.npz", "key 'cmdpos_time'", "increasing"),
    ("rows", "task1c_data.npz", "key 'joy_cmd'", "rows"),
    ("unknown name", "task3a_data.npz", "file name", "session-name"),
]


@pytest.mark.parametrize(("damage", "name", "where", "rule"), DAMAGED, ids=[d[0] for d in DAMAGED])
def test_damaged_files_stop_the_import_naming_file_and_key(
    sessions, tmp_path, capsys, damage, name, where, rule
):
    path = sessions / name
    if damage == "truncated":
        data = (sessions / "task1b_data.npz").read_bytes()
        path.write_bytes(data[: len(data) // 2])
    elif damage == "not an archive":
        path.write_text("time,x\n0,1\n")
    elif damage == "no curr_pos":
        write_session(sessions, name, curr_pos=None)
    elif damage == "wrong shape":
        write_session(sessions, name, curr_pos=joint_angles(TIMES)[:, :6])
    elif damage == "decreasing time":
        write_session(sessions, name, cmdpos_time=TIMES[::-1].copy())
    elif damage == "rows":
        write_session(sessions, name, joy_cmd=np.zeros((3, 7)))
    else:
        write_session(sessions, name)
    before = digest(sessions)
    out = tmp_path / "out"
    assert run_import(sessions, out) == 2
    err = capsys.readouterr().err
    assert f"{path}: {where}: [{rule}]".replace(": : ", ": ") in err
    assert "Traceback" not in err
    assert "pickle" not in err  # numpy's hint to load a file unsafely is not for this user
    assert not out.exists()  # nothing half-written
    assert digest(sessions) == before
    # --skip-bad lists the bad file and converts the others.
    assert run_import(sessions, out, "--skip-bad") == 0
    assert f"left out: {path}" in capsys.readouterr().out
    assert not (out / "P03" / f"{name.removesuffix('_data.npz')}.json").exists()
    assert (out / "P03" / "task1a.json").is_file()


def test_the_dataset_is_processed_with_its_own_scene(sessions, tmp_path):
    out = tmp_path / "raw" / "original"
    assert run_import(sessions, out) == 0
    tables = tmp_path / "processed"
    argv = ["process", str(out), "--out", str(tables), "--scene", str(out / "scene.yaml")]
    assert main(argv) == 0
    trials = pd.read_csv(tables / "trials.csv", keep_default_na=False)
    assert sorted(trials["trial"]) == [
        "P03/task1a",
        "P03/task1b",
        "P03/task1c",
        "P03/task2c_learned",
    ]
    assert main(["validate", str(out), "--report", str(tables / "validation.csv")]) == 0
    validation = pd.read_csv(tables / "validation.csv", keep_default_na=False)
    assert validation.set_index("file").loc["scene.yaml", ["kind", "status"]].tolist() == [
        "scene",
        "ok",
    ]


def test_validate_names_the_key_of_a_bad_dataset_scene(sessions, tmp_path, capsys):
    out = tmp_path / "out"
    assert run_import(sessions, out) == 0
    scene = out / "scene.yaml"
    scene.write_text(scene.read_text().replace("  red:", "  blue:"))
    capsys.readouterr()
    assert main(["validate", str(out)]) == 1
    assert f"{scene}: key 'goals.red': [scene] missing" in capsys.readouterr().out


def test_the_scene_holds_link7_and_the_tool_points_of_the_reference_angles():
    scene = load_scene(ORIGINAL_SCENE)
    assert scene.point == "link7"
    roles = {"start": "start", "green": "goal 0", "purple": "goal 1", "red": "unknown goal"}
    assert set(REFERENCE_ANGLES) == set(roles.values())
    for name, role in roles.items():
        link7 = kin.link7_position(reference_q(role))
        written = scene.start.position if name == "start" else scene.goals[name]
        assert np.allclose(written, link7, atol=0.0005 + 1e-9), name  # rounded to 1 mm
        if name != "start":
            tool = kin.forward_kinematics(reference_q(role))[:3, 3]
            assert np.allclose(scene.goal(name, "tool"), tool, atol=0.0005 + 1e-9), name
    # The original's goal 0 at link 7, to 1 mm, as docs/data-contracts.md gives it.
    assert scene.goals["green"] == (-0.548, -0.444, 0.424)
    assert np.allclose(scene.start.joints, np.radians(REFERENCE_ANGLES["start"]))
    assert scene.start.rot == 0.0
    # The pouring pose: 15 cm from the unknown goal toward the base, 4.8 cm lower.
    offset = np.subtract(scene.pouring.position, scene.goals["red"])
    assert np.allclose(offset, [0.0, 0.15, -0.048], atol=1e-9)
    # The file is plain YAML with the scene's keys and nothing else.
    assert set(yaml.safe_load(ORIGINAL_SCENE.read_text())) == {
        "point",
        "start",
        "goals",
        "tool",
        "pouring",
        "teleop",
        "trial_length",
    }
    assert scene.trial_length == 15.0  # the original's trials stop at 15 s


@pytest.mark.pipeline
def test_the_workflow_builds_and_replays_the_eleven_recorded_layouts(tmp_path):
    from tests.workflow.test_workflow import copy_workflow, snakemake

    repo = copy_workflow(tmp_path / "repo")
    folder = write_recorded(tmp_path / "sessions" / "P01")
    assert run_import(folder, repo / "data" / "raw" / "original") == 0
    target = "data/processed/original/trials.csv"
    # Targets before --config, which takes every word after it.
    dry = snakemake(repo, target, "--dry-run", "--printshellcmds", "--config", "simulate=false")
    assert dry.returncode == 0, dry.stderr
    assert "--scene data/raw/original/scene.yaml" in dry.stdout
    # The default target takes the imported dataset all the way: its tables, statistics,
    # figures and the replay of its assisted trials, with its own scene.
    result = snakemake(repo, "--config", "simulate=false")
    assert result.returncode == 0, result.stderr
    trials = pd.read_csv(repo / target, keep_default_na=False)
    assert len(trials) == 9 and set(trials["dataset"]) == {"original"}
    flags = dict(zip(trials["trial"], trials["flags"], strict=True))
    assert {trial for trial, flag in flags.items() if flag} == {
        f"P01/{stem}" for stem in ("task1a", "task1b", "task2a", "task2b", "task4a")
    }
    assert flags["P01/task4a"] == "no-user-command" and flags["P01/task1b"] == "no-logged-inference"
    assert set(trials["preset"]) == {"original_defects"}
    # C1 is judged on the Known Goal CASA trial's own ticks: its last timed step's beta and
    # the lowest alpha its steps gave, not the step after the trial (beta -1.5 for green,
    # its most likely goal, which read as a tick would give beta 0 and alpha 0).
    name = "task1c_data.npz"
    arrays = recorded_layout(*RECORDED[name], seed=list(RECORDED).index(name))
    beta, belief = arrays["beta_hist"][:-1], arrays["belief_hist"][:-1]
    final = beta[-1, 0]
    lowest = min(1.0, np.clip(1 / beta[np.arange(len(beta)), belief.argmax(axis=1)], 0, 1).min())
    results = (repo / "data/processed/original/results.md").read_text()
    c1 = next(line for line in results.splitlines() if line.startswith("| C1"))
    assert f"final beta_hat median {final:.3g}" in c1 and f"lowest alpha median {lowest:.3g}" in c1
    assert final > 0 and lowest > 0
    replayed = pd.read_csv(repo / "data/processed/original/replay/replay.csv")
    status = dict(zip(replayed["trial"], replayed["status"], strict=True))
    # NA is not replayed by default; the original's learned intents are not imported.
    assert status == {
        "P01/task0c": "replayed",
        "P01/task1a": "skipped",
        "P01/task1b": "replayed",
        "P01/task1c": "replayed",
        "P01/task2a": "skipped",
        "P01/task2b": "replayed",
        "P01/task2c": "replayed",
        "P01/task4a": "skipped",
        "P01/task4c_learned": "skipped",
    }
    done = replayed[replayed["status"] == "replayed"]
    assert set(done["preset"]) == {"original_defects"} and set(done["point"]) == {"link7"}
    learned = replayed.set_index("trial").loc["P01/task4c_learned", "reason"]
    assert "'learned_pour' is not a goal of the scene" in learned
    # Each assisted trial read its recorded waypoints; the PBA ones had nothing to compare.
    assert set(done["path"]) == {"waypoints"}
    pba = done[done["method"] == "PBA"]
    assert pba["max_diff_belief"].isna().all() and pba["max_diff_alpha"].isna().all()
    assert pba["reason"].str.contains("flagged no-logged-inference").all()
    assert list((repo / "figures/original/replay").rglob("*.replay.png"))
    for name in ("objective.png", "objective.pdf"):
        assert (repo / "figures/original" / name).stat().st_size > 0
    assert (repo / "data/processed/original/stats.md").exists()


class RunsCode:
    """Unpickled, it runs a shell command: what a crafted session file could hold."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


def crafted(marker):
    return np.array([RunsCode(marker)], dtype=object)


def test_an_object_array_is_never_unpickled(sessions, tmp_path):
    # The original stores its goals' planned trajectories as object arrays (pickles); the
    # import uses none of them, so a crafted one is left unread and the session imports.
    marker = tmp_path / "ran"
    path = write_session(sessions, "task1c_data.npz", goal_traj_by_idx=crafted(marker))
    assert run_import(sessions, tmp_path / "out") == 0
    assert not marker.exists()
    assert (tmp_path / "out" / "P03" / "task1c.json").is_file()
    # The file is a real threat: loading it with pickles allowed runs its command.
    with np.load(path, allow_pickle=True) as archive:
        archive["goal_traj_by_idx"]
    assert marker.exists()


def test_a_needed_key_held_as_a_pickle_is_refused_unread(sessions, tmp_path, capsys):
    marker = tmp_path / "ran"
    path = write_session(sessions, "task1b_data.npz", curr_pos=crafted(marker))
    assert run_import(sessions, tmp_path / "out") == 2
    err = capsys.readouterr().err
    assert f"{path}: key 'curr_pos': [pickle]" in err and "Traceback" not in err
    assert not marker.exists()


#: The eleven sessions the authors recorded, by their layout: control-loop samples n,
#: timed inference steps m (the histories have m + 1 rows), goals, whether betas were
#: logged, and the optional cost arrays (shapes as the files hold them). Their keys,
#: shapes and dtypes are those of the files; the values here are synthetic.
RECORDED = {
    "task0c_data.npz": (128, 29, 2, True, {}),
    "task0ex_data.npz": (125, 29, 2, True, {}),
    "task1a_data.npz": (289, 29, 2, False, {}),
    "task1b_data.npz": (288, 29, 2, False, {}),
    "task1c_data.npz": (289, 29, 2, True, {}),
    "task2a_data.npz": (287, 29, 2, False, {}),
    "task2b_data.npz": (124, 27, 2, False, {}),
    "task2c_data.npz": (
        145,
        29,
        2,
        True,
        {"goal_costs": (29, 2), "curr_cost": (30, 2), "optimal_costs": (2,)},
    ),
    "task4a_data.npz": (125, 29, 3, True, {}),
    "task4c_learned_data.npz": (126, 9, 3, True, {}),
    "task4ex_data.npz": (132, 29, 3, True, {}),
}
#: The waypoint of each timed step by the number of steps: 29 when none ran late (waypoints
#: 1..29; waypoint 30 ends the trial and starts the final step), 27 when two steps ran into
#: the next waypoint, 9 after learning, where a step takes about 1.5 s.
STEP_WAYPOINTS = {
    29: list(range(1, 30)),
    27: [w for w in range(1, 30) if w not in (8, 20)],
    9: [1, 4, 7, 10, 13, 16, 19, 22, 25],
}


def object_array(value):
    """A 0-d object array, as Python 2 pickled the original's lists of plans."""
    array = np.empty((), dtype=object)
    array[()] = value
    return array


#: The recorded session whose user command is zero on every row while the arm moves.
ROBOT_DROVE = "task4a_data.npz"


def recorded_layout(n, m, goals, with_beta, costs, seed, *, command=True):
    """A session laid out as the original logs one (NOTES section 4): samples over 15.55 s,
    31 waypoints, each timed step just after its waypoint, the final step's beta negative
    for green; without betas, the prior on every belief row."""
    rng = np.random.default_rng(seed)
    time = np.sort(rng.uniform(0.0, 15.55, n))
    time[0], time[-1] = 0.0, 15.55
    q = joint_angles(time)
    command = np.array([command_of(qi, [0.0, 0.0, 0.05 * command]) for qi in q])
    timed = 0.5 * np.array(STEP_WAYPOINTS[m]) + rng.uniform(0.001, 0.04, m)
    belief = rng.dirichlet(np.ones(goals), m + 1)
    belief[m] = np.r_[0.9, np.full(goals - 1, 0.1 / (goals - 1))]
    beta = rng.uniform(0.5, 4, (m + 1, goals))
    beta[m, 0] = -1.5  # the step after the trial, which ended short of green, its most likely
    arrays = {
        "cmdpos_time": time,
        "curr_pos": q,
        "joy_cmd": command,
        "ctl_cmd": np.zeros((n, 7)),
        "cmd": command,
        "num_key_presses": np.arange(n, dtype=np.int64),
        "traj_hist": recorded_waypoints(time, q, 31),
        "inf_start_time": timed,
        "sub_hist": rng.uniform(0, 5, (m + 1, goals)),
        "belief_hist": belief if with_beta else np.full((m + 1, goals), 1.0 / goals),
        "beta_hist": beta if with_beta else np.zeros(0),
        "goal_costs": np.zeros(0),
        "curr_cost": np.zeros(0),
        "start_T": np.array(1.6e9),
        "goal_traj_by_idx": object_array([[0.0] * 7] * 3),
        "goal_traj_plan_by_idx": object_array([[0.0] * 7] * 3),
    }
    arrays |= {key: rng.uniform(0, 1, shape) for key, shape in costs.items()}
    return arrays


def write_recorded(folder):
    """The eleven recorded layouts in ``folder``, the robot driving in :data:`ROBOT_DROVE`."""
    folder.mkdir(parents=True)
    for seed, (name, layout) in enumerate(RECORDED.items()):
        arrays = recorded_layout(*layout, seed=seed, command=name != ROBOT_DROVE)
        np.savez(folder / name, **arrays)
    return folder


def test_every_recorded_layout_imports_with_its_steps_real_times(tmp_path, capsys):
    folder = write_recorded(tmp_path / "sessions" / "P01")
    out = tmp_path / "out"
    assert run_import(folder, out) == 0
    stems = {p.stem for p in (out / "P01").glob("*.json")}
    assert stems == {n.removesuffix("_data.npz") for n in RECORDED if "ex_" not in n}
    # The session the robot drove is imported, said and flagged.
    printed = capsys.readouterr().out
    warning = f"{folder / ROBOT_DROVE}: key 'joy_cmd': warning [no-user-command] the user's"
    assert printed.count("warning [no-user-command]") == 1 and warning in printed
    flags = {
        stem: json.loads((out / "P01" / f"{stem}.json").read_text()).get("flags") for stem in stems
    }
    assert flags.pop("task4a") == ["no-user-command"]
    # NA and PBA logged the prior on every row: no beliefs, flagged; the others have theirs.
    unlogged = {stem for stem in flags if not RECORDED[f"{stem}_data.npz"][3]}
    assert unlogged == {"task1a", "task1b", "task2a", "task2b"}
    for stem, flag in flags.items():
        _, frame = read_trial(out / "P01" / stem)
        beliefs = [c for c in frame.columns if c.startswith(("belief:", "beta:"))]
        if stem in unlogged:
            assert flag == ["no-logged-inference"] and beliefs == [], stem
        else:
            assert flag is None and beliefs, stem
    meta, _ = read_trial(out / "P01" / "task1c")
    assert meta["inference"] == {
        "preset": "original_defects",
        "evidence": "executed",
        "point": "link7",
    }
    # Row k holds from the first tick at or after inf_start_time[k], late steps included;
    # the prior before row 0; the final row (beta -1.5 for green) on no tick.
    for stem in ("task1c", "task4c_learned"):
        name = f"{stem}_data.npz"
        arrays = recorded_layout(*RECORDED[name], seed=list(RECORDED).index(name))
        meta, frame = read_trial(out / "P01" / stem)
        times = arrays["inf_start_time"]
        belief = arrays["belief_hist"] / arrays["belief_hist"].sum(axis=1, keepdims=True)
        step = [held_at(times, range(len(times)), t) for t in frame["t"]]
        expected = [1 / belief.shape[1] if k is None else belief[k, 0] for k in step]
        assert np.allclose(frame["belief:green"], expected), stem
        assert frame["beta:green"].min() >= 0 and frame["beta:green"].iloc[-1] > 0
        steps = meta["inference_steps"]
        m = RECORDED[name][1]
        assert steps["started"] == times.tolist() and steps["waypoint"] == STEP_WAYPOINTS[m]
        assert len(steps["waypoints"]) == 31 and steps["after_trial"]["waypoint"] == 30
        assert steps["after_trial"]["beta"]["green"] == -1.5


def test_histories_without_the_final_row_are_refused_naming_the_rule(sessions, capsys, tmp_path):
    path = write_session(sessions, "task1c_data.npz", inf_start_time=np.r_[STEPS, 2.8])
    assert run_import(sessions, tmp_path / "out") == 2
    err = capsys.readouterr().err
    assert f"{path}: key 'belief_hist': [rows] has 5 rows, expected 6" in err


@pytest.mark.parametrize(
    ("steps", "message"),
    [
        ([0.52, 0.8, 2.01, 2.5], "steps 0 and 1 started at 0.52 and 0.8 s, both after waypoint 1"),
        ([0.3, 1.03, 2.01, 2.5], "step 0 started at 0.3 s, before waypoint 1"),
        ([0.52, 1.03, 2.01, 3.6], "step 3 started at 3.6 s, after waypoint 7, but traj_hist has 7"),
    ],
    ids=["two-at-one-waypoint", "before-waypoint-1", "after-the-last-waypoint"],
)
def test_steps_that_no_waypoint_started_are_refused(sessions, capsys, tmp_path, steps, message):
    path = write_session(sessions, "task1c_data.npz", inf_start_time=np.array(steps))
    assert run_import(sessions, tmp_path / "out") == 2
    assert f"{path}: key 'inf_start_time': [waypoints] {message}" in capsys.readouterr().err
