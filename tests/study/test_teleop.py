"""``casa teleop``: headless through the same code path, then once in a real window (Xvfb)."""

import os
import shutil
import subprocess
import sys
import textwrap

import pybullet as p
import pytest

from casa_core.assist.presets import preset
from casa_core.cli import build_parser, main
from casa_core.io import read_trial, validate_paths
from casa_core.robot import teleop
from casa_core.study.key_sources import ScriptedKeys
from casa_core.study.teleop_session import run_teleop
from tests.display import start_xvfb


def test_headless_teleop_writes_a_valid_log_and_never_overwrites(scene, tmp_path):
    script = ScriptedKeys([(1.0, ["x+", "z-"]), (0.5, ["rot+"])])
    stem = run_teleop(
        scene, "unknown_skill", "PBA", "h7", tmp_path, gui=False, key_source=script, countdown=0
    )
    assert stem == tmp_path / "unknown_skill_before_learning_PBA"
    assert validate_paths([tmp_path]) == []
    meta, frame = read_trial(stem)
    assert meta["participant"] == "h7" and meta["source"] == "simulated"
    assert "started_at" in meta
    assert (frame["keys"][:20] == "x+ z-").all() and (frame["keys"][20:30] == "rot+").all()
    with pytest.raises(FileExistsError, match="never overwritten"):
        run_teleop(
            scene, "unknown_skill", "PBA", "h7", tmp_path, gui=False, key_source=ScriptedKeys([])
        )


@pytest.mark.parametrize(
    ("task", "method", "phase", "rule"),
    [
        ("known_goal", "BELIEF", None, "enum"),
        ("known_goal", "CASA", "after_learning", "task-phase"),
        ("unknown_goal", "PBA", "after_learning", "phase-method"),
    ],
)
def test_teleop_refuses_a_trial_it_could_not_log_before_opening_a_window(
    scene, tmp_path, task, method, phase, rule
):
    with pytest.raises(ValueError, match=rule):
        run_teleop(scene, task, method, "h1", tmp_path, phase=phase, gui=True)
    assert not list(tmp_path.iterdir())


def test_keyboard_events_become_held_keys_and_enter_ends(monkeypatch):
    events = {
        p.B3G_UP_ARROW: p.KEY_IS_DOWN,
        ord("a"): p.KEY_WAS_TRIGGERED | p.KEY_WAS_RELEASED,  # a tap within one tick
        ord("s"): p.KEY_IS_DOWN | p.KEY_WAS_TRIGGERED,
        ord("q"): p.KEY_IS_DOWN,  # not a control key
    }
    monkeypatch.setattr(p, "getKeyboardEvents", lambda physicsClientId=0: events)
    keyboard = teleop.KeyboardKeys(client=0)
    assert keyboard.keys(0.0, None) == {"x+", "rot+", "z-"}
    events.pop(ord("a"))
    events[ord("s")] = p.KEY_WAS_RELEASED  # released after being held: not held any more
    assert keyboard.keys(0.05, None) == {"x+"}
    # Under X11 pybullet may drop the press of a tap shorter than its frame and report
    # only the release (measured under Xvfb with xdotool): still a tap.
    events.pop(ord("s"))  # pybullet reports a release once
    events[ord("d")] = p.KEY_WAS_RELEASED
    assert keyboard.keys(0.1, None) == {"x+", "rot-"}
    assert not keyboard.done
    events.pop(ord("d"))
    events[p.B3G_RETURN] = p.KEY_WAS_RELEASED  # a one-frame tap of Enter ends the trial
    assert keyboard.keys(0.15, None) == frozenset()
    assert keyboard.done and not keyboard.paused


def test_a_pause_key_ends_the_trial_as_paused(monkeypatch):
    events = {ord("p"): p.KEY_WAS_TRIGGERED}
    monkeypatch.setattr(p, "getKeyboardEvents", lambda physicsClientId=0: events)
    keyboard = teleop.KeyboardKeys(client=0, pause_keys=(ord("p"),))
    assert keyboard.keys(0.0, None) == frozenset()
    assert keyboard.done and keyboard.paused


def test_bindings_cover_the_eight_keys_once():
    assert sorted(teleop.KEY_BINDINGS.values()) == sorted(
        ["x+", "x-", "y+", "y-", "z+", "z-", "rot+", "rot-"]
    )


def test_cli_has_teleop_and_bench():
    parser = build_parser()
    args = parser.parse_args(
        ["teleop", "--task", "known_goal", "--method", "CASA", "--participant", "a", "--out", "d"]
    )
    assert args.func.__name__ == "_teleop" and args.scene is None  # the package's scene
    assert parser.parse_args(["bench", "--json"]).json


