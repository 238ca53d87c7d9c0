"""One style for every figure: colours, condition names, labels and saving.

Methods get the colour-blind-safe Okabe-Ito palette (Okabe and Ito, 2008); the
paper's goals keep their colours (green, purple, red). Every figure is built by
a function that takes processed tables and returns a :class:`matplotlib.figure.Figure`;
:func:`save_figure` writes it as vector PDF plus 200 dpi PNG, atomically.
"""

from __future__ import annotations

import itertools
import os
import textwrap
from collections.abc import Iterable, Sequence
from pathlib import Path

import matplotlib as mpl
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from casa_core.io.atomic import atomic_path
from casa_core.vocabulary import KNOWN_TASK, UNKNOWN_TASKS, condition_of

#: Resolution of the PNG copies.
PNG_DPI = 200

#: Okabe-Ito colours for the conditions (colour-blind safe; the CASA family in blues/green).
METHOD_COLOURS: dict[str, str] = {
    "NA": "#999999",  # grey: no assistance
    "PBA": "#E69F00",  # orange
    "CASA": "#0072B2",  # blue
    "CASA before learning": "#56B4E9",  # sky blue
    "CASA after learning": "#009E73",  # bluish green
    "NA after learning": "#000000",  # black
    "PBA after learning": "#D55E00",  # vermillion
}

#: The tasks the figures show, in the paper's order: those run in the study's conditions
#: (familiarization is practice). Their names are :data:`casa_core.vocabulary.TASK_LABELS`.
SHOWN_TASKS: tuple[str, ...] = (KNOWN_TASK, *UNKNOWN_TASKS)

#: The goals' colours in the paper's scene figure; learned or other intents fall back
#: to :data:`OTHER_INTENT_COLOURS` in name order.
GOAL_COLOURS: dict[str, str] = {"green": "#1A9E3F", "purple": "#7B3294", "red": "#D7191C"}
OTHER_INTENT_COLOURS: tuple[str, ...] = ("#A6611A", "#000000", "#0072B2", "#E69F00")

SIMULATED_NOTE = "simulated participants"
#: A caption's sentence on data of simulated participants (:func:`model_note`).
SIMULATED_MODEL_NOTE = (
    "The participant is simulated: a model of a person's teleoperation, not a person."
)

#: What the figures call a participant of the tables by its name: the case study's
#: ``expert`` is not a person but a simulated operator with expert settings that holds
#: the keys along each task's intended path.
PARTICIPANT_NAMES: dict[str, str] = {"expert": "scripted expert (waypoint follower)"}


def display_name(name: str) -> str:
    """The words a figure shows for an intent or participant named ``name`` in the tables.

    Underscores become spaces; a goal's colour names the goal (``"green"`` is the
    "green goal", a learned ``"learned_red"`` the "learned red goal"); names of
    :data:`PARTICIPANT_NAMES` take their description; any other name (a condition such
    as "CASA before learning") is kept.

    Examples
    --------
    >>> [display_name(n) for n in ("green", "learned_red", "learned_pour", "CASA")]
    ['green goal', 'learned red goal', 'learned pour', 'CASA']
    >>> display_name("expert")
    'scripted expert (waypoint follower)'
    """
    name = str(name)
    if name in PARTICIPANT_NAMES:
        return PARTICIPANT_NAMES[name]
    words = name.replace("_", " ").split()
    if words and words[-1].lower() in GOAL_COLOURS:
        words.append("goal")
    return " ".join(words) or name


def row_condition(method: str, phase: str) -> str:
    """The condition a figure labels a row with: the paper's, else the method's name.

    Examples
    --------
    >>> row_condition("CASA", "before_learning"), row_condition("NA", "familiarization")
    ('CASA before learning', 'NA')
    """
    return condition_of(method, phase) or method


def label_conditions(rows: pd.DataFrame, table: str) -> pd.DataFrame:
    """``rows`` with a ``condition`` column, the paper's name of each row's condition.

    The name is :func:`casa_core.vocabulary.condition_of`; phases the study does not
    analyse (familiarization, demonstrations) keep the method's name. An unknown method
    is an error naming the row.
    """
    conditions = []
    for index, row in rows.iterrows():
        try:
            conditions.append(row_condition(str(row["method"]), str(row["phase"])))
        except ValueError as error:
            raise ValueError(f"{table} row {index}: {error}") from None
    rows["condition"] = conditions
    return rows


def intent_colours(names: Iterable[str]) -> dict[str, str]:
    """Colour of each intent: the paper's goal colour if the name holds one, else a fallback.

    A name that contains ``green``, ``purple`` or ``red`` (e.g. a learned ``"red"`` or
    ``"learned_red"``) takes that goal's colour, so a goal keeps its colour before and
    after it is learned. Other names (e.g. the pouring skill) take the fallbacks in
    sorted order.
    """
    colours: dict[str, str] = {}
    fallback = itertools.cycle(OTHER_INTENT_COLOURS)
    for name in sorted(set(names)):
        match = [goal for goal in GOAL_COLOURS if goal in name.lower()]
        colours[name] = GOAL_COLOURS[match[0]] if match else next(fallback)
    return colours


