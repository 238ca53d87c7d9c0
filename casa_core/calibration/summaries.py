"""Summary statistics of trials: what `casa calibrate` compares between people and operators.

Each trial gives eight numbers, chosen so that each of the operator model's parameters moves
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
``hold`` (s)
    The median length of a stretch of ticks with a key held: intermittent control's bouts
    cut it short (0 if no key was held).
``gap`` (s)
    The median length of a stretch of ticks with no key held between two such stretches:
    the watch after letting go, its reaction time after a bout and its pause after any
    release (0 if there is none). The stretch before the first press is ``first_press``'s,
    and the one after the last release (waiting at the end) counts in neither.

A *cell* is a task and a method; a dataset's summary is each cell's mean of each summary,
in the order of :func:`cell_means`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from casa_core.analysis import metrics

SUMMARIES: tuple[str, ...] = ("duration", "first_press", "presses_per_s", "keys_held", "error")
SUMMARIES += ("path_length", "hold", "gap")


def held_stretches(held: np.ndarray, *, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The lengths (s) of the stretches of ticks with a key held, and of those without one
    between two of them.

    Examples
    --------
    >>> held = np.array([0, 1, 1, 0, 0, 0, 1, 0, 1, 1, 1, 0], dtype=bool)
    >>> holds, gaps = held_stretches(held, dt=0.5)
    >>> holds.tolist(), gaps.tolist()
    ([1.0, 0.5, 1.5], [1.5, 0.5])
    """
    edges = np.flatnonzero(np.diff(np.concatenate([[0], held.astype(np.int8), [0]])))
    starts, ends = edges[0::2], edges[1::2]
    return (ends - starts) * dt, (starts[1:] - ends[:-1]) * dt


def _median(values: np.ndarray) -> float:
    return float(np.median(values)) if len(values) else 0.0


def trial_summaries(frame: pd.DataFrame, intended: np.ndarray, *, dt: float) -> dict[str, float]:
    """The summaries of one trial log, in :data:`SUMMARIES` (module docstring).

    Examples
    --------
    >>> frame = pd.DataFrame({"t": [0.0, 0.5, 1.0], "x": [0.0, 0.0, 0.1], "y": 0.0,
    ...                       "z": 0.0, "rot": 0.0, "keys": ["", "x+", "x+ y+"]})
    >>> s = trial_summaries(frame, frame[["t", "x", "y", "z", "rot"]].to_numpy(), dt=0.5)
    >>> s["duration"], s["first_press"], s["presses_per_s"], s["keys_held"], s["path_length"]
    (1.0, 0.5, 2.0, 1.0, 0.1)
    >>> s["hold"], s["gap"]
    (1.0, 0.0)
    """
    measured: dict[str, Any] = metrics.trial_metrics(frame, intended, dt=dt)
    duration = float(measured["duration"])
    t = frame["t"].to_numpy(dtype=float)
    held = np.array([bool(cell.split()) for cell in frame["keys"]])
    first = float(t[held.argmax()]) if held.any() else duration
    xyz = frame[["x", "y", "z"]].to_numpy(dtype=float)
    steps = np.sqrt(np.sum(np.diff(xyz, axis=0) ** 2, axis=1))
    holds, gaps = held_stretches(held, dt=dt)
    return {
        "duration": duration,
        "first_press": first,
        "presses_per_s": float(measured["effort"]) / max(duration, dt),
        "keys_held": float(measured["effort_ticks"]) / len(t),
        "error": float(measured["error"]),
        "path_length": float(np.sum(steps)),
        "hold": _median(holds),
        "gap": _median(gaps),
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
    [2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]
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
