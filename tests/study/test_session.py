"""``casa session``: the session's logic without a window, then a whole session in a real one.

The window test runs ``casa session`` under Xvfb and drives its real pybullet window
with synthetic key events (xdotool), as a participant would: a short session (a config
written here: 1-second previews, 2-second trials, one demonstration per task, one IRL
iteration) is killed mid-session, rerun with the same command, finished, and its
dataset validated. Screenshots of each kind of screen go to ``$CASA_SESSION_SHOTS``
(default: a temporary folder), for a person to look at.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from casa_core.config import DEFAULT_CONFIG, load_config
from casa_core.io import SURVEYS_NAME, read_surveys, read_trial, validate_paths
from casa_core.scene import load_scene
from casa_core.study import protocol, session_texts
from casa_core.study.closed_loop import TrialResult
from casa_core.study.session import (
    SESSION_FOLDER,
    SessionRecord,
    SessionSettings,
    Step,
    label_of,
    participant_index,
    robot_labels,
)
from casa_core.study.simulate import participant_id
from casa_core.vocabulary import METHODS, QUESTIONS
from tests.display import start_xvfb

#: Words that would tell a participant which method a robot is.
METHOD_WORDS = re.compile(
    r"\b(NA|PBA|CASA|BELIEF)\b|casa|confiden|blend|arbitrat|policy|distance|belief",
    re.IGNORECASE,
)


def settings(**overrides) -> SessionSettings:
    config = load_config(DEFAULT_CONFIG)
    config["simulation"].update(overrides.pop("simulation", {}))
    config["session"].update(overrides)
    return SessionSettings.from_config(config)


def fake_trial(spec, participant: str, *, beta: float = 0.0) -> TrialResult:
    """A 1-second trial log of ``spec`` whose known intents' beta_hat is ``beta`` throughout."""
    t = np.round(np.arange(0, 1.05, 0.05), 6)
    frame = pd.DataFrame({"t": t, "x": 0.45, "y": -0.22, "z": 0.38, "rot": 0.0, "keys": ""})
    frame["alpha"] = 1.0
    for i in range(7):
        frame[f"q{i + 1}"] = 0.0
    for name in ("green", "purple"):
        frame[f"beta:{name}"] = beta
        frame[f"belief:{name}"] = 0.5
    meta = {
        "participant": participant,
        "task": spec.task,
        "method": spec.method,
        "phase": spec.phase,
        "source": "human",
        "intents": ["green", "purple"],
    }
    return TrialResult(meta=meta, frame=frame)


# -- the session's logic, without a window -----------------------------------------------


def test_counterbalancing_is_the_simulated_studys_for_the_same_number():
    # `casa simulate --participant N` simulates participant index N - 1, id pNN, with
    # protocol.before_learning(N - 1): a real participant numbered N runs the same order.
    for number in range(1, 14):
        index = number - 1
        assert participant_index(participant_id(index)) == index
        assert participant_index(f"P{number:02d}") == index
        record = SessionRecord(Path("unused"), f"P{number:02d}", settings())
        trials = [s.spec for s in record.steps() if s.kind == "trial"][: 1 + 3 + 3 + 3]
        assert trials == protocol.before_learning(index)
    # 6 participants in a row meet the 6 orders once each (the orders' construction).
    orders = {protocol.method_order(participant_index(f"P{n}")) for n in range(1, 7)}
    assert len(orders) == 6


def test_the_steps_are_the_protocol_and_questions_follow_each_study_condition(tmp_path):
    record = SessionRecord(tmp_path / "P01", "P01", settings(simulation={"demonstrations": 2}))
    steps = record.steps()
    kinds = [s.kind for s in steps]
    # 10 trials before learning, 2 x 2 demonstrations, learning, 2 after: 16 trials;
    # questions after the 9 + 2 study conditions (not the practice nor demonstrations).
    assert kinds.count("trial") == 16 and kinds.count("questions") == 11
    assert kinds.count("learning") == 1
    assert steps[0] == Step("trial", protocol.TrialSpec("familiarization", "NA", "familiarization"))
    for before, after in zip(steps, steps[1:], strict=False):
        if after.kind == "questions":
            assert before == Step("trial", after.spec)
    learning = kinds.index("learning")
    assert all(s.spec.phase == "demonstration" for s in steps[learning - 4 : learning])
    assert [s.spec.phase for s in steps[learning + 1 :]] == ["after_learning"] * 4


