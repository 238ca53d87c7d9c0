"""Summary statistics of trials: what `casa calibrate` compares between people and operators.

Each trial gives six numbers, chosen so that each of the operator model's parameters moves
at least one of them (docs/calibration.md, "Summaries"):

``duration`` (s)
    The trial's last tick: slow reactions and lapses lengthen it.
``first_press`` (s)
    Time of the first tick with a key held (the duration if none is): the reaction time.
``presses_per_s``
    Key presses (press events, the effort of the paper) per second: the deadband and the
    noise of perception make an operator press and let go more often.
``keys_held``
    Keys held per tick, on average: how many axes an operator drives at once.
``error`` (m)
    The trial's error, the paper's (trials.csv ``error``,
    :func:`~casa_core.analysis.metrics.trajectory_error`): the deadband sets how far an
    operator lets the arm stray.
``path_length`` (m)
    The end effector's path: wrong keys and corrections add to it.

A *cell* is a task and a method; a dataset's summary is each cell's mean of each summary,
in the order of :func:`cell_means`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from casa_core.analysis import metrics

SUMMARIES = ("duration", "first_press", "presses_per_s", "keys_held", "error", "path_length")


def trial_summaries(frame: pd.DataFrame, intended: np.ndarray, *, dt: float) -> dict[str, float]:
    """The six summaries of one trial log (module docstring).

    Examples
    --------
    >>> frame = pd.DataFrame({"t": [0.0, 0.5, 1.0], "x": [0.0, 0.0, 0.1], "y": 0.0,
    ...                       "z": 0.0, "rot": 0.0, "keys": ["", "x+", "x+ y+"]})
    >>> s = trial_summaries(frame, frame[["t", "x", "y", "z", "rot"]].to_numpy(), dt=0.5)
    >>> s["duration"], s["first_press"], s["presses_per_s"], s["keys_held"], s["path_length"]
    (1.0, 0.5, 2.0, 1.0, 0.1)
    """
    measured: dict[str, Any] = metrics.trial_metrics(frame, intended, dt=dt)
    duration = float(measured["duration"])
    t = frame["t"].to_numpy(dtype=float)
    held = np.array([bool(cell.split()) for cell in frame["keys"]])
    first = float(t[held.argmax()]) if held.any() else duration
    xyz = frame[["x", "y", "z"]].to_numpy(dtype=float)
    steps = np.sqrt(np.sum(np.diff(xyz, axis=0) ** 2, axis=1))
    return {
        "duration": duration,
        "first_press": first,
        "presses_per_s": float(measured["effort"]) / max(duration, dt),
        "keys_held": float(measured["effort_ticks"]) / len(t),
        "error": float(measured["error"]),
        "path_length": float(np.sum(steps)),
    }


def cell_means(rows: pd.DataFrame, cells: Sequence[tuple[str, str]]) -> np.ndarray:
    """Each cell's mean of each summary, cells in the order given, summaries in :data:`SUMMARIES`.

    ``rows`` has one row per trial with ``task``, ``method`` and the summaries. A cell with
    no trial gives NaN.

    Examples
    --------
    >>> rows = pd.DataFrame({"task": ["a", "a"], "method": ["NA", "NA"],
    ...                      **{name: [1.0, 3.0] for name in SUMMARIES}})
    >>> cell_means(rows, [("a", "NA")]).tolist()
    [2.0, 2.0, 2.0, 2.0, 2.0, 2.0]
    """
    out = []
    for task, method in cells:
        chosen = rows[(rows["task"] == task) & (rows["method"] == method)]
        for name in SUMMARIES:
            out.append(float(chosen[name].mean()) if len(chosen) else float("nan"))
    return np.array(out)


def summary_labels(cells: Sequence[tuple[str, str]]) -> list[tuple[str, str, str]]:
    """``(task, method, summary)`` of each entry of :func:`cell_means`, in its order."""
    return [(task, method, name) for task, method in cells for name in SUMMARIES]
