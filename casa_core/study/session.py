"""A real participant's session: the protocol's steps, what is recorded, where to resume.

``casa session`` runs one participant's whole protocol (paper, Sec. V-A) in one window;
this module is the part that knows nothing of the window. The steps are the simulated
study's (:mod:`casa_core.study.protocol`): familiarization, Known Goal, the unknown
tasks before learning, the demonstrations (always, or only for the tasks in which CASA
flagged misspecification), learning, CASA after learning. After each trial of a study
condition the participant answers the three Likert questions.

The method order is the simulated study's counterbalancing: participant ``P07`` is
number 7, 0-based index 6, and uses :func:`casa_core.study.protocol.method_order` of 6,
exactly as ``casa simulate --participant 7``. The participant sees the methods under
neutral labels (:func:`robot_labels`), never their names.

Everything lives in the participant's folder ``OUT/<participant>``: the trial logs
(casa-trial/1) and ``surveys.csv``, each written atomically when it is complete, and the
hidden folder ``.session`` (the session log and the learned intents; validation and the
workflow skip hidden folders). A step is done when its output is on disk, so rerunning
the same command resumes at the first step not recorded (:meth:`SessionRecord.next_step`).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from casa_core.assist.presets import Preset
from casa_core.io import SURVEY_COLUMNS, SURVEYS_NAME, read_surveys, read_trial, write_surveys
from casa_core.io.contract import INTENT_SUFFIX, SINGLE_TRIAL_PHASES
from casa_core.robot.devices import DEADZONE
from casa_core.scene import Scene
from casa_core.study import protocol
from casa_core.study.closed_loop import TrialResult
from casa_core.study.protocol import TrialSpec
from casa_core.vocabulary import LEARNED_NAMES, QUESTIONS, UNANALYSED_PHASES, UNKNOWN_TASKS

#: The hidden folder of a participant's session state (skipped by validation).
SESSION_FOLDER = ".session"
#: The neutral names of the methods, in the order the participant first meets them.
LABELS = ("robot A", "robot B", "robot C")
#: The label of CASA after learning: a robot the participant has not met.
AFTER_LEARNING_LABEL = "robot D"
_NUMBER = re.compile(r"(\d+)$")


def participant_index(participant: str) -> int:
    """The 0-based index of a participant id ending in its 1-based number.

    The simulated study's participant N (``casa simulate --participant N``, id ``pNN``)
    has index N - 1; so has a real participant whose id ends in N.

    Examples
    --------
    >>> participant_index("P07"), participant_index("p01"), participant_index("lab2-12")
    (6, 0, 11)
    >>> participant_index("anna")
    Traceback (most recent call last):
    ...
    ValueError: participant 'anna': the id must end in the participant's number (1, 2, ...) \
from which the method order is counterbalanced, e.g. P07
    """
    found = _NUMBER.search(participant)
    if found is None or int(found.group(1)) < 1:
        raise ValueError(
            f"participant {participant!r}: the id must end in the participant's number "
            "(1, 2, ...) from which the method order is counterbalanced, e.g. P07"
        )
    return int(found.group(1)) - 1


def robot_labels(index: int) -> dict[str, str]:
    """Method -> neutral label for the participant of 0-based ``index``.

    The first method of the participant's order is "robot A", and so on, so a label
    tells nothing of the method across participants.

    Examples
    --------
    >>> robot_labels(0)
    {'NA': 'robot A', 'PBA': 'robot B', 'CASA': 'robot C'}
    >>> robot_labels(1)
    {'NA': 'robot A', 'CASA': 'robot B', 'PBA': 'robot C'}
    """
    return dict(zip(protocol.method_order(index), LABELS, strict=True))


def label_of(spec: TrialSpec, index: int) -> str | None:
    """The label a trial's robot is shown under; None for trials without a robot's help.

    Examples
    --------
    >>> label_of(TrialSpec("known_goal", "CASA", "no_misspecification"), 0)
    'robot C'
    >>> label_of(TrialSpec("unknown_goal", "CASA", "after_learning"), 0)
    'robot D'
    >>> label_of(TrialSpec("familiarization", "NA", "familiarization"), 0) is None
    True
    """
    if spec.phase in UNANALYSED_PHASES:
        return None
    if spec.phase == "after_learning":
        return AFTER_LEARNING_LABEL
    return robot_labels(index)[spec.method]


@dataclass(frozen=True)
class Step:
    """One step of a session: a ``trial``, its ``questions``, or ``learning``."""

    kind: str
    spec: TrialSpec | None = None

    def describe(self) -> str:
        """The step for the session log (it names the method: never shown in the window)."""
        if self.spec is None:
            return self.kind
        return f"{self.kind} {self.spec.stem}"


@dataclass(frozen=True)
class SessionSettings:
    """What a session reads from the config: ``session``, ``simulation``, ``inference``."""

    max_duration: float
    countdown: int
    preview: float
    demonstrations: int
    demonstrations_when: str
    epsilon: float
    seed: int
    learning_iterations: int | None
    inference: Preset
    input: str = "keyboard"
    deadzone: float = DEADZONE

    @classmethod
    def from_config(cls, config: dict) -> SessionSettings:
        """From a validated config (:func:`casa_core.config.load_config`).

        The protocol's settings and the inference are the simulated study's
        (:meth:`casa_core.study.settings.StudySettings.from_config`).
        """
        from casa_core.study.settings import StudySettings

        session, study = config["session"], StudySettings.from_config(config)
        return cls(
            max_duration=float(session["max_duration"]),
            countdown=int(session["countdown"]),
            preview=float(session["preview"]),
            demonstrations=study.demonstrations,
            demonstrations_when=study.demonstrations_when,
            epsilon=study.epsilon,
            seed=study.seed,
            learning_iterations=session["learning_iterations"],
            inference=study.inference,
            input=session["input"],
            deadzone=float(session["deadzone"]),
        )


class SessionRecord:
    """A participant's folder: what is recorded, the steps left, and the writers.

    Parameters
    ----------
    folder : path
        ``OUT/<participant>``; created when the first file is written.
    participant : str
        The id written to every log; ends in the participant's number.
    settings : SessionSettings
    """

    def __init__(self, folder: Path | str, participant: str, settings: SessionSettings):
        self.folder = Path(folder)
        self.participant = participant
        self.index = participant_index(participant)
        self.settings = settings

    # -- where things are --------------------------------------------------------------
    @property
    def state_folder(self) -> Path:
        return self.folder / SESSION_FOLDER

    @property
    def library(self) -> Path:
        """The learned intents' library (hidden: not part of the dataset's logs)."""
        return self.state_folder / "library"

    @property
    def surveys_path(self) -> Path:
        return self.folder / SURVEYS_NAME

    def stem(self, spec: TrialSpec) -> Path:
        return self.folder / spec.stem

    # -- what is recorded --------------------------------------------------------------
    def trial_recorded(self, spec: TrialSpec) -> bool:
        """Both files of the trial's log are on disk."""
        stem = self.stem(spec)
        return stem.with_suffix(".json").is_file() and stem.with_suffix(".csv").is_file()

    def answers(self) -> pd.DataFrame:
        """The participant's recorded Likert answers (empty without a surveys file)."""
        if not self.surveys_path.is_file():
            return pd.DataFrame(columns=[*SURVEY_COLUMNS, "source"])
        return read_surveys(self.surveys_path)

    def answered(self, spec: TrialSpec) -> bool:
        """Every question of the trial's condition is answered."""
        answers = self.answers()
        mine = answers[
            (answers["task"] == spec.task)
            & (answers["method"] == spec.method)
            & (answers["phase"] == spec.phase)
        ]
        return set(QUESTIONS) <= set(mine["question"])

    def detected(self, task: str) -> bool:
        """Whether CASA flagged misspecification in the task's recorded trial before learning."""
        spec = TrialSpec(task, "CASA", "before_learning")
        if not self.trial_recorded(spec):
            return False
        _, frame = read_trial(self.stem(spec))
        return protocol.misspecification_detected(frame, self.settings.epsilon)

    def demonstration_tasks(self) -> list[str]:
        """The unknown tasks demonstrated (and learned), as the config's protocol says."""
        if self.settings.demonstrations == 0:
            return []
        flags = {task: self.detected(task) for task in UNKNOWN_TASKS}
        return protocol.demonstration_tasks(self.settings.demonstrations_when, flags)

    def intent_file(self, task: str) -> Path:
        return self.library / f"{LEARNED_NAMES[task]}{INTENT_SUFFIX}"

    def learned_files(self) -> list[Path]:
        """The learned intents on disk, in the tasks' order."""
        return [self.intent_file(t) for t in UNKNOWN_TASKS if self.intent_file(t).is_file()]

    # -- the plan ----------------------------------------------------------------------
    def steps(self) -> list[Step]:
        """Every step of the session, given what the recorded trials decided."""
        steps = []

        def add(spec: TrialSpec) -> None:
            steps.append(Step("trial", spec))
            if spec.phase in SINGLE_TRIAL_PHASES:
                steps.append(Step("questions", spec))

        for spec in protocol.before_learning(self.index):
            add(spec)
        tasks = self.demonstration_tasks()
        for task in tasks:
            for spec in protocol.demonstrations(task, self.settings.demonstrations):
                add(spec)
        if tasks:
            steps.append(Step("learning"))
            for spec in protocol.after_learning():
                add(spec)
        return steps

    def done(self, step: Step) -> bool:
        """Whether the step's output is on disk."""
        if step.kind == "trial":
            assert step.spec is not None  # trials and questions carry their spec
            return self.trial_recorded(step.spec)
        if step.kind == "questions":
            assert step.spec is not None
            return self.answered(step.spec)
        return all(self.intent_file(task).is_file() for task in self.demonstration_tasks())

    def next_step(self) -> Step | None:
        """The first step not yet recorded; None when the session is complete."""
        return next((step for step in self.steps() if not self.done(step)), None)

    # -- writers -----------------------------------------------------------------------
    def write_trial(self, spec: TrialSpec, result: TrialResult) -> Path:
        """Write a finished trial's log (each file atomically); returns its stem.

        A complete log is never overwritten; a lone half of one (the session was killed
        between its two files) is replaced.
        """
        if self.trial_recorded(spec):
            raise FileExistsError(f"{self.stem(spec)}.json exists; logs are never overwritten")
        if spec.method == "CASA" and spec.phase == "before_learning":
            found = protocol.misspecification_detected(result.frame, self.settings.epsilon)
            note = f"misspecification detected: {found}"
            result.meta["notes"] = "; ".join(filter(None, [result.meta.get("notes"), note]))
        result.write(self.stem(spec))
        return self.stem(spec)

    def write_answers(self, spec: TrialSpec, scores: dict[str, int]) -> None:
        """Add one condition's answers to ``surveys.csv`` (rewritten atomically)."""
        rows = [
            {
                "participant": self.participant,
                "task": spec.task,
                "method": spec.method,
                "phase": spec.phase,
                "question": question,
                "score": int(scores[question]),
                "source": "human",
            }
            for question in QUESTIONS
        ]
        old = self.answers()
        same = (
            (old["task"] == spec.task)
            & (old["method"] == spec.method)
            & (old["phase"] == spec.phase)
        )
        frame = pd.concat([old[~same], pd.DataFrame(rows)], ignore_index=True)
        write_surveys(self.surveys_path, frame[[*SURVEY_COLUMNS, "source"]])

    def learn(
        self, task: str, scene: Scene, *, progress: Callable[[int, int], None] | None = None
    ) -> tuple[Path, float]:
        """Learn the task's intent from the recorded demonstrations; the file and seconds.

        The seed is the simulated study's for this participant (``simulation.seed`` +
        index).
        """
        from dataclasses import replace

        from casa_core.learning import IRLConfig
        from casa_core.study.learn_from_logs import learn_to_library
        from casa_core.study.learning_evidence import scene_objects

        config = IRLConfig()
        if self.settings.learning_iterations is not None:
            most = self.settings.learning_iterations
            config = replace(
                config, max_iterations=most, min_iterations=min(config.min_iterations, most)
            )
        path, _history, seconds = learn_to_library(
            self.folder,
            LEARNED_NAMES[task],
            library=self.library,
            objects=scene_objects(scene),
            seed=self.settings.seed + self.index,
            task=task,
            participant=self.participant,
            config=config,
            progress=progress,
        )
        return path, seconds


def method_order_line(participant: str) -> str:
    """The session log's line on the counterbalancing (it names the methods).

    Examples
    --------
    >>> print(method_order_line("P07"))
    method order: participant P07 is number 7 (0-based index 6), order 6 mod 6 = 0 of the \
simulated study's: NA, PBA, CASA; shown as robot A = NA, robot B = PBA, robot C = CASA, \
CASA after learning = robot D
    """
    index = participant_index(participant)
    order = protocol.method_order(index)
    labels = ", ".join(f"{label} = {method}" for method, label in robot_labels(index).items())
    count = len(protocol.METHOD_ORDERS)
    return (
        f"method order: participant {participant} is number {index + 1} (0-based index "
        f"{index}), order {index} mod {count} = {index % count} of the simulated study's: "
        f"{', '.join(order)}; shown as {labels}, CASA after learning = {AFTER_LEARNING_LABEL}"
    )
