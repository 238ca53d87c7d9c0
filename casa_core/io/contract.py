"""The casa-trial/1 contract as data: names of keys, columns and files, and allowed values.

A dataset is a folder. A trial is a pair of files with the same stem anywhere below
it: ``<stem>.json`` (metadata) and ``<stem>.csv`` (one row per control tick). Likert
answers live in files named :data:`SURVEYS_NAME`. The contract is written out in
``docs/data-contracts.md``; :mod:`casa_core.io.validation` enforces it. The study's
names (tasks, methods, phases, sources, keys, questions) come from
:mod:`casa_core.vocabulary`.

Examples
--------
>>> SCHEMA
'casa-trial/1'
>>> dict(META_ENUMS)["method"]
('NA', 'PBA', 'CASA')
>>> JOINTS[0], JOINTS[-1]
('q1', 'q7')
"""

from __future__ import annotations

import math

from casa_core.defaults import TICK
from casa_core.vocabulary import (
    CONTINUOUS_INPUTS,
    INPUTS,
    KEYS,
    METHODS,
    PHASE_METHOD,
    PHASES,
    QUESTIONS,
    SINGLE_TRIAL_PHASES,
    SOURCES,
    TASK_PHASES,
    TASKS,
)

__all__ = [
    "BELIEF_SUM_TOLERANCE",
    "CASE_STEPS_COLUMNS",
    "COLUMN_RANGES",
    "COMMAND_BOUND",
    "COMMAND_COLUMNS",
    "CONTINUOUS_INPUTS",
    "INPUTS",
    "CONDITION_KEYS",
    "FRAME_OPTIONAL",
    "FRAME_REQUIRED",
    "INTENT_PREFIXES",
    "JOINTS",
    "KEYS",
    "LIKERT_SCORES",
    "META_ENUMS",
    "META_OPTIONAL",
    "TRIAL_FLAGS",
    "NOT_OWN_BEHAVIOUR",
    "NO_LOGGED_INFERENCE",
    "NO_USER_COMMAND",
    "INFERENCE_STEPS_KEYS",
    "META_REQUIRED",
    "METHODS",
    "PHASES",
    "PHASE_METHOD",
    "POSITION_BOUND",
    "QUESTIONS",
    "ROT_BOUND",
    "SCHEMA",
    "SINGLE_TRIAL_PHASES",
    "SOURCES",
    "SURVEYS_NAME",
    "INTENT_SUFFIX",
    "SURVEY_ANSWER_KEY",
    "SURVEY_COLUMNS",
    "SURVEY_ENUMS",
    "SURVEY_OPTIONAL",
    "TASKS",
    "TASK_PHASES",
    "TICK",
    "TICK_TOLERANCE",
    "TIME_RANGE",
]

#: The value of the metadata's ``schema`` key.
SCHEMA = "casa-trial/1"
#: The name of every file of Likert answers.
SURVEYS_NAME = "surveys.csv"
#: The suffix of a learned intent's file (casa-intent, casa_core.learning.library).
INTENT_SUFFIX = ".intent.json"

#: Metadata keys every trial has, and the ones it may have.
META_REQUIRED = ("schema", "participant", "task", "method", "phase", "source")
META_OPTIONAL = (
    "intents",
    "seed",
    "started_at",
    "notes",
    "max_duration",
    "inference",
    "inference_steps",
    "flags",
    "input",
)
#: The flag of a trial in which the robot drove: the user's command is zero throughout.
NO_USER_COMMAND = "no-user-command"
#: The flag of a trial whose log holds no inference result (a replay compares nothing).
NO_LOGGED_INFERENCE = "no-logged-inference"
#: The flags a trial's metadata may carry (``"flags": [...]``), each with what it says.
TRIAL_FLAGS = {
    NO_USER_COMMAND: "the user's command is zero throughout while the arm moves: the robot "
    "drove, so the trial is not a person's own behaviour (analyses of people's behaviour, "
    "such as calibrating simulated participants, leave it out)",
    NO_LOGGED_INFERENCE: "the recording holds no inference result (the original's NA and "
    "PBA sessions logged the prior on every row): the log has no belief or beta columns, "
    "its alpha is recomputed by the method's rule, and a replay has nothing to compare",
}
#: The flags that leave a trial out of analyses of people's behaviour (calibration).
NOT_OWN_BEHAVIOUR = (NO_USER_COMMAND,)
#: The keys of the metadata's ``inference_steps``, the required ones first.
INFERENCE_STEPS_KEYS = ("started", "waypoint", "waypoints", "after_trial")
#: A trial's two files: ``<stem>.json`` (its metadata) and ``<stem>.csv`` (its ticks).
TRIAL_SUFFIXES = (".json", ".csv")
#: A dataset's own scene: this file at the dataset's top level (docs/data-contracts.md).
SCENE_NAME = "scene.yaml"
#: The keys that name a participant's condition (a trial, or a survey answer's subject).
CONDITION_KEYS = ("participant", "task", "method", "phase")
#: Metadata keys whose value is one of a fixed set, in the order they are checked.
META_ENUMS = (
    ("task", TASKS),
    ("method", METHODS),
    ("phase", PHASES),
    ("source", SOURCES),
    ("input", INPUTS),
)