def test_demonstrations_only_when_detected_follow_the_recorded_casa_trials(tmp_path):
    record = SessionRecord(
        tmp_path / "P01", "P01", settings(simulation={"demonstrations_when": "detected"})
    )
    assert "learning" not in [s.kind for s in record.steps()]
    # beta_hat 0 < epsilon throughout: misspecification detected in Unknown Goal only.
    goal = protocol.TrialSpec("unknown_goal", "CASA", "before_learning")
    skill = protocol.TrialSpec("unknown_skill", "CASA", "before_learning")
    record.write_trial(goal, fake_trial(goal, "P01", beta=0.0))
    record.write_trial(skill, fake_trial(skill, "P01", beta=5.0))
    demos = [s.spec.task for s in record.steps() if s.spec and s.spec.phase == "demonstration"]
    assert demos == ["unknown_goal"] * 5  # simulation.demonstrations: 5
    assert "misspecification detected: True" in (tmp_path / "P01" / f"{goal.stem}.json").read_text()


def test_resume_point_is_the_first_step_not_on_disk_and_nothing_is_redone(tmp_path):
    record = SessionRecord(tmp_path / "P02", "P02", settings())
    steps = record.steps()
    for step in steps[:4]:  # practice, first Known Goal trial and its answers, second trial
        if step.kind == "trial":
            record.write_trial(step.spec, fake_trial(step.spec, "P02"))
        else:
            record.write_answers(step.spec, dict.fromkeys(QUESTIONS, 4))
    assert record.next_step() == steps[4]  # the second trial's questions
    with pytest.raises(FileExistsError, match="never overwritten"):
        record.write_trial(steps[3].spec, fake_trial(steps[3].spec, "P02"))
    # Answers written twice for a condition are replaced, never doubled (unique-answer).
    record.write_answers(steps[2].spec, dict.fromkeys(QUESTIONS, 6))
    answers = read_surveys(tmp_path / "P02" / SURVEYS_NAME)
    assert len(answers) == 3 and (answers["score"] == 6).all()
    assert (answers["source"] == "human").all()
    assert validate_paths([tmp_path]) == []


def test_no_text_of_any_step_names_a_method():
    for index in range(6):
        labels = robot_labels(index)
        assert sorted(labels) == sorted(METHODS)
        assert len(set(labels.values())) == 3
        record = SessionRecord(Path("unused"), f"P{index + 1}", settings())
        for step in [*record.steps(), *(Step("trial", s) for s in protocol.after_learning())]:
            if step.spec is None:
                continue
            label = label_of(step.spec, index)
            shown = list(session_texts.instructions(step.spec, label, demonstrations=5))
            if label:
                shown += [session_texts.statement(q, label) for q in QUESTIONS]
            for text in shown:
                assert not METHOD_WORDS.search(text), (step, text)
    others = [session_texts.WELCOME, session_texts.GOODBYE, session_texts.STOPPED]
    for task in session_texts.TARGETS:
        others.append((session_texts.learning_message(1, 2, task),))
    from casa_core.robot import screens, teleop

    others.append((teleop.HELP, screens.SCALE))
    for texts in others:
        for text in texts:
            assert not METHOD_WORDS.search(text), text


class FakeWindow:
    """The session window's interface over a headless arm, answering from a script."""

    def __init__(self, scene, *, notify=None, script=()):
        from casa_core.robot.sim import ArmSimulation

        self.sim = ArmSimulation(scene)
        self.client = self.sim.client
        self.script = list(script)  # answers of instructions/pause, in order
        self.rate = self.slowest = 1.0
        self.shown: list[str] = []

    def _next(self, default):
        return self.script.pop(0) if self.script else default

    def message(self, title, body, kind, seconds=2.0):
        self.shown += [title, body]

    def instructions(self, title, body, task):
        self.shown += [title, body]
        return self._next("start")

    def preview(self, task, reference, seconds):
        pass

    def countdown(self, seconds):
        pass

    def keyboard(self):
        from casa_core.study.key_sources import ScriptedKeys

        keys = ScriptedKeys([(0.5, ["x+"])])
        keys.paused = False
        return keys

    def start_trial(self, task):
        pass

    def on_tick(self, t, state, keys, alpha):
        pass

    def end_trial(self, message):
        pass

    def likert(self, statement, number, total):
        self.shown.append(statement)
        return 5

    def pause(self):
        return self._next("continue")

    def close(self):
        self.sim.close()


