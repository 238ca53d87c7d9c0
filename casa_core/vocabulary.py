"""The study's vocabulary: tasks, methods, phases, conditions, keys and Likert questions.

Every other module (logs, statistics, figures, the protocol, the command line and the
workflow's rules) takes these names from here, so that each is defined once. Names are
the ones written in trial logs (``casa-trial/1``, see ``docs/data-contracts.md``);
``*_LABELS`` give the paper's words for display.

Examples
--------
>>> condition_of("CASA", "after_learning")
'CASA after learning'
>>> condition_of("NA", "demonstration") is None
True
"""

from __future__ import annotations

#: The simulated operator's optional parameters of intermittent control, in the order a
#: participant draws them (config ``simulation.population``, population files).
INTERMITTENT_PARAMETERS = ("bout", "pause", "planning")
#: The study's tasks, in the order the protocol runs them (paper, Sec. V-A).
TASKS = ("familiarization", "known_goal", "unknown_goal", "unknown_skill")
#: The well-specified task: its goal is one of the robot's known intents.
KNOWN_TASK = "known_goal"
#: The misspecified tasks: the robot learns their intents from demonstrations.
UNKNOWN_TASKS = ("unknown_goal", "unknown_skill")
#: The paper's names of the tasks.
TASK_LABELS = {
    "familiarization": "Familiarization",
    "known_goal": "Known Goal",
    "unknown_goal": "Unknown Goal",
    "unknown_skill": "Unknown Skill",
}

#: Assistance methods: direct teleoperation, policy blending, confidence-aware.
METHODS = ("NA", "PBA", "CASA")

#: The protocol's phases, in order.
PHASES = (
    "familiarization",
    "no_misspecification",
    "before_learning",
    "demonstration",
    "after_learning",
)
#: The phases each task is run in: the unknown tasks go through learning.
TASK_PHASES = {
    "familiarization": ("familiarization",),
    "known_goal": ("no_misspecification",),
    "unknown_goal": ("before_learning", "demonstration", "after_learning"),
    "unknown_skill": ("before_learning", "demonstration", "after_learning"),
}
#: The methods in which the robot assists.
ASSISTED_METHODS = ("PBA", "CASA")
#: Phases run with one method only: demonstrations without assistance, CASA after learning.
PHASE_METHOD = {"demonstration": "NA", "after_learning": "CASA"}
#: Phases in which a participant does each condition once (repeats would be counted twice).
SINGLE_TRIAL_PHASES = ("no_misspecification", "before_learning", "after_learning")
#: Phases whose trials are not study conditions: practice and demonstrations.
UNANALYSED_PHASES = ("familiarization", "demonstration")

#: Who produced a log.
SOURCES = ("human", "simulated")
#: Who gave a Likert answer, by the answer's source: a simulated participant's answers
#: are the output of an answer model (casa_core.study.likert), not a person's rating.
ANSWERED_BY = {"human": "participant", "simulated": "model"}

#: The eight keys of the keyboard interface: +- along x, y, z and the two rotate keys.
KEYS = ("x+", "x-", "y+", "y-", "z+", "z-", "rot+", "rot-")
#: The input devices a person drives the arm with; the keyboard is the paper's and the
#: default (a log without the metadata key ``input`` was driven by keys).
INPUTS = ("keyboard", "gamepad", "spacemouse")
#: The devices that command a velocity instead of holding keys; their logs carry it.
CONTINUOUS_INPUTS = ("gamepad", "spacemouse")

#: The paper's three 7-point Likert questions, and their display names.
QUESTIONS = ("understood", "effortless", "useful")
QUESTION_LABELS = {"understood": "Understood", "effortless": "Effortless", "useful": "Useful"}

