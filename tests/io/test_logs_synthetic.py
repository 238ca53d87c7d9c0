"""Synthetic casa-trial/1 datasets for the tests, written only through ``casa_core.io.write_trial``.

Not a participant model: each trial drives the task's intended trajectory with
the keys that produce its motion, optionally scaled in time (a slower person),
offset in space, and with a per-trial effort factor, so that the tests know the
metrics in closed form. The functions are imported by the other test files; the
tests at the bottom check the generator itself.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from casa_core.assist import tasks
from casa_core.io import SURVEY_COLUMNS, read_trial, validate_paths, write_surveys, write_trial
from casa_core.scene import load_scene
from casa_core.vocabulary import QUESTIONS

ROOT = Path(__file__).resolve().parents[2]
SCENE = load_scene()
AXES = ("x", "y", "z", "rot")

# The study protocol of the paper (Sec. V-A), familiarization left out.
CONDITIONS = (
    [("known_goal", m, "no_misspecification") for m in ("NA", "PBA", "CASA")]
    + [
        (t, m, "before_learning")
        for t in ("unknown_goal", "unknown_skill")
        for m in ("NA", "PBA", "CASA")
    ]
    + [(t, "CASA", "after_learning") for t in ("unknown_goal", "unknown_skill")]
)


def keys_of_motion(states: np.ndarray) -> list[str]:
    """The keys whose motion leads from each row of ``states`` (n, 4) to the next one."""
    keys = []
    steps = np.diff(states, axis=0, append=states[-1:])
    for step in steps:
        held = [
            f"{a}{'+' if d > 0 else '-'}" for a, d in zip(AXES, step, strict=True) if abs(d) > 1e-12
        ]
        keys.append(" ".join(held))
    return keys


def trial_frame(
    task: str,
    *,
    offset=(0.0, 0.0, 0.0, 0.0),
    slowdown: int = 1,
    intents: tuple[str, ...] = (),
    lapses: float = 0.0,
    rng: np.random.Generator | None = None,
) -> pd.DataFrame:
    """A trial that follows ``task``'s intended trajectory.

    ``slowdown`` repeats every intended sample that many ticks (a slower
    operator); ``offset`` is added to every state; each tick's keys are dropped
    with probability ``lapses``; with ``intents`` the frame logs ``alpha`` and
    ``beta:``/``belief:`` columns drawn from ``rng``.
    """
    intended = tasks.intended_trajectory(task, SCENE)
    rng = rng if rng is not None else np.random.default_rng(0)
    states = np.repeat(intended[:, 1:], slowdown, axis=0) + np.asarray(offset, dtype=float)
    dt = SCENE.teleop.dt
    frame = pd.DataFrame(states, columns=list(AXES))
    frame.insert(0, "t", np.arange(len(states)) * dt)
    frame["keys"] = keys_of_motion(states)
    if lapses:
        # Keys released for single ticks (extra press events); the motion is left as is.
        frame.loc[rng.uniform(size=len(frame)) < lapses, "keys"] = ""
    if intents:
        frame["alpha"] = rng.uniform(0, 1, len(frame))
        belief = rng.dirichlet(np.ones(len(intents)), len(frame))
        for j, name in enumerate(intents):
            frame[f"beta:{name}"] = rng.exponential(1.0, len(frame))
            frame[f"belief:{name}"] = belief[:, j]
    return frame


def write_dataset(
    folder: Path,
    participants=("p01", "p02"),
    *,
    seed: int = 0,
    surveys: bool = True,
    conditions=CONDITIONS,
) -> list[Path]:
    """Write a small study below ``folder``; return the trial stems written."""
    rng = np.random.default_rng(seed)
    stems = []
    for participant in participants:
        for task, method, phase in conditions:
            stem = folder / participant / f"{task}_{method}_{phase}"
            intents = ("green", "purple") if method != "NA" else ()
            meta = {
                "participant": participant,
                "task": task,
                "method": method,
                "phase": phase,
                "source": "simulated",
                "intents": list(intents),
                "seed": seed,
            }
            slowdown = 2 if method == "NA" else 1
            # Trials differ (an offset, a few lapses) so that statistics have variance.
            offset = [*rng.normal(0.0, 0.01, 3), 0.0]
            frame = trial_frame(
                task, offset=offset, slowdown=slowdown, intents=intents, lapses=0.05, rng=rng
            )
            write_trial(stem, meta, frame)
            stems.append(stem)
    if surveys:
        rows = [
            (p, task, method, phase, question, int(rng.integers(1, 8)))
            for p in participants
            for task, method, phase in conditions
            for question in QUESTIONS
        ]
        answers = pd.DataFrame(rows, columns=list(SURVEY_COLUMNS))
        write_surveys(folder / "surveys.csv", answers)
    return stems


def test_synthetic_dataset_is_valid_and_keys_reproduce_the_motion(tmp_path):
    stems = write_dataset(tmp_path / "ds", participants=("p01",))
    assert validate_paths([tmp_path / "ds"]) == []
    # Keys and motion agree: each axis moves at most one teleoperation step per tick.
    _, frame = read_trial(stems[0])
    step = np.abs(np.diff(frame[["x", "y", "z"]].to_numpy(), axis=0)).max()
    assert step <= SCENE.teleop.speed * SCENE.teleop.dt + 1e-12
