"""``casa session``'s loop: the steps of a participant's session, run in one window.

:func:`run_session` asks the participant's folder which step is next
(:meth:`casa_core.study.session.SessionRecord.next_step`), runs it in the window
(:class:`casa_core.robot.screens.SessionWindow`) and records it, until the session is
complete or the participant stops it from the pause screen. Trials run through the
closed loop of the simulated study (:func:`casa_core.study.closed_loop.run_trial`).
Everything the session does, the method of each trial included, goes to the session
log (``.session/session.log`` in the participant's folder, and the console); the
window shows only neutral labels.
"""

from __future__ import annotations

import threading
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pybullet as p

from casa_core.assist.tasks import intended_trajectory
from casa_core.defaults import HORIZON
from casa_core.io import SCHEMA, check_meta
from casa_core.io.atomic import atomic_write_text
from casa_core.io.contract import SCENE_NAME, TRIAL_SUFFIXES
from casa_core.robot.devices import CONTROLS
from casa_core.robot.screens import SLOW, SessionWindow, WindowClosed
from casa_core.scene import Scene, load_scene
from casa_core.study import session_texts as texts
from casa_core.study.closed_loop import run_trial, trial_intents
from casa_core.study.command_sources import DeviceCommands
from casa_core.study.session import (
    SessionRecord,
    SessionSettings,
    Step,
    label_of,
    method_order_line,
)
from casa_core.vocabulary import LEARNED_NAMES, QUESTIONS

COMPLETE, STOPPED = "complete", "stopped"
#: A trial's outcome when its device was lost: the session stops.
LOST = "lost"


class SessionLog:
    """Timestamped lines in the session log (rewritten atomically), echoed on the console
    unless ``echo`` is false: the log names the methods, which a participant who can see
    the console must not read."""

    def __init__(self, path: Path, *, echo: bool = True):
        self.path, self.echo = path, echo
        self.text = path.read_text(encoding="utf-8") if path.is_file() else ""

    def __call__(self, line: str) -> None:
        stamped = f"{datetime.now(UTC).isoformat(timespec='seconds')} {line}"
        if self.echo:
            print(stamped, flush=True)
        self.text += stamped + "\n"
        atomic_write_text(self.path, self.text)


def check_dataset_scene(out: Path, scene: Scene, source: Path) -> None:
    """Give the dataset the scene's file (``OUT/scene.yaml``), or check it is the same layout.

    The workflow builds a dataset with its own ``scene.yaml``, so the tables are
    computed in the layout the participants saw.
    """
    own = out / SCENE_NAME
    if not own.is_file():
        atomic_write_text(own, source.read_text(encoding="utf-8"))
    elif load_scene(own) != scene:
        raise ValueError(
            f"{own}: the dataset's scene is not the layout of {source}; every participant of "
            f"a dataset must see the same scene (give --scene {own}, or another --out)"
        )


def run_session(
    scene: Scene,
    participant: str,
    out: Path | str,
    *,
    settings: SessionSettings,
    scene_source: Path,
    window_factory=SessionWindow,
    quiet: bool = False,
    device=None,
) -> str:
    """Run (or resume) one participant's session; :data:`COMPLETE` or :data:`STOPPED`.

    Parameters
    ----------
    scene : Scene
        The layout, loaded from ``scene_source`` (copied into the dataset).
    participant : str
        The id; ends in the participant's number (the counterbalancing).
    out : path
        The dataset's folder; the participant's is ``out/<participant>``.
    settings : SessionSettings
    window_factory : callable
        ``window_factory(scene, notify=...)`` opens the window.
    quiet : bool
        Write the session log's lines (the method order, each trial's method) to the log
        only, not to the console.
    device : Device, optional
        The open continuous device of ``settings.input``
        (:func:`casa_core.robot.devices.open_device`); None drives with the keyboard. A
        device lost mid-trial stops the arm, keeps the trial as far as it ran and stops
        the session.

    Raises
    ------
    ValueError
        If the participant id or the dataset's scene cannot be used; nothing is opened.
    """
    out = Path(out)
    record = SessionRecord(out / participant, participant, settings)
    problems = check_meta(
        {
            "schema": SCHEMA,
            "participant": participant,
            "task": "known_goal",
            "method": "NA",
            "phase": "no_misspecification",
            "source": "human",
        },
        f"participant {participant!r}",
    )
    if problems:
        raise ValueError("cannot log this participant: " + "; ".join(map(str, problems)))
    check_dataset_scene(out, scene, scene_source)
    log = SessionLog(record.state_folder / "session.log", echo=not quiet)
    if quiet:
        print(f"casa session: the steps and the method order go to {log.path} only", flush=True)
    log(f"session of participant {participant} in {record.folder.resolve()}")
    log(method_order_line(participant))
    _remove_halves(record, log)
    step = record.next_step()
    if step is None:
        log("the session is already complete: nothing to do")
        return COMPLETE
    log(f"next step: {step.describe()}")
    if (device is None) != (settings.input == "keyboard"):
        raise ValueError(f"session input {settings.input!r} needs its device open, and only it")
    runner = _Runner(record, scene, log, window_factory, device)
    try:
        return runner.run()
    finally:
        runner.window.close()