def test_stopping_from_the_pause_screen_keeps_what_was_recorded_and_resumes_there(tmp_path):
    from casa_core.scene import DEFAULT_SCENE
    from casa_core.study.session_run import STOPPED, run_session

    scene = load_scene()
    windows = []

    def factory(script):
        def make(scene, *, notify=None):
            windows.append(FakeWindow(scene, script=script))
            return windows[-1]

        return make

    options = {"settings": settings(), "scene_source": DEFAULT_SCENE}
    # Practice recorded, then P at the next instructions and a confirmed stop.
    outcome = run_session(
        scene, "P05", tmp_path, window_factory=factory(["start", "pause", "abort"]), **options
    )
    assert outcome == STOPPED
    folder = tmp_path / "P05"
    assert [p.name for p in folder.glob("*.json")] == ["familiarization_familiarization_NA.json"]
    log = (folder / SESSION_FOLDER / "session.log").read_text()
    assert "stopped by the participant; everything recorded is kept" in log
    record = SessionRecord(folder, "P05", settings())
    first_assisted = protocol.before_learning(participant_index("P05"))[1]
    assert record.next_step() == Step("trial", first_assisted)
    # The window showed no method's name, in the instructions or the questions.
    assert not [text for text in windows[0].shown if METHOD_WORDS.search(text)]
    # The same command again resumes at the first assisted trial.
    assert "next step: trial" in log
    run_session(
        scene, "P05", tmp_path, window_factory=factory(["start", "pause", "abort"]), **options
    )
    assert len(list(folder.glob("*.json"))) == 2
    assert (
        f"next step: trial {first_assisted.stem}"
        in (folder / SESSION_FOLDER / "session.log").read_text()
    )


def test_quiet_keeps_the_methods_off_the_console_and_in_the_session_log(tmp_path, capsys):
    from casa_core.scene import DEFAULT_SCENE
    from casa_core.study.session_run import run_session

    def make(scene, *, notify=None):
        return FakeWindow(scene, script=["start", "pause", "abort"])

    options = {"settings": settings(), "scene_source": DEFAULT_SCENE, "window_factory": make}
    methods = re.compile(r"\b(NA|PBA|CASA)\b")
    run_session(load_scene(), "P05", tmp_path / "loud", **options)
    assert methods.search(capsys.readouterr().out)  # without it the console names them
    run_session(load_scene(), "P05", tmp_path / "quiet", quiet=True, **options)
    console = capsys.readouterr().out
    assert "session.log only" in console and not methods.search(console)
    log = tmp_path / "quiet" / "P05" / SESSION_FOLDER / "session.log"
    assert "method order: participant P05" in log.read_text()


def test_a_dataset_of_another_layout_is_refused_before_a_window_opens(tmp_path, capsys):
    from casa_core.cli import main
    from casa_core.scene import DEFAULT_SCENE

    moved = DEFAULT_SCENE.read_text().replace("red: [0.40, 0.22, 0.12]", "red: [0.40, 0.25, 0.12]")
    assert moved != DEFAULT_SCENE.read_text()
    (tmp_path / "scene.yaml").write_text(moved, encoding="utf-8")
    assert main(["session", "--participant", "P01", "--out", str(tmp_path)]) == 2
    error = capsys.readouterr().err
    assert "the dataset's scene is not the layout of" in error and "Traceback" not in error
    assert not (tmp_path / "P01").exists()


def test_a_participant_id_without_a_number_is_refused_naming_the_rule(tmp_path, capsys):
    from casa_core.cli import main

    assert main(["session", "--participant", "anna", "--out", str(tmp_path)]) == 2
    assert "must end in the participant's number" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


