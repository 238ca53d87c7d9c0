"""A dataset of people's trials as `casa calibrate` reads it: who did which trial, and how.

:func:`read_people` checks a dataset folder (:func:`casa_core.io.check_paths`), keeps the
trials whose ``source`` is ``human`` and that the simulator can run again, and returns them
as a :class:`Design` (what to simulate) with the people's summaries
(:mod:`casa_core.calibration.summaries`). Left out, each with a warning naming the file: a
trial flagged as not the person's own behaviour (``no-user-command``: the robot drove), and
a trial after learning, which ran with intents learned from that person's demonstrations,
which a simulated operator does not have, and a trial driven with a continuous device
(gamepad, SpaceMouse), since the simulated operators press keys.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from casa_core.assist import tasks
from casa_core.calibration.summaries import SUMMARIES, trial_summaries
from casa_core.io import FileCheck, check_paths
from casa_core.io.contract import NOT_OWN_BEHAVIOUR, TRIAL_FLAGS
from casa_core.scene import Scene

#: The phases the simulator runs with the robot's known intents only.
SIMULATED_PHASES = ("familiarization", "no_misspecification", "before_learning", "demonstration")
#: A calibration needs at least this many usable trials.
MIN_TRIALS = 2


class CalibrationInputError(ValueError):
    """A dataset `casa calibrate` cannot fit to; the message names what is missing."""


@dataclass(frozen=True)
class PlannedTrial:
    """One trial to simulate: a person's, with the time limit it ran under."""

    participant: str
    task: str
    method: str
    phase: str
    max_duration: float


@dataclass(frozen=True)
class Design:
    """The trials of a dataset's people, in a fixed order, and the cells they fall in."""

    trials: tuple[PlannedTrial, ...]

    @property
    def participants(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(trial.participant for trial in self.trials))

    @property
    def cells(self) -> tuple[tuple[str, str], ...]:
        """The ``(task, method)`` cells present, sorted."""
        return tuple(sorted({(trial.task, trial.method) for trial in self.trials}))

    def of(self, participant: str) -> list[PlannedTrial]:
        return [trial for trial in self.trials if trial.participant == participant]


@dataclass(frozen=True)
class People:
    """What :func:`read_people` found: the design, the people's summaries, the warnings."""

    dataset: str
    design: Design
    summaries: pd.DataFrame
    warnings: tuple[str, ...]


def read_people(raw_dir: Path | str, scene: Scene, *, max_duration: float) -> People:
    """The human trials of a dataset folder that the simulator can run again.

    Parameters
    ----------
    raw_dir : path
        The dataset's folder (``casa session`` output, or ``casa import`` output); only read.
    scene : Scene
        The scene the trials ran in: their intended trajectories and control tick.
    max_duration : float
        The time limit of a trial whose log does not say its own.

    Raises
    ------
    CalibrationInputError
        When the folder has invalid logs, no human trial, or fewer than :data:`MIN_TRIALS`
        trials the simulator can run.
    """
    root = Path(raw_dir)
    name = root.resolve().name
    human = _human_logs(root)
    warnings = []
    kept, rows = [], []
    dt = scene.teleop.dt
    intended: dict = {}
    for check in sorted(human, key=lambda c: str(c.file)):
        meta, frame = check.meta, check.frame
        assert meta is not None and frame is not None
        why = _left_out(meta)
        if why is not None:
            warnings.append(f"{check.file}: left out, {why}")
            continue
        task = meta["task"]
        if task not in intended:
            intended[task] = tasks.intended_trajectory(task, scene)
        limit = meta.get("max_duration")
        kept.append(
            PlannedTrial(
                str(meta["participant"]),
                task,
                meta["method"],
                meta["phase"],
                float(limit) if limit is not None else float(max_duration),
            )
        )
        summary = trial_summaries(frame, intended[task], dt=dt)
        rows.append(
            {"participant": str(meta["participant"]), "task": task, "method": meta["method"]}
            | summary
        )
    if len(kept) < MIN_TRIALS:
        raise CalibrationInputError(
            f"dataset {str(root)!r}: {len(kept)} human trial(s) the simulator can run "
            f"(phases {', '.join(SIMULATED_PHASES)}); calibration needs at least {MIN_TRIALS}"
        )
    columns = ["participant", "task", "method", *SUMMARIES]
    return People(name, Design(tuple(kept)), pd.DataFrame(rows, columns=columns), tuple(warnings))


def _human_logs(root: Path) -> list[FileCheck]:
    """The checks of the folder's valid trial logs whose source is ``human``.

    Raises :class:`CalibrationInputError` if any file is invalid or none is human.
    """
    checks = check_paths([root])
    errors = [problem for check in checks for problem in check.errors]
    if errors:
        listed = "\n".join(f"  {problem}" for problem in errors[:10])
        raise CalibrationInputError(
            f"dataset {str(root)!r}: {len(errors)} problem(s); `casa validate` lists them all:\n"
            f"{listed}"
        )
    logs = [check for check in checks if check.kind == "trial" and check.ok]
    human = [check for check in logs if check.meta and check.meta["source"] == "human"]
    if not human:
        raise CalibrationInputError(
            f"dataset {str(root)!r}: no trial with source 'human' among its {len(logs)} "
            "trial log(s); calibration fits the operator model to people's trials"
        )
    return human


def _left_out(meta: dict) -> str | None:
    """Why the simulator cannot run a trial again like the person did, or None."""
    excluded = [flag for flag in meta.get("flags", ()) if flag in NOT_OWN_BEHAVIOUR]
    if excluded:
        return f"flagged {excluded[0]}: {TRIAL_FLAGS[excluded[0]]}"
    device = meta.get("input", "keyboard")
    if device != "keyboard":
        return (
            f"driven with a {device}: the simulated operators press keys, so their "
            "summaries would not compare with a continuous command's"
        )
    if meta["phase"] not in SIMULATED_PHASES:
        return (
            f"phase {meta['phase']!r} ran with intents learned from this person's "
            "demonstrations, which the simulator does not have"
        )
    return None