def _remove_halves(record: SessionRecord, log: SessionLog) -> None:
    """A trial log with one file of two was cut by a kill: it is run again."""
    for step in record.steps():
        if step.kind != "trial":
            continue
        assert step.spec is not None  # a trial step carries its spec
        stem = record.stem(step.spec)
        halves = [stem.with_suffix(s) for s in TRIAL_SUFFIXES if stem.with_suffix(s).is_file()]
        if len(halves) == 1:
            halves[0].unlink()
            log(f"removed {halves[0].name}, the half of an unfinished log; the trial runs again")


class _Runner:
    def __init__(
        self, record: SessionRecord, scene: Scene, log: SessionLog, window_factory, device
    ):
        self.record, self.scene, self.log = record, scene, log
        self.settings = record.settings
        self.device = device
        self._after: list | None = None  # the intents after learning, once loaded
        self.window = window_factory(scene, notify=lambda kind: print(f"screen {kind}", flush=True))
        if device is not None:
            self.window.controls = CONTROLS[self.settings.input]

    def run(self) -> str:
        outcome = self._guarded(lambda: self.window.message(*texts.WELCOME, "welcome", None))
        while True:
            if outcome == "pause":
                if self._pause() == "abort":
                    self.log("stopped by the participant; everything recorded is kept")
                    self._guarded(lambda: self.window.message(*texts.STOPPED, "stopped"))
                    return STOPPED
                self.log("continued")
            step = self.record.next_step()
            if step is None:
                break
            outcome = self._guarded(lambda step=step: self._step(step))
            if outcome == LOST:
                self.log(
                    f"the session stops: the {self.settings.input} is gone; everything "
                    "recorded is kept. Plug it in and run the same command to continue"
                )
                self._guarded(lambda: self.window.message(*texts.STOPPED, "stopped"))
                return STOPPED
            if outcome == "pause":
                self.log(f"paused before finishing: {step.describe()}")
        self.log("session complete")
        self._guarded(lambda: self.window.message(*texts.GOODBYE, "end", 3.0))
        return COMPLETE

    def _guarded(self, action):
        """Run a screen; a closed window (Escape) is reopened and counts as a pause."""
        try:
            return action()
        except (WindowClosed, p.error):
            if p.isConnected(self.window.client):
                raise
            self.log("the window was closed (Escape or its close button): reopened, paused")
            self.window.reopen()
            return "pause"

    def _pause(self) -> str:
        while True:
            choice = self._guarded(self.window.pause)
            if choice != "pause":
                return choice

    def _step(self, step: Step) -> str | None:
        if step.kind == "trial":
            return self._trial(step.spec)
        if step.kind == "questions":
            return self._questions(step.spec)
        self._learning()
        return None

    def _learned_intents(self) -> list:
        """What the robot knows after learning, planned from the start once, before GO.

        The assistant plans every intent from the start state when a trial begins; for
        a learned intent that takes seconds, so it is done here, on a waiting screen, and
        the intents (their plans cached) serve every trial after learning.
        """
        if self._after is None:
            self.window.message(*texts.GETTING_READY, "getting-ready", 0.0)
            learned = self.record.learned_files()
            intents = trial_intents(self.scene, learned, inference=self.settings.inference)
            start = self.window.sim.reset_to_start()
            for intent in intents:
                intent.cost_to_go(start, HORIZON)  # the assistant's default
            self._after = intents
        return self._after

    def _trial(self, spec) -> str | None:
        window, settings = self.window, self.settings
        label = label_of(spec, self.record.index)
        # Planned before the instructions, on a waiting screen of its own.
        intents = self._learned_intents() if spec.phase == "after_learning" else None
        title, body = texts.instructions(
            spec,
            label,
            demonstrations=settings.demonstrations,
            trial_length=self.scene.trial_length,
        )
        if window.instructions(title, body, spec.task) == "pause":
            return "pause"
        window.preview(spec.task, intended_trajectory(spec.task, self.scene), settings.preview)
        window.countdown(settings.countdown)
        source = self._source(window.keyboard())
        window.start_trial(spec.task)
        started = datetime.now(UTC).isoformat(timespec="seconds")
        result = run_trial(
            self.scene,
            spec.task,
            spec.method,
            source,
            participant=self.record.participant,
            intents=intents,
            phase=spec.phase,
            source_kind="human",
            max_duration=settings.max_duration,
            sim=window.sim,
            inference=settings.inference,
            on_tick=window.on_tick,
        )
        if source.paused:
            self.log(f"trial {spec.stem} interrupted by a pause: not recorded, it runs again")
            return "pause"
        rate, slowest = window.rate, window.slowest
        result.meta["started_at"] = started
        shown = f"shown as {label}" if label else "no robot help"
        result.meta["notes"] = (
            f"{shown}; loop rate {rate:.3f} of real time, slowest 2 s {slowest:.3f}"
        )
        lost = getattr(source, "lost", None)
        if lost:
            result.meta["notes"] += f"; ended early, the arm stopped: {lost}"
        stem = self.record.write_trial(spec, result)
        seconds = float(result.frame["t"].iloc[-1])
        if lost:
            self.log(
                f"recorded {stem.name} as far as it ran ({shown}, method {spec.method}): "
                f"{seconds:.1f} s, then {lost}; the arm was stopped"
            )
            window.end_trial("The controller is gone: the arm stopped. Saved.")
            return LOST
        by_enter = source.done and self.scene.trial_length is None
        ended = "Enter" if by_enter else "time limit"
        self.log(
            f"recorded {stem.name} ({shown}, method {spec.method}): {seconds:.1f} s, ended by "
            f"{ended}, loop rate {100 * rate:.1f}% of real time (slowest 2 s "
            f"{100 * slowest:.1f}%)"
        )
        if min(rate, slowest) < SLOW:
            self.log(
                f"WARNING: the loop ran below {100 * SLOW:.0f}% of real time in {stem.name} "
                f"({100 * rate:.1f}% over the trial, {100 * slowest:.1f}% in its slowest 2 s): "
                "the arm moved slower than commanded"
            )
        window.end_trial("Finished. Saved." if by_enter else "Time is up. Saved.")
        return None

    def _source(self, keyboard):
        """The trial's source: the keyboard, or the device with the keyboard's Enter and P."""
        if self.device is None:
            return keyboard
        return DeviceCommands.in_scene(
            self.device, self.scene, input=self.settings.input, keyboard=keyboard
        )

    def _questions(self, spec) -> str | None:
        label = label_of(spec, self.record.index)
        assert label is not None  # questions follow only the trials with a robot's help
        scores = {}
        for number, question in enumerate(QUESTIONS, start=1):
            score = self.window.likert(texts.statement(question, label), number, len(QUESTIONS))
            if score is None:
                return "pause"
            scores[question] = score
        self.record.write_answers(spec, scores)
        answers = ", ".join(f"{q} {s}" for q, s in scores.items())
        self.log(f"answers for {spec.stem} ({label}): {answers} -> {self.record.surveys_path}")
        return None

    def _learning(self) -> None:
        record = self.record
        tasks = record.demonstration_tasks()
        for number, task in enumerate(tasks, start=1):
            if record.intent_file(task).is_file():
                continue
            state: dict[str, Any] = {"done": 0.0, "result": None, "error": None}

            def progress(iteration, most, state=state):
                state["done"] = iteration / most

            def learn(task=task, state=state):
                try:
                    state["result"] = record.learn(task, self.scene, progress=progress)
                except Exception as error:  # reported in the main thread
                    state["error"] = error

            self.log(f"learning {LEARNED_NAMES[task]} from the demonstrations of {task}")
            worker = threading.Thread(target=learn, daemon=True)
            worker.start()
            message = texts.learning_message(number, len(tasks), task)
            while worker.is_alive():
                fraction = (number - 1 + 0.95 * state["done"]) / len(tasks)
                try:
                    self.window.resting(message, fraction)
                except (WindowClosed, p.error):
                    self.log("the window was closed during learning: reopened")
                    self.window.reopen()
                worker.join(0.25)
            if state["error"] is not None:
                raise state["error"]
            path, seconds = state["result"]
            self.log(f"learned {path.name} in {seconds:.1f} s -> {path}")
        return None