CASA_BEFORE_LEARNING = "CASA before learning"
CASA_AFTER_LEARNING = "CASA after learning"
#: The study's conditions, in the paper's order and words. A condition is a method in a
#: phase; the protocol runs only CASA after learning, but NA or PBA after learning (a
#: lab's own design) are conditions of their own.
CONDITIONS = (
    "NA",
    "PBA",
    "CASA",
    CASA_BEFORE_LEARNING,
    CASA_AFTER_LEARNING,
    "NA after learning",
    "PBA after learning",
)
#: The conditions the protocol runs on each analysed task.
TASK_CONDITIONS = {
    "known_goal": ("NA", "PBA", "CASA"),
    "unknown_goal": ("NA", "PBA", CASA_BEFORE_LEARNING, CASA_AFTER_LEARNING),
    "unknown_skill": ("NA", "PBA", CASA_BEFORE_LEARNING, CASA_AFTER_LEARNING),
}


#: The assistant's arbitration under each method (casa_core.assist.assistant.Assistant): NA is
#: direct teleoperation, PBA distance arbitration with beta = 1, CASA confidence arbitration.
METHOD_ARBITRATION = {"NA": "none", "PBA": "distance", "CASA": "confidence"}
#: The arbitration of every method a trial can run: the logged ones and BELIEF, arbitration
#: on the belief in the most likely intent (the arbitration analysis only: not logged).
TRIAL_ARBITRATION = {**METHOD_ARBITRATION, "BELIEF": "belief"}
#: The name of the intent learned in each unknown task.
LEARNED_NAMES = {"unknown_goal": "learned_red", "unknown_skill": "learned_pour"}
#: The inference presets (casa_core.assist.presets): this project's, the original
#: implementation's, the paper's as written.
PRESET_NAMES = ("casa", "original", "paper")
#: What the original implementation computed, its defects included: a replay of imported
#: sessions, to check them against their logs (casa_core.io.original.numerics); not a
#: preset of the assistant and not for analysis.
DEFECTS_PRESET = "original_defects"
#: The presets a replay can redo: the assistant's and :data:`DEFECTS_PRESET`.
REPLAY_PRESETS = (*PRESET_NAMES, DEFECTS_PRESET)
#: What the trajectory of inference is: the user's commanded motion or the arm's executed one.
EVIDENCE = ("commanded", "executed")
#: Where inference measures the arm: the tool point (this project's end effector) or the
#: origin of link 7, 0.16 m before it (the original implementation's end effector).
POINTS = ("tool", "link7")
#: What a replay's inference steps read: a trial's recorded waypoints, or its log's ticks.
REPLAY_PATHS = ("waypoints", "ticks")
#: How the keys move the arm: ``held``, the tool point by a Cartesian velocity with the
#: tool orientation held (this project's); ``original``, link 7's target by position-only
#: inverse kinematics, the orientation following the reach (the authors' implementation).
TELEOP_MODES = ("held", "original")
#: The scene's two views (:mod:`casa_core.robot.camera`): the participant's window and the
#: scene figure.
VIEWS = ("window", "figure")


def condition_of(method: str, phase: str) -> str | None:
    """The study condition of a trial, in the paper's words; None for unanalysed phases.

    CASA before and after learning are conditions of their own; NA and PBA keep their
    names except after learning. Familiarization and demonstration trials
    (:data:`UNANALYSED_PHASES`) are not conditions.

    Parameters
    ----------
    method : {"NA", "PBA", "CASA"}
    phase : str
        One of :data:`PHASES`.

    Returns
    -------
    str or None
        One of :data:`CONDITIONS`, or None.

    Raises
    ------
    ValueError
        If ``method`` is not one of :data:`METHODS`.

    Examples
    --------
    >>> condition_of("PBA", "before_learning")
    'PBA'
    >>> condition_of("CASA", "before_learning")
    'CASA before learning'
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    if phase in UNANALYSED_PHASES:
        return None
    if method == "CASA" and phase == "before_learning":
        return CASA_BEFORE_LEARNING
    return f"{method} after learning" if phase == "after_learning" else method
