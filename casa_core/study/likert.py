"""Likert answers of simulated participants: a documented model of what they experienced.

The paper asked three 7-point questions after each condition: whether the robot
*understood* how they wanted the task done, whether it made the interaction more
*effortless*, and whether the assistance was *useful*. A simulated participant
answers from three quantities of the trial it just did, each compared with its
own direct-teleoperation (NA) trial of the same task:

- ``help``: mean robot authority 1 - alpha over the trial (0 under NA);
- ``fight``: fraction of ticks with a key held in which the arm moved more than
  45 degrees away from the direction the keys commanded: the robot pulling
  against the person;
- ``effort_gain``: 1 - relative effort (key presses / NA key presses), clipped to
  [-1, 1]; and ``error_gain``: 1 - error / NA error, clipped to [-1, 1].

Latent impressions, each in about [-1, 1]:

    understood = help - 2 fight
    effortless = effort_gain - fight
    useful     = (understood + effortless + error_gain) / 3

Score = round(4 + 3 * latent + bias + noise), clipped to 1..7, with a per-participant
``bias`` ~ N(0, 0.5) (some people rate high) and a per-answer ``noise`` ~ N(0, 0.5).
Everything built from these answers is labelled simulated.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from casa_core.analysis import metrics
from casa_core.assist.tasks import intended_trajectory
from casa_core.io import SURVEY_COLUMNS, read_trial
from casa_core.robot.keys import keys_to_action
from casa_core.scene import Scene
from casa_core.vocabulary import QUESTIONS, UNANALYSED_PHASES

FIGHT_ANGLE = np.deg2rad(45.0)


def fight_fraction(frame: pd.DataFrame) -> float:
    """Fraction of ticks with keys held where the arm moved > 45 deg off the commanded direction."""
    commanded = np.array([keys_to_action(keys.split())[:3] for keys in frame["keys"].fillna("")])
    position = frame[["x", "y", "z"]].to_numpy(dtype=float)
    moved = np.diff(position, axis=0)
    commanded = commanded[:-1]
    pressing = np.linalg.norm(commanded, axis=1) > 0
    if not pressing.any():
        return 0.0
    c, m = commanded[pressing], moved[pressing]
    norms = np.linalg.norm(c, axis=1) * np.linalg.norm(m, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = np.where(norms > 0, (c * m).sum(axis=1) / norms, 1.0)
    return float(np.mean(cosine < np.cos(FIGHT_ANGLE)))


def experience(frame: pd.DataFrame) -> dict:
    """``help`` and ``fight`` of one trial log (module docstring)."""
    alpha = frame["alpha"].to_numpy(dtype=float) if "alpha" in frame else np.ones(len(frame))
    return {"help": float(np.mean(1.0 - alpha)), "fight": fight_fraction(frame)}


def latent_impressions(help_: float, fight: float, effort_gain: float, error_gain: float) -> dict:
    """The three latent impressions in about [-1, 1] (module docstring)."""
    effort_gain = float(np.clip(effort_gain, -1, 1))
    error_gain = float(np.clip(error_gain, -1, 1))
    understood = help_ - 2.0 * fight
    effortless = effort_gain - fight
    return {
        "understood": understood,
        "effortless": effortless,
        "useful": (understood + effortless + error_gain) / 3.0,
    }


def answer(latent: dict, bias: float, rng: np.random.Generator, noise: float = 0.5) -> dict:
    """Integer scores 1..7 for the three questions."""
    return {
        question: int(
            np.clip(np.rint(4 + 3 * latent[question] + bias + noise * rng.standard_normal()), 1, 7)
        )
        for question in QUESTIONS
    }


def simulated_surveys(
    pid: str,
    folders: list[Path],
    *,
    scene: Scene,
    rng: np.random.Generator,
    logs: Mapping[Path, tuple[dict, pd.DataFrame]] | None = None,
) -> pd.DataFrame:
    """Likert answers (the model above) for every condition of one participant's logs.

    The logs are the ``.json`` + ``.csv`` pairs in ``folders``; those in ``logs`` (by the
    ``.json``'s path, as :func:`casa_core.io.write_trial` returns them) are not read again.
    """
    dt = scene.teleop.dt
    logs = logs or {}
    trials: dict[tuple[str, str, str], tuple[dict[str, Any], pd.DataFrame]] = {}
    for folder in folders:
        for json_path in sorted(Path(folder).glob("*.json")):
            meta, frame = logs.get(json_path) or read_trial(json_path.with_suffix(""))
            if meta["phase"] in UNANALYSED_PHASES:
                continue
            measured: dict[str, Any] = metrics.trial_metrics(
                frame, intended_trajectory(meta["task"], scene), dt=dt
            )
            trials[(meta["task"], meta["method"], meta["phase"])] = (measured, frame)
    bias = 0.5 * rng.standard_normal()
    rows = []
    for (task, method, phase), (measured, frame) in sorted(trials.items()):
        reference = next(
            (m for (t, me, _), (m, _f) in trials.items() if t == task and me == "NA"), measured
        )
        effort_gain = 1 - measured["effort"] / max(reference["effort"], 1)
        error_gain = 1 - measured["error"] / reference["error"] if reference["error"] > 0 else 0.0
        felt = experience(frame)
        latent = latent_impressions(felt["help"], felt["fight"], effort_gain, error_gain)
        for question, score in answer(latent, bias, rng).items():
            rows.append(
                {
                    "participant": pid,
                    "task": task,
                    "method": method,
                    "phase": phase,
                    "question": question,
                    "score": score,
                    "source": "simulated",
                }
            )
    return pd.DataFrame(rows, columns=[*SURVEY_COLUMNS, "source"])