def test_teleop_help_works_from_any_directory(tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "casa_core.cli", "teleop", "--help"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    assert "--scene" in run.stdout


@pytest.mark.parametrize("command", ["teleop", "bench"])
def test_a_bad_scene_file_is_named_without_a_traceback(tmp_path, capsys, command):
    bad = tmp_path / "scene.yaml"
    bad.write_text("start: {position: [0, 0], rot: 0}\n", encoding="utf-8")
    args = [command, "--scene", str(bad)]
    if command == "teleop":
        args += ["--task", "known_goal", "--method", "NA", "--participant", "a"]
        args += ["--out", str(tmp_path / "logs")]
    assert main(args) == 2
    error = capsys.readouterr().err
    assert f"casa {command}: {bad}: " in error and "Traceback" not in error
    assert not (tmp_path / "logs").exists()


WINDOW_SCRIPT = textwrap.dedent(
    """
    import sys
    import pybullet as p
    from casa_core.scene import load_scene
    from casa_core.study.key_sources import ScriptedKeys
    from casa_core.study.teleop_session import run_teleop

    class KeysAndKeyboard(ScriptedKeys):
        # Scripted keys, while polling the window's keyboard as the real source does.
        def keys(self, t, state):
            assert isinstance(p.getKeyboardEvents(), dict)
            return super().keys(t, state)

    scene = load_scene()
    source = KeysAndKeyboard([(0.5, ["y+"]), (0.5, ["z+"])])
    run_teleop(scene, "known_goal", "CASA", "w1", sys.argv[1], key_source=source,
               countdown=1, realtime=False)
    """
)


@pytest.mark.skipif(shutil.which("Xvfb") is None, reason="Xvfb is not on PATH: no display")
def test_teleop_in_a_real_window_under_xvfb(tmp_path):
    server, display = start_xvfb()
    try:
        env = {**os.environ, "DISPLAY": display}
        run = subprocess.run(
            [sys.executable, "-c", WINDOW_SCRIPT, str(tmp_path)],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 0, run.stderr[-2000:]
        # pybullet's GUI prints its OpenGL context: a window was really opened.
        assert "Created GL" in run.stdout, run.stdout[-2000:]
    finally:
        server.terminate()
        server.wait(timeout=10)
    stem = tmp_path / "known_goal_no_misspecification_CASA"
    assert validate_paths([tmp_path]) == []
    _, frame = read_trial(stem)
    assert list(frame["keys"][:10]) == ["y+"] * 10


def test_learned_intent_files_join_the_known_goals_after_learning(scene, tmp_path):
    from casa_core.bench.suite import untrained_neural_intent
    from casa_core.learning import IRLConfig
    from casa_core.learning.library import save_intent
    from casa_core.planning import PlannerConfig
    from casa_core.study.closed_loop import trial_intents

    # A short planner keeps the test fast; the log, not the plan, is under test here.
    quick = PlannerConfig(iterations=20, warm_iterations=5)
    path = save_intent(
        tmp_path / "library",
        untrained_neural_intent(scene, seed=1, planner=quick),
        task="unknown_goal",
        participant="h1",
        seed=1,
        demos=[],
        history=[],
        config=IRLConfig(),
    )
    intents = trial_intents(scene, [path])
    assert [intent.name for intent in intents] == ["green", "purple", "neural"]
    script = ScriptedKeys([(1.0, ["y+"])])
    stem = run_teleop(
        scene,
        "unknown_goal",
        "CASA",
        "h1",
        tmp_path / "logs",
        phase="after_learning",
        gui=False,
        key_source=script,
        countdown=0,
        intents=intents,
    )
    meta, frame = read_trial(stem)
    assert meta["intents"] == ["green", "purple", "neural"]
    assert frame["beta:neural"].iloc[-1] > 0
    (tmp_path / "broken.intent.json").write_text("{", encoding="utf-8")
    with pytest.raises(ValueError, match="broken.intent.json"):
        trial_intents(scene, [tmp_path / "broken.intent.json"])


@pytest.mark.parametrize(("driven_to", "detected"), [("unknown_goal", True), ("known_goal", False)])
def test_misspecification_in_teleop_asks_for_and_records_demonstrations(
    scene, tmp_path, driven_to, detected
):
    # When no known intent explains the person, casa teleop asks for demonstrations and
    # records them. In an Unknown Goal trial the expert drives to
    # the end of `driven_to`: to red, which no known intent explains, or to green,
    # which one does.
    from casa_core.assist.tasks import task_waypoints
    from casa_core.study.key_sources import WaypointKeys
    from casa_core.study.teleop_session import teleop_session

    stems, found = teleop_session(
        scene,
        "unknown_goal",
        "CASA",
        "h2",
        tmp_path,
        n_demonstrations=2,
        make_key_source=lambda: WaypointKeys(task_waypoints(driven_to, scene)[1:]),
        gui=False,
        countdown=0,
        realtime=False,
    )
    assert found is detected
    if not detected:
        assert [s.name for s in stems] == ["unknown_goal_before_learning_CASA"]
        return
    assert [s.name for s in stems] == [
        "unknown_goal_before_learning_CASA",
        "unknown_goal_demonstration_NA_1",
        "unknown_goal_demonstration_NA_2",
    ]
    meta, frame = read_trial(stems[1])
    assert (meta["phase"], meta["method"], meta["source"]) == ("demonstration", "NA", "simulated")
    assert (frame["alpha"] == 1.0).all()  # demonstrations are unassisted


@pytest.mark.parametrize(
    ("name", "evidence", "expected"),
    [("casa", None, "commanded"), ("casa", "executed", "executed"), ("original", None, "executed")],
)
def test_the_log_says_what_inference_observed(scene, tmp_path, name, evidence, expected):
    # `casa teleop --preset/--evidence` reach the assistant, and the log's metadata
    # records them (the preset's evidence when --evidence is not given).
    args = ["teleop", "--task", "known_goal", "--method", "CASA", "--participant", "a"]
    parsed = build_parser().parse_args(
        [*args, "--out", "d", "--preset", name, *(["--evidence", evidence] if evidence else [])]
    )
    assert (parsed.preset, parsed.evidence) == (name, evidence)
    stem = run_teleop(
        scene,
        "known_goal",
        "CASA",
        "h3",
        tmp_path,
        gui=False,
        key_source=ScriptedKeys([(1.0, ["y+"])]),
        countdown=0,
        inference=preset(name, evidence=evidence),
    )
    meta, _ = read_trial(stem)
    assert meta["inference"] == {"preset": name, "evidence": expected}
    with pytest.raises(SystemExit):
        build_parser().parse_args([*args, "--out", "d", "--evidence", "robot"])