def source_note(frame: pd.DataFrame) -> str:
    """Words for the data's origin: ``"simulated participants"``, ``"human participants"``...

    Uses the ``source`` column of the processed tables; a table without it says nothing.
    """
    if "source" not in frame.columns or frame.empty:
        return ""
    sources = sorted(set(frame["source"].dropna().astype(str)))
    words = {"simulated": SIMULATED_NOTE, "human": "human participants"}
    return " and ".join(words.get(s, f"{s} participants") for s in sources)


def model_note(source: str | None) -> str:
    """The caption's sentence that a simulated participant is a model; empty for others.

    Examples
    --------
    >>> model_note("simulated") == SIMULATED_MODEL_NOTE, model_note("human")
    (True, '')
    """
    return SIMULATED_MODEL_NOTE if source == "simulated" else ""


def describe(what: str, frame: pd.DataFrame) -> str:
    """First sentence of a caption: what is shown, by whom, how many (``"..., n = 11."``)."""
    who = source_note(frame) or "participants"
    n = frame["participant"].nunique() if "participant" in frame.columns else 0
    return f"{what}, {who} (n = {n})." if n else f"{what}, {who}."


#: Matplotlib settings for every figure: small serif-free fonts readable at column width,
#: no top/right spines, fonts embedded as TrueType in the PDF (editable, no Type 3).
RC: dict[str, object] = {
    "font.size": 8,
    "axes.titlesize": 9,
    "axes.labelsize": 8,
    "xtick.labelsize": 7.5,
    "ytick.labelsize": 7.5,
    "legend.fontsize": 7.5,
    "legend.frameon": False,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.linewidth": 0.7,
    "lines.linewidth": 1.4,
    "pdf.fonttype": 42,
    "savefig.pad_inches": 0.03,
}


def context():
    """A context in which to build a figure in the house style (``with style.context(): ...``)."""
    return mpl.rc_context(RC)


def new_figure(width: float, height: float) -> Figure:
    """An empty figure of ``width`` x ``height`` inches on the headless Agg canvas.

    Built without :mod:`matplotlib.pyplot`, so no global figure registry fills up and
    no display is needed; call it inside :func:`context`.
    """
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def note_axes(ax, text: str) -> None:
    """Mark an empty panel with a note saying why it is empty."""
    ax.text(
        0.5,
        0.5,
        text,
        transform=ax.transAxes,
        ha="center",
        va="center",
        fontsize=7.5,
        color="0.35",
        wrap=True,
    )
    # Hide ticks without removing them: the axes may share its y axis with others.
    ax.tick_params(left=False, labelleft=False, bottom=False, labelbottom=False)
    for spine in ax.spines.values():
        spine.set_visible(False)


def setup_line(setup: str | None) -> str:
    """The caption's line naming the setup the data come from; empty without one.

    Examples
    --------
    >>> setup_line("scene scene.yaml (teleop held)"), setup_line(None)
    ('Setup: scene scene.yaml (teleop held).', '')
    """
    return f"Setup: {setup}." if setup else ""


def add_caption(fig: Figure, text: str, last_line: str = "") -> None:
    """A one-line caption at the bottom of the figure (data origin and notes).

    ``last_line`` (e.g. the configuration that built the figure) is written on a line of
    its own under the caption.
    """
    if text:
        # About 20 characters of 7-pt text per inch of figure width.
        wrapped = textwrap.fill(text, width=int(20 * fig.get_figwidth()))
        if last_line:
            wrapped += "\n" + textwrap.fill(last_line, width=int(20 * fig.get_figwidth()))
        # Just below the figure (the saved bounding box grows to hold it), clear of a
        # legend placed at the bottom edge.
        fig.text(0.5, -0.02, wrapped, ha="center", va="top", fontsize=7, color="0.25")


def add_setup_caption(fig: Figure, text: str, setup: str | None) -> None:
    """The caption of a figure drawn from the study's tables: ``text``, then the line
    naming the ``setup`` the data come from (:func:`setup_line`; none without one)."""
    add_caption(fig, text, setup_line(setup))


def _atomic_savefig(fig: Figure, path: Path, **kwargs) -> None:
    """Write ``fig`` to ``path`` atomically (:func:`casa_core.io.atomic.atomic_path`)."""
    with atomic_path(path) as tmp, context():
        fig.savefig(tmp, format=path.suffix.lstrip("."), bbox_inches="tight", **kwargs)


def save_figure(fig: Figure, prefix: str | os.PathLike, formats: Sequence[str] = ("pdf", "png")):
    """Write ``fig`` as ``<prefix>.pdf`` (vector) and ``<prefix>.png`` (200 dpi), atomically.

    Parameters
    ----------
    fig : Figure
        The figure to write.
    prefix : path-like
        Output path without suffix; a given ``.pdf`` or ``.png`` suffix is dropped.
    formats : sequence of str
        Which files to write, among ``"pdf"`` and ``"png"``.

    Returns
    -------
    list of Path
        The files written.
    """
    prefix = Path(prefix)
    if prefix.suffix.lower() in (".pdf", ".png"):
        prefix = prefix.with_suffix("")
    written = []
    for fmt in formats:
        if fmt not in ("pdf", "png"):
            raise ValueError(f"unknown figure format {fmt!r}; expected 'pdf' or 'png'")
        path = prefix.with_name(f"{prefix.name}.{fmt}")
        if fmt == "png":
            _atomic_savefig(fig, path, dpi=PNG_DPI)
        else:
            # No creation date: the same tables give the same bytes, run after run.
            _atomic_savefig(fig, path, metadata={"CreationDate": None})
        written.append(path)
    return written