#: Columns every trial has: time (s), end-effector position (m), rotation (rad), keys held.
FRAME_REQUIRED = ("t", "x", "y", "z", "rot", "keys")
#: The velocity ``[vx, vy, vz, vrot]`` (m/s, rad/s) a continuous device commanded during
#: the tick: the log of a trial whose ``input`` is one of ``CONTINUOUS_INPUTS`` has these
#: columns and an empty ``keys`` column; a keyboard trial has none of them.
COMMAND_COLUMNS = ("command_x", "command_y", "command_z", "command_rot")
#: Bound of a command column (m/s or rad/s): 20 times the keys' speeds, so anything
#: beyond is a unit error, not a device's command.
COMMAND_BOUND = 10.0
#: The arbitration weight, logged by assisted trials, and a continuous device's command.
FRAME_OPTIONAL = ("alpha", *COMMAND_COLUMNS)
#: The arm's joint angles (rad).
JOINTS = tuple(f"q{i}" for i in range(1, 8))
#: Per-intent columns ``PREFIX:NAME``: the rationality ``beta`` and the ``belief``.
INTENT_PREFIXES = ("beta", "belief")
#: Bounds of the end-effector position (m): the JACO reaches about 0.9 m from its base, so
#: anything beyond 2 m is not a pose of the arm (a unit error, a corrupted cell).
POSITION_BOUND = 2.0
#: Bounds of ``rot`` (rad): the rotate keys turn 0.5 rad/s, 20 rad in a 40 s trial.
ROT_BOUND = 100.0
#: Bounds of a column (or of every column with that prefix): (low, high), both included.
COLUMN_RANGES = {
    "alpha": (0.0, 1.0),
    "belief": (0.0, 1.0),
    "beta": (0.0, math.inf),
    **dict.fromkeys(("x", "y", "z"), (-POSITION_BOUND, POSITION_BOUND)),
    "rot": (-ROT_BOUND, ROT_BOUND),
    **dict.fromkeys(COMMAND_COLUMNS, (-COMMAND_BOUND, COMMAND_BOUND)),
}
#: Bounds of ``t`` (s): a trial starts at or after 0 and lasts less than an hour.
TIME_RANGE = (0.0, 3600.0)
#: The relative tolerance on the step between two rows, around the control tick (20 Hz,
#: the scene's ``teleop.dt``).
TICK_TOLERANCE = 0.1
#: The beliefs of a row sum to 1 within this.
BELIEF_SUM_TOLERANCE = 1e-6

#: Columns of the case study's ``steps.csv``, in order: one row per tick and intent of the
#: expert's PBA and CASA trials (casa_core.study.simulate.run_case_study writes it,
#: casa_core.figures.case_study draws it).
CASE_STEPS_COLUMNS = (
    *CONDITION_KEYS,
    "t",
    "alpha",
    "intent",
    "beta",
    "belief",
    "distance",
)

#: Columns of a surveys file; ``source`` is optional.
SURVEY_COLUMNS = ("participant", "task", "method", "phase", "question", "score")
SURVEY_OPTIONAL = ("source",)
#: Survey columns whose value is one of a fixed set, in the order they are checked.
SURVEY_ENUMS = (
    ("task", TASKS),
    ("method", METHODS),
    ("phase", PHASES),
    ("question", QUESTIONS),
    ("source", SOURCES),
)
#: The 7-point Likert scale.
LIKERT_SCORES = tuple(range(1, 8))
#: A participant answers each question once per task, method and phase.
SURVEY_ANSWER_KEY = (*CONDITION_KEYS, "question")