# -- a whole session in a real window ------------------------------------------------------

TOOLS = ("Xvfb", "xdotool")
MISSING = [tool for tool in TOOLS if shutil.which(tool) is None]
#: The short session: 2-second trials, 1-second previews and countdowns, one demonstration.
SHORT = """\
simulation: {demonstrations: 1}
session: {max_duration: 2.0, countdown: 1, preview: 1.0, learning_iterations: 1}
"""
#: Screens the test photographs, once each.
SHOTS = (
    "welcome",
    "instructions",
    "preview",
    "countdown",
    "trial",
    "end-of-trial",
    "likert",
    "learning",
    "pause",
    "confirm-abort",
    "end",
)


class Operator:
    """A scripted participant: reads the session's screens from its output and presses keys."""

    def __init__(self, display: str, shots: Path):
        self.env = {**os.environ, "DISPLAY": display}
        self.display = display
        self.shots = shots
        self.seen: set[str] = set()
        self.score = 0
        # At the first instructions of each run: P (first run), Escape (second run).
        self.interrupt: list[str] = ["p", "Escape"]
        self.first_instructions = True
        self.pauses = 0
        self.titles: set[str] = set()

    def xdotool(self, *args: str) -> str:
        run = subprocess.run(
            ["xdotool", *args], env=self.env, capture_output=True, text=True, timeout=10
        )
        return run.stdout

    def key(self, name: str) -> None:
        # The pointer in the window: without a window manager, keys go to the window under it.
        self.xdotool("mousemove", "500", "380")
        self.xdotool("key", name)

    def shoot(self, kind: str, delay: float = 0.25) -> None:
        if kind in self.seen or kind not in SHOTS:
            return
        self.seen.add(kind)
        from PIL import ImageGrab

        time.sleep(delay)
        ImageGrab.grab(xdisplay=self.display).save(self.shots / f"{len(self.seen):02d}-{kind}.png")

    def react(self, kind: str) -> None:
        self.shoot(kind)
        if kind in ("welcome", "end-of-trial"):
            if kind == "welcome":
                for window in self.xdotool("search", "--name", ".").split():
                    self.titles.add(self.xdotool("getwindowname", window).strip())
                self.key("Return")
        elif kind == "instructions":
            if self.first_instructions and self.interrupt:
                self.key(self.interrupt.pop(0))
            else:
                self.key("Return")
            self.first_instructions = False
        elif kind == "trial":
            self.xdotool("mousemove", "500", "380")
            self.xdotool("keydown", "Up")
            time.sleep(0.4)
            self.xdotool("keyup", "Up")
            self.key("Return")  # a tap: xdotool holds it about 12 ms
        elif kind == "likert":
            self.score = self.score % 7 + 1
            self.key(str(self.score))
            time.sleep(0.1)
            self.key("Return")
        elif kind == "pause":
            self.pauses += 1
            # The second pause asks to stop, then takes it back (N).
            self.key("q" if self.pauses == 2 else "c")
        elif kind == "confirm-abort":
            self.key("n")


def session_command(out: Path, config: Path) -> list[str]:
    return [
        sys.executable,
        "-m",
        "casa_core.cli",
        "session",
        "--participant",
        "P03",
        "--out",
        str(out),
        "--config",
        str(DEFAULT_CONFIG),
        "--config",
        str(config),
    ]


