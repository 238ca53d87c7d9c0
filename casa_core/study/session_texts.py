"""What the session's window says to the participant, in plain words.

The texts name the robots by their neutral labels only
(:func:`casa_core.study.session.label_of`): no text here may name an assistance method
(tests/study/test_session.py checks every text of every step).
"""

from __future__ import annotations

from casa_core.assist.tasks import PRACTICE_GOAL
from casa_core.study.protocol import TrialSpec

#: Where each task goes, in words (the window also highlights it).
TARGETS = {
    "familiarization": f"the {PRACTICE_GOAL} ball",
    "known_goal": "the green ball",
    "unknown_goal": "the red ball",
    "unknown_skill": "the yellow bowl",
}
#: What to do in each task.
GOALS = {
    "familiarization": f"move the cup in the robot's hand to {TARGETS['familiarization']}",
    "known_goal": f"move the cup to {TARGETS['known_goal']}",
    "unknown_goal": f"move the cup to {TARGETS['unknown_goal']}",
    "unknown_skill": "move the cup over the yellow bowl, into the blue bubble above it, then "
    "tilt the cup with A to pour into the bowl",
}
#: The paper's three questions (Sec. V-B) as statements about the robot just used.
STATEMENTS = {
    "understood": "{robot} understood how I wanted the task done.",
    "effortless": "{robot} made the task more effortless.",
    "useful": "The help {robot} gave was useful.",
}
_DONE = "Press Enter as soon as you are done."
#: The same under a fixed trial length (a scene's ``trial_length``), where Enter does not end it.
_FIXED = "The task stops by itself after {seconds:g} s: once there, wait with no key pressed."


def instructions(
    spec: TrialSpec, label: str | None, *, demonstrations: int, trial_length: float | None = None
) -> tuple[str, str]:
    """The title and the text shown before a trial; ``trial_length`` (s), if given, is
    the fixed length of every trial (the scene's), said in place of "press Enter".

    Examples
    --------
    >>> title, body = instructions(
    ...     TrialSpec("known_goal", "PBA", "no_misspecification"), "robot B", demonstrations=5
    ... )
    >>> title
    'Task: move the cup to the green ball'
    >>> body.splitlines()[0]
    'This time robot B helps you: it may move the arm too.'
    >>> spec = TrialSpec("known_goal", "NA", "no_misspecification")
    >>> instructions(spec, None, demonstrations=5, trial_length=15.0)[1].split(". ")[-1]
    'The task stops by itself after 15 s: once there, wait with no key pressed.'
    """
    goal = GOALS[spec.task]
    done = _DONE if trial_length is None else _FIXED.format(seconds=trial_length)
    where = f"The target is highlighted in yellow and marked TARGET. {done}"
    if spec.phase == "familiarization":
        return (
            "Practice",
            f"Get to know the keys: {goal}. The robot does not help in this practice.\n{where}",
        )
    if spec.phase == "demonstration":
        return (
            f"Show the robot: {spec.repeat + 1} of {demonstrations}",
            f"Do the task your own way so that the robot can learn it: {goal}. The robot does "
            f"not help while you show it.\n{where}",
        )
    help_line = f"This time {label} helps you: it may move the arm too."
    if spec.phase == "after_learning":
        help_line = (
            f"This time {label} helps you; it has learned from the times you showed the task."
        )
    return f"Task: {goal}", f"{help_line}\n{where}"


def statement(question: str, label: str) -> str:
    """The Likert statement of ``question`` about the robot ``label``.

    Examples
    --------
    >>> statement("useful", "robot A")
    'The help robot A gave was useful.'
    >>> statement("understood", "robot C")
    'Robot C understood how I wanted the task done.'
    """
    text = STATEMENTS[question].format(robot=label)
    return text[0].upper() + text[1:]


def learning_message(task_number: int, tasks: int, task: str) -> str:
    """The rest screen's text while the robot learns one task.

    Examples
    --------
    >>> learning_message(1, 2, "unknown_goal")
    'The robot is learning from the times you showed it the task (1 of 2: the red ball).'
    """
    return (
        "The robot is learning from the times you showed it the task "
        f"({task_number} of {tasks}: {TARGETS[task]})."
    )


WELCOME = (
    "Welcome",
    "You will drive a robot arm holding a cup, with the keyboard. Some robots help you "
    "by moving the arm too. Before each task you see what to do and the path to follow, "
    "then a countdown. After each task with a robot you answer three short questions.\n"
    "Press Enter to begin.",
)
GOODBYE = ("Thank you!", "The session is complete. You may call the experimenter.")
GETTING_READY = ("One moment", "The robot is getting ready for the next task.")
STOPPED = ("Stopped", "The session is stopped. Everything recorded so far is kept.")
