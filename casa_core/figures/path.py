"""A trial's path against its intended path (``casa replay``, beside the replay figure).

Four panels: the end effector's logged path seen from above (x, y) and from the side
(x, z), each over the task's intended path; the cup's rotation over time against the
intended one; and the distance at each logged tick to where the intended path is at that
time, the quantity whose squares the error metric sums. It takes two tables of
``t, x, y, z, rot`` (the trial's log and the intended path), so it knows nothing of the
robot or the scene: the caller computes the intended path
(:func:`casa_core.assist.tasks.intended_trajectory`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from casa_core.figures import style
from casa_core.io import tables
from casa_core.io.contract import FRAME_REQUIRED

#: The columns the figure reads of both tables: a log's time and pose.
COLUMNS = [name for name in FRAME_REQUIRED if name != "keys"]
#: The legend's words of the two paths.
LOGGED_LABEL, INTENDED_LABEL = "logged path", "intended path"
#: The panels' titles, in order.
TITLES = ("Top view", "Side view", "Cup rotation", "Distance to the intended path")


def path_figure(
    logged: pd.DataFrame,
    intended: pd.DataFrame,
    *,
    method: str | None = None,
    title: str | None = None,
    source: str | None = None,
) -> Figure:
    """Draw one trial's logged path over the path its task intends.

    Parameters
    ----------
    logged : DataFrame
        The trial's log: ``t, x, y, z, rot`` per control tick (m, rad, s).
    intended : DataFrame
        The task's intended path, the same columns, from the trial's start.
    method : str, optional
        The trial's method: the logged path takes its colour.
    title : str, optional
        First words of the caption (e.g. the trial).
    source : str, optional
        The trial's ``source``; ``"simulated"`` adds :func:`.style.model_note` to the caption.

    Returns
    -------
    Figure
        Four axes (:data:`TITLES`); a log without rows gives the panels with a note.

    Examples
    --------
    >>> intended = pd.DataFrame({"t": [0.0, 1.0], "x": [0.4, 0.5], "y": 0.0, "z": 0.3,
    ...                          "rot": 0.0})
    >>> logged = intended.assign(y=[0.0, 0.02])
    >>> fig = path_figure(logged, intended, method="CASA")
    >>> [ax.get_title() for ax in fig.axes]
    ['Top view', 'Side view', 'Cup rotation', 'Distance to the intended path']
    >>> round(float(fig.axes[3].lines[0].get_ydata()[-1]), 3)  # 2 cm off at t = 1 s
    0.02
    """
    logged = _read(logged, "trial log")
    intended = _read(intended, "intended path")
    colour = style.METHOD_COLOURS.get(method or "", style.METHOD_COLOURS["CASA"])
    with style.context():
        fig = style.new_figure(6.4, 5.0)
        axes = fig.subplots(2, 2).ravel()
        for ax, name in zip(axes, TITLES, strict=True):
            ax.set_title(name)
        if logged.empty or intended.empty:
            for ax in axes:
                style.note_axes(ax, "no logged tick" if logged.empty else "no intended path")
        else:
            _views(axes[:2], logged, intended, colour)
            _over_time(axes[2:], logged, intended, colour)
            handles, labels = axes[0].get_legend_handles_labels()
            fig.legend(handles, labels, loc="outside upper center", ncols=len(labels))
        style.add_caption(fig, _caption(title, source))
    return fig


def _read(frame: pd.DataFrame, what: str) -> pd.DataFrame:
    tables.require_columns(frame, COLUMNS, what)
    return tables.numeric_columns(frame[COLUMNS].copy(), COLUMNS, what).sort_values("t")


def _views(axes, logged: pd.DataFrame, intended: pd.DataFrame, colour: str) -> None:
    """Top and side views: both paths in metres, the start and the task's end marked."""
    for ax, (across, up) in zip(axes, (("x", "y"), ("x", "z")), strict=True):
        ax.plot(intended[across], intended[up], color="0.2", ls="--", lw=1.1, label=INTENDED_LABEL)
        ax.plot(logged[across], logged[up], color=colour, label=LOGGED_LABEL)
        start, end = intended.iloc[0], intended.iloc[-1]
        ax.plot(start[across], start[up], "o", color="0.2", ms=4, label="start")
        ax.plot(end[across], end[up], "*", color="0.2", ms=8, label="task's end")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{across} (m)")
        ax.set_ylabel(f"{up} (m)")


def _over_time(axes, logged: pd.DataFrame, intended: pd.DataFrame, colour: str) -> None:
    """The rotation over time, and the distance to the intended position at the same time."""
    rot_ax, gap_ax = axes
    held = intended[["t", "rot"]]
    if logged["t"].iloc[-1] > held["t"].iloc[-1]:  # drawn waiting at its end, as it does
        held = pd.concat([held, held.iloc[-1:].assign(t=logged["t"].iloc[-1])])
    rot_ax.plot(held["t"], held["rot"], color="0.2", ls="--", lw=1.1)
    rot_ax.plot(logged["t"], logged["rot"], color=colour)
    rot_ax.set_ylabel("rot (rad)")
    t = logged["t"].to_numpy(dtype=float)
    # The intended path waits at its end once it gets there, as in the error metric.
    reference = np.column_stack(
        [np.interp(t, intended["t"], intended[axis]) for axis in ("x", "y", "z")]
    )
    gap = np.linalg.norm(logged[["x", "y", "z"]].to_numpy(dtype=float) - reference, axis=1)
    gap_ax.plot(t, gap, color=colour)
    gap_ax.set_ylim(bottom=0.0)
    gap_ax.set_ylabel("distance (m)")
    for ax in axes:
        ax.set_xlabel("Time (s)")


def _caption(title: str | None, source: str | None) -> str:
    caption = f"{title or 'A trial'}."
    caption += (
        " Solid: the end effector's path as the log holds it (its x, y, z and rot at every"
        " control tick). Dashed: the task's intended path, the reference of the error"
        " metric and the exemplary path shown before each task: straight segments from"
        " the start through the scene's via positions, if any, to the task's end (for the pour,"
        " then the cup tilted), driven at the teleoperation speed; it is not a path the"
        " robot planned. Bottom right: the distance at each logged tick to where the"
        " intended path is at that time (waiting at its end once there); the trial's"
        " error sums its square over the ticks."
    )
    note = style.model_note(source)
    return f"{caption} {note}" if note else caption