def drive(command, cwd: Path, operator: Operator, *, kill_after_trials: int | None = None):
    """Run the session, reacting to each screen; kill it by pid mid-trial if asked."""
    process = subprocess.Popen(
        command,
        cwd=cwd,
        env=operator.env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    lines, recorded = [], 0
    try:
        for line in process.stdout:
            lines.append(line.rstrip())
            recorded += " recorded " in line
            if line.startswith("screen "):
                kind = line.split()[1]
                if kind == "trial" and kill_after_trials is not None:
                    if recorded >= kill_after_trials:
                        time.sleep(0.5)
                        os.kill(process.pid, signal.SIGKILL)
                        break
                operator.react(kind)
        process.wait(timeout=60)
    finally:
        if process.poll() is None:
            os.kill(process.pid, signal.SIGKILL)
            process.wait()
    return process.returncode, lines


@pytest.mark.skipif(bool(MISSING), reason=f"{' and '.join(MISSING)} not on PATH: no display")
def test_a_whole_session_in_a_real_window_resumes_after_a_kill_and_validates(tmp_path):
    shots = Path(os.environ.get("CASA_SESSION_SHOTS") or tmp_path / "shots")
    shots.mkdir(parents=True, exist_ok=True)
    config = tmp_path / "short.yaml"
    config.write_text(SHORT, encoding="utf-8")
    elsewhere = tmp_path / "elsewhere"  # not the repository: paths must resolve from anywhere
    elsewhere.mkdir()
    out = tmp_path / "data" / "raw" / "mylab"
    command = session_command(out, config)
    server, display = start_xvfb()
    try:
        operator = Operator(display, shots)
        code, first = drive(command, elsewhere, operator, kill_after_trials=5)
        assert code == -signal.SIGKILL, "\n".join(first[-30:])
        folder = out / "P03"
        on_disk = sorted(p.stem for p in folder.glob("*.json"))
        assert len(on_disk) == 5, on_disk
        operator.first_instructions = True
        code, second = drive(command, elsewhere, operator)
        assert code == 0, "\n".join(second[-40:])
    finally:
        server.terminate()
        server.wait(timeout=10)
    log = "\n".join(second)
    record = SessionRecord(folder, "P03", settings(simulation={"demonstrations": 1}))
    plan = [s.spec.stem for s in record.steps() if s.kind == "trial"]
    # It continued at the sixth trial: the five on disk were not run again.
    assert f"next step: trial {plan[5]}" in log
    assert sum(" recorded " in line for line in second) == len(plan) - 5
    assert sorted(p.stem for p in folder.glob("*.json")) == sorted(plan)
    assert sorted(p.stem for p in folder.glob("*.csv") if p.name != SURVEYS_NAME) == sorted(plan)
    # The keys the operator held (Up: away from the robot) reached the logs.
    held = pd.concat([read_trial(folder / stem)[1]["keys"] for stem in plan])
    assert held.str.contains("x+", regex=False).any()
    answers = read_surveys(folder / SURVEYS_NAME)
    assert len(answers) == 3 * 11 and (answers["source"] == "human").all()
    # Counterbalancing printed in the log (participant 3: order 2 of the simulated study's).
    assert "order 2 mod 6 = 2" in log and ", ".join(protocol.method_order(2)) in log
    assert "loop rate" in log
    # P paused the first run; Escape closed the window in the second: reopened, paused.
    assert "paused before finishing: trial familiarization" in "\n".join(first)
    assert "the window was closed (Escape or its close button): reopened, paused" in log
    # The window's title (pybullet's own) names no method either.
    assert operator.titles and not [t for t in operator.titles if METHOD_WORDS.search(t)]
    assert operator.pauses == 3  # the first run's, Escape's, and the one taken back
    result = subprocess.run(
        [sys.executable, "-m", "casa_core.cli", "validate", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    # The workflow's `process` rule on it: the tables, the answers as the participant's.
    processed = tmp_path / "processed"
    process = [sys.executable, "-m", "casa_core.cli", "process", str(out), "--out", str(processed)]
    process += ["--scene", str(out / "scene.yaml"), "--dataset", "mylab"]
    result = subprocess.run(process, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    likert = pd.read_csv(processed / "likert.csv", keep_default_na=False)
    assert len(likert) == 3 * 11 and (likert["answered_by"] == "participant").all()
    trials = pd.read_csv(processed / "trials.csv", keep_default_na=False)
    assert set(trials["method"]) == set(METHODS)
    assert (out / "scene.yaml").is_file() and (folder / SESSION_FOLDER / "session.log").is_file()
    assert load_scene(out / "scene.yaml") == load_scene()
    missing_shots = set(SHOTS) - {p.stem.split("-", 1)[1] for p in shots.glob("*.png")}
    assert not missing_shots, missing_shots
