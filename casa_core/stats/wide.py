"""The participants' cell means as one wide table, for JASP, SPSS or R (``wide.csv``).

One row per participant and one column per task, condition and metric, named
``<task>_<condition>_<metric>`` in letters, digits and underscores (e.g.
``unknown_goal_CASA_before_learning_error``), as those programs require of a variable's
name. A cell is the participant's mean over their trials in that task and condition, the
observation every test of :mod:`casa_core.stats.study` analyses; empty where the
participant has no such trial. The columns are every condition the study runs on each
task (:data:`~casa_core.vocabulary.TASK_CONDITIONS`), so two datasets give the same header.
"""

from __future__ import annotations

import re

import pandas as pd

from casa_core.stats.study import CONDITION_ORDER, METRICS, _prepare_trials
from casa_core.vocabulary import TASK_CONDITIONS

#: What JASP, SPSS and R accept as a variable's name: a letter, then letters, digits and
#: underscores, at most 64 characters (SPSS's limit).
NAME_RULE = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")


def wide_column(task: str, condition: str, metric: str) -> str:
    """The wide table's column of one task, condition and metric.

    Examples
    --------
    >>> wide_column("unknown_skill", "CASA after learning", "relative_effort")
    'unknown_skill_CASA_after_learning_relative_effort'
    """
    name = re.sub(r"[^A-Za-z0-9]+", "_", f"{task} {condition} {metric}")
    if not NAME_RULE.fullmatch(name):
        raise ValueError(f"wide table: column {name!r} is not a name JASP, SPSS and R accept")
    return name


def wide_means(trials: pd.DataFrame) -> pd.DataFrame:
    """Each participant's cell mean of every metric, one row per participant.

    Parameters
    ----------
    trials : pandas.DataFrame
        The trials table (``participant, task, method, phase`` and the metrics present
        among ``error, efficiency, relative_effort, effort``); unanalysed phases
        (familiarization, demonstrations) are left out.

    Returns
    -------
    pandas.DataFrame
        ``participant``, then :func:`wide_column` of each task of
        :data:`~casa_core.vocabulary.TASK_CONDITIONS`, its conditions (in the order of
        stats.csv) and the metrics; rows sorted by participant.

    Examples
    --------
    >>> trials = pd.DataFrame({"participant": ["p1", "p1", "p1", "p2"],
    ...     "task": "known_goal", "method": ["NA", "NA", "CASA", "NA"],
    ...     "phase": "no_misspecification", "error": [1.0, 3.0, 0.5, 0.7]})
    >>> wide_means(trials)[["participant", "known_goal_NA_error", "known_goal_CASA_error"]]
      participant  known_goal_NA_error  known_goal_CASA_error
    0          p1                  2.0                    0.5
    1          p2                  0.7                    NaN
    """
    metrics = [m for m in METRICS if m in trials.columns]
    cells = _prepare_trials(trials, metrics)
    participants = sorted({p for m in metrics for p in cells[m]["participant"]})
    columns: dict[str, list] = {"participant": participants}
    for task, conditions in TASK_CONDITIONS.items():
        for condition in sorted(conditions, key=CONDITION_ORDER.index):
            for metric in metrics:
                frame = cells[metric]
                chosen = frame[(frame["task"] == task) & (frame["method"] == condition)]
                means = dict(zip(chosen["participant"], chosen[metric], strict=True))
                column = [float(means.get(p, float("nan"))) for p in participants]
                columns[wide_column(task, condition, metric)] = column
    return pd.DataFrame(columns)
