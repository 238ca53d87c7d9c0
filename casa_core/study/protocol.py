"""The study protocol (paper, Sec. V-A), the same for simulated and real participants.

1. familiarization: one direct-teleoperation trial of the familiarization task;
2. no misspecification: Known Goal with NA, PBA and CASA;
3. misspecification before learning: Unknown Goal, then Unknown Skill, each with
   NA, PBA and CASA; when CASA flags misspecification (every known intent's
   beta_hat below epsilon) the robot asks for demonstrations: 5 of each unknown
   task by direct teleoperation;
4. after learning: Unknown Goal and Unknown Skill with CASA and the learned intents.

The order of the three methods is counterbalanced across participants, the same for
every task: participant number i (1-based; 0-based index i - 1) uses order
``(i - 1) mod 6`` of the 6 orders of NA, PBA, CASA in :data:`METHOD_ORDERS`, counted from 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import permutations
from typing import TYPE_CHECKING

from casa_core.defaults import DEMONSTRATIONS
from casa_core.vocabulary import METHODS, UNKNOWN_TASKS

if TYPE_CHECKING:
    import pandas as pd

#: The 6 orders of the methods; the participant of 0-based index k uses the (k mod 6)-th.
METHOD_ORDERS = tuple(permutations(METHODS))
#: Seconds at the end of a CASA trial over which every beta_hat must stay below epsilon.
DETECTION_WINDOW = 3.0


@dataclass(frozen=True)
class TrialSpec:
    """One trial of the protocol; ``repeat`` numbers the demonstrations."""

    task: str
    method: str
    phase: str
    repeat: int = 0

    @property
    def stem(self) -> str:
        """File stem of the trial's log, unique within a participant."""
        suffix = f"_{self.repeat + 1}" if self.phase == "demonstration" else ""
        return f"{self.task}_{self.phase}_{self.method}{suffix}"


def method_order(participant_index: int) -> tuple[str, ...]:
    """The counterbalanced order of NA, PBA and CASA for a participant (0-based index)."""
    return METHOD_ORDERS[participant_index % len(METHOD_ORDERS)]


def before_learning(participant_index: int) -> list[TrialSpec]:
    """Phases 1-3 without the demonstrations, in the order they are run."""
    order = method_order(participant_index)
    trials = [TrialSpec("familiarization", "NA", "familiarization")]
    trials += [TrialSpec("known_goal", method, "no_misspecification") for method in order]
    for task in UNKNOWN_TASKS:
        trials += [TrialSpec(task, method, "before_learning") for method in order]
    return trials


def demonstrations(task: str, n: int = DEMONSTRATIONS) -> list[TrialSpec]:
    """The ``n`` demonstrations of an unknown task, by direct teleoperation."""
    return [TrialSpec(task, "NA", "demonstration", repeat) for repeat in range(n)]


def demonstration_tasks(when: str, detected: dict[str, bool]) -> list[str]:
    """The unknown tasks whose demonstrations are asked for, in the order they are run.

    ``when`` is ``"always"`` (the paper's protocol: every unknown task) or
    ``"detected"`` (only the tasks in which CASA flagged misspecification, ``detected``
    mapping task -> flag; a task missing from it flagged nothing).

    Examples
    --------
    >>> demonstration_tasks("always", {})
    ['unknown_goal', 'unknown_skill']
    >>> demonstration_tasks("detected", {"unknown_goal": False, "unknown_skill": True})
    ['unknown_skill']
    """
    if when not in ("always", "detected"):
        raise ValueError(f"demonstrations_when must be 'always' or 'detected', got {when!r}")
    return [task for task in UNKNOWN_TASKS if when == "always" or detected.get(task, False)]


def after_learning() -> list[TrialSpec]:
    """Phase 4: CASA with the learned intents."""
    return [TrialSpec(task, "CASA", "after_learning") for task in UNKNOWN_TASKS]


def misspecification_detected(frame: pd.DataFrame, epsilon: float) -> bool:
    """Whether every known intent's beta_hat stayed below epsilon over the trial's last seconds.

    ``frame`` is a trial log's rows (columns ``t`` and ``beta:NAME``); a trial
    without confidences (NA) detects nothing.
    """
    betas = frame[[c for c in frame.columns if c.startswith("beta:")]]
    if betas.empty:
        return False
    recent = frame["t"] >= frame["t"].iloc[-1] - DETECTION_WINDOW
    return bool((betas[recent] < epsilon).all().all())
