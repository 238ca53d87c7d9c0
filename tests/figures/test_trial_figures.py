"""The figures of one trial: the replay (replayed alpha over the logged one) and the
trial's path over its task's intended path.

Each figure is built from small tables written here and its lines are read back: the
expected values are the tables' own (what was logged is what is drawn) or, for the
distance panel, the closed form of a straight reference at constant speed.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.figures import style
from casa_core.figures.path import INTENDED_LABEL, path_figure
from casa_core.figures.path import LOGGED_LABEL as LOGGED_PATH
from casa_core.figures.replay import LOGGED_LABEL, REPLAYED_LABEL, replay_figure
from tests.figures.test_figures import texts

#: Two inference steps of two intents: alpha 1 at 0.5 s, 0.4 at 1 s.
REPLAYED = pd.DataFrame(
    {
        "t": [0.5, 0.5, 1.0, 1.0],
        "intent": ["green", "purple"] * 2,
        "beta": [1.0, 0.5, 2.5, 0.4],
        "belief": [0.6, 0.4, 0.9, 0.1],
        "alpha": [1.0, 1.0, 0.4, 0.4],
    }
)
#: A log of 25 ticks (0.05 s) whose alpha drops from 1 to 0.4 at 1 s and to 0.3 at 1.1 s.
TICKS = np.round(np.arange(25) * 0.05, 6)
LOG = pd.DataFrame({"t": TICKS, "alpha": np.where(TICKS < 1.0, 1.0, 0.4)})
LOG.loc[LOG["t"] >= 1.1, "alpha"] = 0.3


def line(ax, label):
    (found,) = [drawn for drawn in ax.lines if drawn.get_label() == label]
    return found


def test_the_replay_figure_draws_the_logged_alpha_under_the_replayed_one():
    fig = replay_figure(REPLAYED, logged=LOG, title="p01/trial", source="simulated")
    alpha_ax = fig.axes[2]
    logged, replayed = line(alpha_ax, LOGGED_LABEL), line(alpha_ax, REPLAYED_LABEL)
    # The logged line is the log's alpha, tick by tick, as logged.
    np.testing.assert_array_equal(logged.get_xdata(), LOG["t"])
    np.testing.assert_array_equal(logged.get_ydata(), LOG["alpha"])
    # The replayed line is one value per step, held to the next step as the arm holds it.
    np.testing.assert_array_equal(replayed.get_xdata(), [0.5, 1.0])
    np.testing.assert_array_equal(replayed.get_ydata(), [1.0, 0.4])
    assert replayed.get_drawstyle() == "steps-post"
    # Both are in the legend, and the caption names both and says who the participant is.
    legend = [text.get_text() for text in fig.legends[0].get_texts()]
    assert LOGGED_LABEL in legend and REPLAYED_LABEL in legend
    words = texts(fig)
    assert "the alpha the log holds at each control tick" in words
    assert style.SIMULATED_MODEL_NOTE in words


def test_without_a_log_the_replay_figure_draws_the_replayed_alpha_alone():
    fig = replay_figure(REPLAYED)
    assert len(fig.axes[2].lines) == 1
    assert "the log holds" not in texts(fig)
    assert style.SIMULATED_MODEL_NOTE not in texts(fig)


def test_a_log_without_alpha_is_an_error_naming_it():
    with pytest.raises(ValueError, match="trial log.*alpha"):
        replay_figure(REPLAYED, logged=LOG.drop(columns="alpha"))


#: The intended path: 0.1 m along x in 1 s from (0.4, 0, 0.3), then waiting there.
INTENDED = pd.DataFrame(
    {"t": [0.0, 1.0], "x": [0.4, 0.5], "y": [0.0, 0.0], "z": [0.3, 0.3], "rot": [0.0, 0.0]}
)


def _logged_path() -> pd.DataFrame:
    """A trial that goes up 0.1 m in z instead, in 1.5 s, turning the cup."""
    t = np.round(np.arange(31) * 0.05, 6)
    up = np.minimum(t / 1.5, 1.0) * 0.1
    return pd.DataFrame({"t": t, "x": 0.4, "y": 0.0, "z": 0.3 + up, "rot": t})


def test_the_path_figure_plots_the_logged_path_over_the_intended_one():
    logged = _logged_path()
    fig = path_figure(logged, INTENDED, method="CASA", title="p01/trial", source="simulated")
    top, side, rot, gap = fig.axes
    assert [ax.get_title() for ax in fig.axes] == [
        "Top view",
        "Side view",
        "Cup rotation",
        "Distance to the intended path",
    ]
    for ax, up in ((top, "y"), (side, "z")):
        drawn = line(ax, LOGGED_PATH)
        np.testing.assert_array_equal(drawn.get_xdata(), logged["x"])
        np.testing.assert_array_equal(drawn.get_ydata(), logged[up])
        reference = line(ax, INTENDED_LABEL)
        np.testing.assert_array_equal(reference.get_xdata(), INTENDED["x"])
        np.testing.assert_array_equal(reference.get_ydata(), INTENDED[up])
    np.testing.assert_array_equal(rot.lines[1].get_ydata(), logged["rot"])
    assert line(side, LOGGED_PATH).get_color() == style.METHOD_COLOURS["CASA"]
    # Distance at t to the intended position at t: the reference is 0.1 t along x until
    # 1 s, then 0.1; the log 0.1 t / 1.5 up in z until 1.5 s, then 0.1.
    t = logged["t"].to_numpy()
    expected = np.hypot(np.minimum(t, 1.0) * 0.1, np.minimum(t / 1.5, 1.0) * 0.1)
    np.testing.assert_allclose(gap.lines[0].get_ydata(), expected, rtol=0, atol=1e-12)
    words = texts(fig)
    assert "Dashed: the task's intended path, the reference of the error metric" in words
    assert style.SIMULATED_MODEL_NOTE in words


def test_a_path_table_without_a_column_is_an_error_naming_it():
    with pytest.raises(ValueError, match="intended path.*rot"):
        path_figure(_logged_path(), INTENDED.drop(columns="rot"))


def test_an_empty_log_gives_the_panels_with_a_note():
    fig = path_figure(_logged_path().iloc[:0], INTENDED)
    assert len(fig.axes) == 4
    assert "no logged tick" in texts(fig)
