"""What stats.md opens with: where the data come from, how many participants, and the
mean +- SD of every metric per task and condition (from the trials table).

The SD is across participants of their cell means (several trials of one participant in
one condition are averaged first, as for every test in :mod:`casa_core.stats.study`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.io.contract import CONDITION_KEYS
from casa_core.io.tables import require_columns
from casa_core.stats.study import CONDITION_ORDER, METRICS, _prepare_trials
from casa_core.vocabulary import TASK_LABELS

DESCRIPTIVE_COLUMNS = ["task", "condition", "metric", "mean", "sd", "n"]


def descriptives(trials: pd.DataFrame) -> pd.DataFrame:
    """Mean, SD and number of participants per task, condition and metric.

    Parameters
    ----------
    trials : pandas.DataFrame
        The trials table (``participant, task, method, phase`` and the metrics present
        among ``error, efficiency, relative_effort, effort``).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`DESCRIPTIVE_COLUMNS`; ``sd`` is the sample SD (ddof 1) of the
        participants' cell means, NaN for one participant.

    Examples
    --------
    >>> trials = pd.DataFrame({"participant": ["p1", "p2", "p1", "p2"],
    ...     "task": "known_goal", "method": ["NA", "NA", "CASA", "CASA"],
    ...     "phase": "no_misspecification", "error": [1.0, 3.0, 0.5, 0.7]})
    >>> descriptives(trials)[["condition", "mean", "sd", "n"]].round(3)
      condition  mean     sd  n
    0      CASA   0.6  0.141  2
    1        NA   2.0  1.414  2
    """
    metrics = [m for m in METRICS if m in trials.columns]
    rows = []
    for metric, cells in _prepare_trials(trials, metrics).items():
        if metric not in metrics:
            continue  # a derived scale (log effort), not a measure
        grouped = cells.groupby(["task", "method"], observed=True)[metric]
        for (task, condition), values in grouped:
            rows.append(
                {
                    "task": task,
                    "condition": condition,
                    "metric": metric,
                    "mean": float(values.mean()),
                    "sd": float(values.std(ddof=1)) if len(values) > 1 else np.nan,
                    "n": int(values.count()),
                }
            )
    table = pd.DataFrame(rows, columns=DESCRIPTIVE_COLUMNS)
    order = {c: i for i, c in enumerate(CONDITION_ORDER)}
    table["_order"] = table["condition"].map(order)
    return (
        table.sort_values(["task", "_order"], kind="stable")
        .drop(columns="_order")
        .reset_index(drop=True)
    )


def _cell(mean: float, sd: float) -> str:
    return (
        "n/a"
        if not np.isfinite(mean)
        else f"{mean:.3g} ± {sd:.2g}"
        if np.isfinite(sd)
        else (f"{mean:.3g}")
    )


def data_lines(trials: pd.DataFrame) -> list[str]:
    """The opening of stats.md: the data's source and size, then the means +- SD table.

    Examples
    --------
    >>> trials = pd.DataFrame({"participant": ["p1", "p2"], "task": "known_goal",
    ...     "method": "NA", "phase": "no_misspecification", "error": [1.0, 3.0],
    ...     "source": "simulated"})
    >>> print("\\n".join(data_lines(trials)[:3]))
    ## Data
    <BLANKLINE>
    The data are simulated (source: simulated): 2 simulated participants. ...
    """
    require_columns(trials, CONDITION_KEYS, "trials table")
    n = trials["participant"].astype(str).nunique()
    sources = sorted(set(trials["source"].dropna().astype(str))) if "source" in trials else []
    if sources == ["simulated"]:
        origin = (
            f"The data are simulated (source: simulated): {n} simulated participants. "
            "The tests describe the simulation model, not people."
        )
    elif "simulated" in sources:
        origin = f"The data are partly simulated (sources: {', '.join(sources)}): {n} participants."
    else:
        known = f" (source: {', '.join(sources)})" if sources else ""
        origin = f"{n} participants{known}."
    table = descriptives(trials)
    metrics = [m for m in METRICS if m in set(table["metric"])]
    lines = ["## Data", "", origin + " Verdicts per hypothesis: [results.md](results.md).", ""]
    lines += [
        "Mean ± SD across participants per task and condition (n participants):",
        "",
        "| Task | Condition | n | " + " | ".join(metrics) + " |",
        "| --- | --- | --- |" + " --- |" * len(metrics),
    ]
    wide = table.set_index(["task", "condition", "metric"])
    for (task, condition), part in table.groupby(["task", "condition"], sort=False):
        cells = []
        for metric in metrics:
            key = (task, condition, metric)
            cells.append(
                _cell(wide.loc[key, "mean"], wide.loc[key, "sd"]) if key in wide.index else "n/a"
            )
        label = TASK_LABELS.get(task, task)
        lines.append(
            f"| {label} | {condition} | {int(part['n'].max())} | " + " | ".join(cells) + " |"
        )
    return lines + [""]


def left_out(validation: pd.DataFrame | None, where: str) -> str:
    """A sentence on the trials a build left out (``allow_invalid``), else "".

    ``validation`` is the dataset's validation table (``validation.csv``: one row per
    problem, ``status`` ``excluded`` for a file or line left out), ``where`` the path
    the sentence names for the list.

    Examples
    --------
    >>> validation = pd.DataFrame({"file": ["p1/a.csv", "p1/a.csv", "p1/b.csv"],
    ...     "kind": "trial", "status": ["excluded", "excluded", "ok"]})
    >>> print(left_out(validation, "lab/validation.csv").replace("; ", ";\\n"))
    Left out: 1 trial log that breaks the data contract, excluded with allow_invalid=true;
    the list, with each problem, is in lab/validation.csv (status excluded).
    >>> left_out(validation.assign(status="ok"), "validation.csv")
    ''
    """
    if validation is None or validation.empty:
        return ""
    require_columns(validation, ["file", "kind", "status"], "validation table")
    excluded = validation[validation["status"].astype(str) == "excluded"]
    trials = excluded.loc[excluded["kind"].astype(str) == "trial", "file"].nunique()
    surveys = int((excluded["kind"].astype(str) == "surveys").sum())
    said = [f"{trials} trial log{'s' * (trials != 1)}"] if trials else []
    if surveys:
        said.append(f"the lines of {surveys} problem{'s' * (surveys != 1)} in surveys.csv")
    if not said:
        return ""
    breaks = "break" if trials + surveys > 1 else "breaks"
    return (
        f"Left out: {' and '.join(said)} that {breaks} the data contract, excluded with "
        f"allow_invalid=true; the list, with each problem, is in {where} (status excluded)."
    )


__all__ = ["DESCRIPTIVE_COLUMNS", "data_lines", "descriptives", "left_out"]
