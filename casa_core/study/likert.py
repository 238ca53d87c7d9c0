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

import numpy as np
import pandas as pd

from casa_core.robot.keys import keys_to_action
from casa_core.vocabulary import QUESTIONS

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
