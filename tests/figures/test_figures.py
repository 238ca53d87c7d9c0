"""Tests of the figures: each figure is built from a small fixture table and the
figure object is inspected (panels, series, labels, values).

Expected bar heights and error bars are the closed forms mean = sum / n and standard error
= sd / sqrt(n) (sd with n - 1) of the fixture values written in each test.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PathCollection
from matplotlib.colors import to_hex
from matplotlib.patches import Rectangle

from casa_core.figures import (
    arbitration_figure,
    case_study_figure,
    likert_figure,
    objective_figure,
    save_figure,
    style,
)
from casa_core.figures.objective import parse_comparison, stars
from casa_core.vocabulary import CONDITIONS

# --------------------------------------------------------------------------- fixtures

#: Error of participants P1..P3 per (task, method, phase); other metrics derive from it.
ERRORS = {
    ("known_goal", "NA", "no_misspecification"): [1.0, 2.0, 3.0],
    ("known_goal", "PBA", "no_misspecification"): [2.0, 2.0, 5.0],
    ("known_goal", "CASA", "no_misspecification"): [0.5, 1.0, 1.5],
    ("unknown_goal", "NA", "before_learning"): [1.0, 1.0, 4.0],
    ("unknown_goal", "PBA", "before_learning"): [3.0, 4.0, 5.0],
    ("unknown_goal", "CASA", "before_learning"): [1.0, 2.0, 3.0],
    ("unknown_goal", "CASA", "after_learning"): [1.0, 1.5, 2.0],
}


#: (task, method, participant index) of the fixture's trial that ran out of time, and
#: of the trials that failed: that one and Known Goal NA P3.
TIMED_OUT = {("unknown_goal", "PBA", 2)}
FAILED = TIMED_OUT | {("known_goal", "NA", 2)}
#: Axes of the objective figure of two tasks: rows error, efficiency, effort, success;
#: columns Known Goal, Unknown Goal (matplotlib orders them row by row).
ROWS = {"error": 0, "efficiency": 1, "relative_effort": 2, "success": 3}


def panel(fig, row: str, column: int):
    return fig.axes[2 * ROWS[row] + column]


def make_trials(errors=ERRORS, source="simulated") -> pd.DataFrame:
    rows = []
    for (task, method, phase), values in errors.items():
        for i, value in enumerate(values):
            rows.append(
                {
                    "dataset": "fixture",
                    "participant": f"P{i + 1}",
                    "task": task,
                    "method": method,
                    "phase": phase,
                    "source": source,
                    "error": value,
                    "efficiency": value / 100,
                    "effort": 10 * value,
                    "effort_ticks": 10 * value,
                    "relative_effort": value / 4,
                    "duration": 20.0,
                    "timed_out": (task, method, i) in TIMED_OUT,
                    "success": (task, method, i) not in FAILED,
                }
            )
            if rows[-1]["timed_out"]:
                rows[-1]["duration"] = 40.0  # ran to a 40 s limit
    # A familiarization trial, which the figure must leave out.
    rows.append(rows[0] | {"task": "familiarization", "phase": "familiarization"})
    return pd.DataFrame(rows)


def tukey(task, metric, comparison, p) -> dict:
    return {
        "hypothesis": "H1",
        "analysis": "tukey",
        "task": task,
        "metric": metric,
        "term": "method",
        "comparison": comparison,
        "p": p,
    }


def bars(ax) -> list[Rectangle]:
    return [patch for patch in ax.patches if isinstance(patch, Rectangle)]


def bar_heights_by_colour(ax) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    for patch in bars(ax):
        out.setdefault(to_hex(patch.get_facecolor()), []).append(patch.get_height())
    return out


def closed_form_se(values) -> float:
    mean = sum(values) / len(values)
    return math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1) / len(values))


def texts(fig) -> str:
    """All text of the figure, whitespace normalised (captions are wrapped)."""
    words = " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")))
    return " ".join(words.split())


# --------------------------------------------------------------------------- style


@pytest.mark.parametrize(
    "method, phase, condition",
    [
        ("NA", "no_misspecification", "NA"),
        ("CASA", "no_misspecification", "CASA"),
        ("CASA", "before_learning", "CASA before learning"),
        ("CASA", "after_learning", "CASA after learning"),
        ("PBA", "before_learning", "PBA"),
        ("NA", "after_learning", "NA after learning"),
        # Phases the study does not analyse keep the method's name.
        ("NA", "familiarization", "NA"),
        ("NA", "demonstration", "NA"),
    ],
)
def test_condition_names_follow_the_paper(method, phase, condition):
    # The task text: "CASA before learning" = method CASA with phase before_learning, etc.
    assert style.row_condition(method, phase) == condition


def test_condition_of_rejects_unknown_method():
    with pytest.raises(ValueError, match="unknown method 'XX'"):
        style.row_condition("XX", "before_learning")
    with pytest.raises(ValueError, match="unknown method 'XX'"):
        style.row_condition("XX", "familiarization")


def test_figures_import_no_robot_study_or_learning():
    import subprocess
    import sys

    code = (
        "import sys, casa_core.figures, casa_core.figures.build; "
        "bad = sorted(m for m in sys.modules if m.split('.')[:2] in "
        "(['casa_core', 'robot'], ['casa_core', 'study'], ['casa_core', 'learning']) "
        "or m == 'pybullet'); print(bad)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_condition_has_a_distinct_colour():
    colours = [style.METHOD_COLOURS[c] for c in CONDITIONS]
    assert len(set(colours)) == len(colours)


def test_intent_colours_keep_the_goal_colour_after_learning():
    colours = style.intent_colours(["green", "purple", "learned_red", "pour", "other"])
    assert colours["green"] == style.GOAL_COLOURS["green"]
    assert colours["learned_red"] == style.GOAL_COLOURS["red"]
    assert colours["pour"] != colours["other"]
    assert colours["pour"] not in style.GOAL_COLOURS.values()


def test_save_figure_writes_vector_pdf_and_200_dpi_png(tmp_path):
    from PIL import Image

    fig = objective_figure(make_trials())
    written = save_figure(fig, tmp_path / "out" / "objective")
    pdf, png = tmp_path / "out" / "objective.pdf", tmp_path / "out" / "objective.png"
    assert written == [pdf, png]
    assert pdf.read_bytes().startswith(b"%PDF")
    # Vector: the PDF draws the bars and text, it embeds no raster image.
    assert b"/Subtype /Image" not in pdf.read_bytes()
    with Image.open(png) as image:
        assert image.info["dpi"] == pytest.approx((200, 200), abs=0.01)
    # Atomic writes leave no temporary file behind.
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "objective.pdf",
        "objective.png",
    ]


def test_save_figure_is_reproducible(tmp_path):
    fig = objective_figure(make_trials())
    save_figure(fig, tmp_path / "a")
    save_figure(fig, tmp_path / "b")
    assert (tmp_path / "a.pdf").read_bytes() == (tmp_path / "b.pdf").read_bytes()
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


# --------------------------------------------------------------------------- objective


def test_objective_has_a_panel_per_metric_and_task():
    fig = objective_figure(make_trials())
    # Familiarization is not a compared task; Unknown Skill has no fixture trials.
    assert len(fig.axes) == 4 * 2
    labels = [panel(fig, row, 0).get_ylabel() for row in ROWS]
    assert labels[0].startswith("Error (") and labels[1].startswith("Efficiency cost (")
    assert labels[2] == "Effort (key presses / NA)"
    assert labels[3].startswith("Success")
    assert [ax.get_title() for ax in fig.axes[:2]] == ["Known Goal", "Unknown Goal"]
    assert "simulated participants (n = 3)" in texts(fig)
    assert "No trials for Unknown Skill" in texts(fig)


def test_objective_gives_each_task_its_own_y_scale():
    # Unknown Goal's errors 100 times Known Goal's (as in the study: 0.1-0.4 m^2 against
    # up to 40 m^2): on a shared axis Known Goal's bars would be under 2 % of its height.
    errors = {
        key: [100 * v for v in values] if key[0] == "unknown_goal" else values
        for key, values in ERRORS.items()
    }
    fig = objective_figure(make_trials(errors))
    known, unknown = panel(fig, "error", 0), panel(fig, "error", 1)
    # Each axis ends just above its own highest point (5.0 and 500), with room for brackets.
    assert 5.0 <= known.get_ylim()[1] < 10.0
    assert 500.0 <= unknown.get_ylim()[1] < 1000.0
    assert "each panel on its own y scale" in texts(fig)


def test_objective_bars_are_means_with_standard_errors():
    fig = objective_figure(make_trials())
    heights = bar_heights_by_colour(panel(fig, "error", 0))
    for colour, values in bar_heights_by_colour(panel(fig, "error", 1)).items():
        heights.setdefault(colour, []).extend(values)
    # Known Goal then Unknown Goal, in each colour's order of appearance.
    na = ERRORS[("known_goal", "NA", "no_misspecification")]
    na_unknown = ERRORS[("unknown_goal", "NA", "before_learning")]
    assert heights[style.METHOD_COLOURS["NA"].lower()] == pytest.approx([2.0, 2.0])
    assert heights[style.METHOD_COLOURS["PBA"].lower()] == pytest.approx([3.0, 4.0])
    assert heights[style.METHOD_COLOURS["CASA"].lower()] == pytest.approx([1.0])
    assert heights[style.METHOD_COLOURS["CASA before learning"].lower()] == pytest.approx([2.0])
    assert heights[style.METHOD_COLOURS["CASA after learning"].lower()] == pytest.approx([1.5])
    # Error bars: the first errorbar drawn is Known Goal NA, mean 2, SE = 1 / sqrt(3).
    caps = panel(fig, "error", 0).containers
    first = next(c for c in caps if c.__class__.__name__ == "ErrorbarContainer")
    segment = first.lines[2][0].get_segments()[0]
    assert segment[1][1] - segment[0][1] == pytest.approx(2 * closed_form_se(na))
    assert closed_form_se(na) == pytest.approx(1 / math.sqrt(3))
    assert closed_form_se(na_unknown) == pytest.approx(1.0)


def test_objective_draws_every_participant_as_a_point():
    fig = objective_figure(make_trials())
    scatters = [
        c
        for ax in (panel(fig, "error", 0), panel(fig, "error", 1))
        for c in ax.collections
        if isinstance(c, PathCollection)
    ]
    points = np.concatenate([c.get_offsets() for c in scatters])
    n_points = sum(len(v) for v in ERRORS.values())
    assert len(points) == n_points
    assert sorted(points[:, 1]) == pytest.approx(sorted(sum(ERRORS.values(), [])))


def test_objective_brackets_come_from_significant_tukey_rows():
    stats = pd.DataFrame(
        [
            tukey("known_goal", "error", "CASA vs NA", 0.0005),
            tukey("known_goal", "error", "CASA vs PBA", 0.3),  # not significant
            tukey("known_goal", "efficiency", "PBA vs NA", 0.02),
            # Pooled row and per-task row: the per-task row decides for Unknown Goal.
            tukey("unknown_goal+unknown_skill", "error", "CASA before learning vs PBA", 0.001),
            tukey("unknown_goal", "error", "CASA before learning vs PBA", 0.2),
            # A skipped test: stats.csv keeps its row, with no comparison and no p.
            tukey("known_goal", "relative_effort", np.nan, np.nan),
        ]
    )
    fig = objective_figure(make_trials(), stats)
    # Each task's panel draws that task's rows only (the metric rows; success has none).
    labels = [[t.get_text() for t in ax.texts] for ax in fig.axes[:6]]
    assert labels == [["***"], [], ["*"], [], [], []]
    assert "Tukey HSD between the conditions of one task" in texts(fig)
    assert "the pairwise comparisons after that task's" in texts(fig)


def test_objective_draws_a_pooled_row_where_no_task_row_exists():
    stats = pd.DataFrame(
        [tukey("unknown_goal+unknown_skill", "error", "CASA before learning - PBA", 0.004)]
    )
    fig = objective_figure(make_trials(), stats)
    assert [t.get_text() for t in panel(fig, "error", 1).texts] == ["**"]
    assert [t.get_text() for t in panel(fig, "error", 0).texts] == []
    assert "pooled over the misspecified tasks" in texts(fig)


@pytest.mark.parametrize(
    "p, code", [(0.0009, "***"), (0.001, "**"), (0.0099, "**"), (0.01, "*"), (0.05, "")]
)
def test_stars_thresholds(p, code):
    assert stars(p) == code


def test_parse_comparison_spellings():
    assert parse_comparison("CASA vs NA") == ("CASA", "NA")
    assert parse_comparison("CASA before learning - PBA") == ("CASA before learning", "PBA")
    assert parse_comparison("casa_after_learning vs. na") == ("CASA after learning", "NA")
    with pytest.raises(ValueError, match="unknown condition 'Magic'"):
        parse_comparison("Magic vs NA")
    with pytest.raises(ValueError, match="not of the form"):
        parse_comparison("CASA")


def test_objective_notes_missing_conditions():
    errors = {k: v for k, v in ERRORS.items() if k[1] != "PBA"}
    fig = objective_figure(make_trials(errors))
    assert "Known Goal: no PBA." in texts(fig)
    assert "Unknown Goal: no PBA." in texts(fig)


def test_objective_says_human_participants_for_human_data():
    fig = objective_figure(make_trials(source="human"))
    assert "human participants" in texts(fig)
    assert "simulated" not in texts(fig)


def test_objective_rejects_bad_input():
    with pytest.raises(ValueError, match="trials: missing column.*relative_effort"):
        objective_figure(make_trials().drop(columns="relative_effort"))
    bad = make_trials()
    bad.loc[2, "method"] = "ZZ"
    with pytest.raises(ValueError, match="trials row 2: unknown method 'ZZ'"):
        objective_figure(bad)
    stats = pd.DataFrame([tukey("known_goal", "error", "CASA versus", 0.01)])
    with pytest.raises(ValueError, match="stats row 0"):
        objective_figure(make_trials(), stats)


# --------------------------------------------------------------------------- likert


def make_likert() -> pd.DataFrame:
    rows = []
    scores = {"NA": [1, 2, 3], "PBA": [5, 6, 7], "CASA": [4, 4, 7]}
    for method, values in scores.items():
        for i, score in enumerate(values):
            for question in ("understood", "effortless", "useful"):
                rows.append(
                    {
                        "participant": f"P{i + 1}",
                        "task": "known_goal",
                        "method": method,
                        "phase": "no_misspecification",
                        "question": question,
                        "score": score,
                        "source": "simulated",
                    }
                )
    return pd.DataFrame(rows)


def test_likert_panels_questions_and_means():
    fig = likert_figure(make_likert())
    assert [ax.get_title() for ax in fig.axes] == ["Known Goal", "Unknown Goal", "Unknown Skill"]
    known = fig.axes[0]
    assert [t.get_text() for t in known.get_xticklabels()] == [
        "Understood",
        "Effortless",
        "Useful",
    ]
    # The 1-7 scale with room for the points at its ends.
    assert known.get_ylim() == pytest.approx((0.7, 7.3))
    heights = bar_heights_by_colour(known)
    # Means of the scores written in make_likert, once per question.
    assert heights[style.METHOD_COLOURS["NA"].lower()] == pytest.approx([2.0] * 3)
    assert heights[style.METHOD_COLOURS["CASA"].lower()] == pytest.approx([5.0] * 3)
    # Tasks without answers keep their panel, with a note.
    assert [t.get_text() for t in fig.axes[1].texts] == ["no survey answers\nfor Unknown Goal"]
    assert "simulated participants (n = 3)" in texts(fig)


@pytest.mark.parametrize("score", [0, 8, 3.5, "x"])
def test_likert_rejects_scores_off_the_scale(score):
    likert = make_likert()
    likert["score"] = likert["score"].astype(object)
    likert.loc[4, "score"] = score
    with pytest.raises(ValueError, match="likert row 4: score"):
        likert_figure(likert)


def test_likert_rejects_unknown_question():
    likert = make_likert()
    likert.loc[1, "question"] = "fun"
    with pytest.raises(ValueError, match="likert row 1: question 'fun'"):
        likert_figure(likert)


def wilcoxon(task, question, comparison, p) -> dict:
    return {
        "hypothesis": "H4",
        "analysis": "wilcoxon",
        "task": task,
        "metric": question,
        "term": "method",
        "comparison": comparison,
        "p": p,
    }


def likert_stats() -> pd.DataFrame:
    """A stats table with one significant Wilcoxon row (Understood, CASA vs NA, p = .004),
    one that is not (CASA vs PBA, p = .3), a Friedman row (p = .2) and a skipped test."""
    friedman = wilcoxon("known_goal", "understood", "", 0.2) | {"analysis": "friedman"}
    return pd.DataFrame(
        [
            friedman,
            wilcoxon("known_goal", "understood", "CASA vs NA", 0.004),
            wilcoxon("known_goal", "understood", "CASA vs PBA", 0.3),
            wilcoxon("known_goal", "useful", "CASA vs NA", np.nan),
        ]
    )


def bracket_lines(ax) -> list:
    """The brackets of an axes: lines of four points, up-across-down."""
    return [line for line in ax.get_lines() if len(line.get_xdata()) == 4]


def test_likert_draws_every_answer_as_a_point():
    fig = likert_figure(make_likert())
    known = fig.axes[0]
    scatters = [c for c in known.collections if isinstance(c, PathCollection)]
    # One point per participant, condition and question: 3 x 3 x 3 in make_likert.
    points = np.concatenate([c.get_offsets() for c in scatters])
    assert len(points) == 27
    scores = sorted(make_likert()["score"].astype(float))
    assert sorted(points[:, 1]) == pytest.approx(scores)
    assert "points: participants' answers" in texts(fig)


def test_likert_marks_come_from_the_stats_table():
    fig = likert_figure(make_likert(), likert_stats())
    known = fig.axes[0]
    # Only the significant row (p = .004 -> "**") draws a bracket; NA's mean (2, left)
    # below CASA's (5, right), the paper's direction: solid.
    assert [t.get_text() for t in known.texts] == ["< **"]
    (bracket,) = bracket_lines(known)
    assert bracket.get_linestyle() == "-"
    # From the NA bar to the CASA bar of the first question (Understood, x = 0): the bars
    # sit at -0.2, 0 and 0.2 (4 slots of 0.2 in a group 0.8 wide), ends pulled in by 0.03.
    assert bracket.get_xdata() == pytest.approx([-0.17, -0.17, 0.17, 0.17])
    # Above the highest answer under it (7, make_likert's CASA and PBA).
    assert min(bracket.get_ydata()) > 7
    ticks = [t.get_text() for t in known.get_xticklabels()]
    assert ticks == ["Understood\nn.s.", "Effortless\nno test", "Useful\nno test"]
    caption = texts(fig)
    for words in ("Friedman", "Wilcoxon signed-rank", "Holm-corrected", "p < .05 (alpha)"):
        assert words in caption


def test_likert_brackets_say_the_direction_and_dash_the_pairs_against_the_paper():
    # Significant both ways in Known Goal's Understood: CASA (mean 5) above NA (2), as
    # the paper expects, and below PBA (6), against it (make_likert's scores).
    stats = likert_stats()
    stats.loc[2, "p"] = 0.02
    known = likert_figure(make_likert(), stats).axes[0]
    marks = {
        (round(float(line.get_xdata()[0]), 2), text.get_text(), line.get_linestyle())
        for line, text in zip(bracket_lines(known), known.texts, strict=True)
    }
    # Bars at -0.2 (NA), 0 (PBA), 0.2 (CASA), bracket ends pulled in by 0.03; each sign
    # reads the left bar against the right one.
    assert marks == {(-0.17, "< **", "-"), (0.03, "> *", "--")}
    caption = texts(likert_figure(make_likert(), stats))
    assert "< or > before the stars: the left bar's mean below or above the right one's" in caption
    assert "dashed: against the paper's direction" in caption


def test_likert_rejects_a_bad_stats_row():
    stats = likert_stats()
    stats.loc[1, "comparison"] = "CASA vs nobody"
    with pytest.raises(ValueError, match="stats row 1: comparison 'CASA vs nobody'"):
        likert_figure(make_likert(), stats)


# --------------------------------------------------------------------------- arbitration


def make_arbitration() -> pd.DataFrame:
    t = np.arange(0.0, 5.5, 0.5)
    rows = []
    for name, belief, beta in (
        ("green", 0.5 + t / 11, 0.1 * t),
        ("purple", 0.5 - t / 11, 0.05 * t),
    ):
        for i, ti in enumerate(t):
            rows.append(
                {
                    "t": ti,
                    "intent": name,
                    "belief": belief[i],
                    "beta": beta[i],
                    "alpha_distance": 1 - ti / 10,
                    "alpha_belief": 1 - 2 * t[i] / 11,
                    "alpha_confidence": 1.0,
                }
            )
    return pd.DataFrame(rows)


def test_arbitration_panels_and_series():
    table = make_arbitration()
    fig = arbitration_figure(table, epsilon=1.0)
    axes = fig.axes_by_name
    assert set(axes) == {"belief", "confidence", "alpha"}
    belief_lines = {line.get_label(): line for line in axes["belief"].get_lines()}
    assert set(belief_lines) == {"green goal", "purple goal"}
    assert to_hex(belief_lines["green goal"].get_color()) == style.GOAL_COLOURS["green"].lower()
    green = table[table["intent"] == "green"]
    assert belief_lines["green goal"].get_ydata() == pytest.approx(green["belief"].to_numpy())
    alpha_labels = [line.get_label() for line in axes["alpha"].get_lines()]
    assert alpha_labels == ["distance (PBA)", "belief", "confidence (CASA)"]
    alpha_lines = axes["alpha"].get_lines()
    # One alpha per time, not one per (time, intent) row.
    assert len(alpha_lines[0].get_xdata()) == table["t"].nunique()
    # The threshold line and its label are on the confidence axes, inside the y range.
    assert axes["confidence"].get_ylim()[1] > 1.0
    assert axes["confidence"].get_xlabel() == "Time (s)"


def test_arbitration_rejects_alphas_that_differ_between_intents():
    table = make_arbitration()
    table.loc[len(table) - 1, "alpha_distance"] = 0.123
    with pytest.raises(ValueError, match="alpha columns differ between intents"):
        arbitration_figure(table)


def test_arbitration_rejects_missing_column_and_text():
    with pytest.raises(ValueError, match="arbitration: missing column.*alpha_belief"):
        arbitration_figure(make_arbitration().drop(columns="alpha_belief"))
    table = make_arbitration()
    table["beta"] = table["beta"].astype(object)
    table.loc[3, "beta"] = "high"
    with pytest.raises(ValueError, match="arbitration: column 'beta', row 3: 'high' is not"):
        arbitration_figure(table)


def test_arbitration_legend_is_clear_of_the_casa_curve():
    table = make_arbitration()
    # A CASA curve that dips and rises through the whole panel, as in the case study.
    table["alpha_confidence"] = 0.5 + 0.5 * np.cos(table["t"])
    fig = arbitration_figure(table, epsilon=1.0)
    fig.canvas.draw()
    alpha = fig.axes_by_name["alpha"]
    casa = next(line for line in alpha.get_lines() if line.get_label() == "confidence (CASA)")
    legend = alpha.get_legend()
    assert not legend.get_window_extent().overlaps(casa.get_window_extent())
    # Nor any other axes' data.
    for ax in fig.axes_by_name.values():
        assert not legend.get_window_extent().overlaps(ax.get_window_extent())


def test_arbitration_draws_and_names_the_threshold():
    fig = arbitration_figure(make_arbitration(), epsilon=0.7)
    flat = [
        line
        for line in fig.axes_by_name["confidence"].get_lines()
        if list(line.get_ydata()) == [0.7, 0.7]
    ]
    assert len(flat) == 1
    assert "threshold epsilon = 0.7" in texts(fig)


# --------------------------------------------------------------------------- case study


def make_steps(participant="expert") -> pd.DataFrame:
    t = np.arange(0.0, 3.0, 0.5)
    rows = []

    def add(task, method, phase, betas, alpha):
        for i, ti in enumerate(t):
            for name, beta in betas.items():
                rows.append(
                    {
                        "participant": participant,
                        "task": task,
                        "method": method,
                        "phase": phase,
                        "t": ti,
                        "alpha": alpha[i],
                        "intent": name,
                        "beta": beta * ti,
                        "belief": 0.5,
                    }
                )

    down = 1 - t / 3
    add("known_goal", "CASA", "no_misspecification", {"green": 0.5, "purple": 0.1}, down)
    add("known_goal", "PBA", "no_misspecification", {"green": 1.0, "purple": 1.0}, down / 2)
    add("unknown_goal", "CASA", "before_learning", {"green": 0.1, "purple": 0.05}, t * 0 + 1)
    add("unknown_goal", "PBA", "before_learning", {"green": 1.0, "purple": 1.0}, down)
    add("unknown_goal", "CASA", "after_learning", {"green": 0.1, "red": 0.6}, down)
    return pd.DataFrame(rows)


def test_case_study_rows_columns_and_series():
    fig = case_study_figure(make_steps(), epsilon=1.0)
    grid = fig.axes_grid
    assert list(grid) == ["known_goal", "unknown_goal"]
    before, after, alpha = grid["unknown_goal"]
    assert {line.get_label() for line in after.get_lines()} >= {"green goal", "red goal"}
    red = next(line for line in after.get_lines() if line.get_label() == "red goal")
    assert to_hex(red.get_color()) == style.GOAL_COLOURS["red"].lower()
    assert red.get_ydata() == pytest.approx(0.6 * np.arange(0.0, 3.0, 0.5))
    labels = [line.get_label() for line in alpha.get_lines()]
    assert labels == ["PBA", "CASA before learning", "CASA after learning"]
    known_after = grid["known_goal"][1]
    assert "nothing to learn" in known_after.texts[0].get_text()
    assert [line.get_label() for line in grid["known_goal"][2].get_lines()] == ["PBA", "CASA"]
    # The case study's expert is scripted, and the figure says so.
    assert "scripted expert (waypoint follower)" in texts(fig)
    assert "participant expert" not in texts(fig)
    # Row labels in the paper's words.
    assert "Known Goal" in [t.get_text() for t in grid["known_goal"][0].texts]


def test_case_study_chooses_the_named_participant():
    steps = pd.concat([make_steps("a"), make_steps("b")], ignore_index=True)
    steps.loc[steps["participant"] == "b", "beta"] *= 2
    fig = case_study_figure(steps, participant="b")
    green = next(
        line
        for line in fig.axes_grid["known_goal"][0].get_lines()
        if line.get_label() == "green goal"
    )
    assert green.get_ydata() == pytest.approx(2 * 0.5 * np.arange(0.0, 3.0, 0.5))
    with pytest.raises(ValueError, match="no rows for participant 'c'"):
        case_study_figure(steps, participant="c")


def test_case_study_rejects_duplicate_rows():
    steps = make_steps()
    steps = pd.concat([steps, steps.iloc[[0]]], ignore_index=True)
    with pytest.raises(ValueError, match="two rows for t = 0.0 and intent 'green'"):
        case_study_figure(steps)


def test_case_study_draws_the_threshold_at_epsilon_with_display_names():
    steps = make_steps()
    steps["intent"] = steps["intent"].replace({"red": "learned_red", "purple": "learned_pour"})
    fig = case_study_figure(steps, epsilon=0.7)
    drawn = 0
    for task, axes in fig.axes_grid.items():
        for ax in axes[:2]:
            if not ax.has_data():
                continue  # "nothing to learn": no run, no line
            threshold = [line for line in ax.get_lines() if line.get_label().startswith("thr")]
            assert len(threshold) == 1, task
            assert list(threshold[0].get_ydata()) == [0.7, 0.7]
            # The panel shows the threshold even when the confidences stay below it.
            assert ax.get_ylim()[1] > 0.7
            drawn += 1
    assert drawn == 3  # make_steps: Known Goal before, Unknown Goal before and after
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend == [
        "green goal",
        "learned pour",
        "learned red goal",
        "threshold $\\epsilon$ = 0.7",
    ]
    assert not any("_" in label for label in legend)
    assert "threshold epsilon = 0.7" in texts(fig)


def test_display_names_of_intents():
    assert style.display_name("learned_pour") == "learned pour"
    assert style.display_name("learned_red") == "learned red goal"
    assert style.display_name("green") == "green goal"
    assert style.display_name("CASA after learning") == "CASA after learning"


def test_brackets_sit_above_their_data_and_do_not_collide():
    from casa_core.figures import _bars

    fig = style.new_figure(3, 2)
    ax = fig.subplots()
    ax.set_ylim(0, 10)
    # Two brackets meeting at x = 1 and one spanning both, all over data up to 5.
    _bars.draw_brackets(ax, [(0.0, 1.0, 5.0, "*"), (1.0, 2.0, 5.0, "**"), (0.0, 2.0, 5.0, "***")])
    heights = {t.get_text(): t.get_position()[1] for t in ax.texts}
    assert min(heights.values()) > 5.0
    assert heights["*"] != heights["**"]
    assert heights["***"] > max(heights["*"], heights["**"])
    # The axis grows to hold the highest bracket.
    assert ax.get_ylim()[1] > heights["***"]


def test_objective_notes_a_metric_the_dataset_lacks():
    trials = make_trials()
    trials["efficiency"] = np.nan
    fig = objective_figure(trials)
    for column in (0, 1):
        efficiency = panel(fig, "efficiency", column)
        assert [t.get_text() for t in efficiency.texts] == ["no efficiency cost in the data"]
        assert not bars(efficiency)
        assert bars(panel(fig, "error", column)) and bars(panel(fig, "relative_effort", column))


def crosses(ax) -> np.ndarray:
    """Offsets of the points drawn as trials that ran out of time."""
    marked = [c for c in ax.collections if c.get_label() == "ran out of time"]
    return np.concatenate([c.get_offsets() for c in marked]) if marked else np.empty((0, 2))


def test_objective_marks_and_counts_trials_that_ran_out_of_time():
    fig = objective_figure(make_trials())
    # The fixture's one timed-out trial: Unknown Goal, PBA, P3, error 5.0 (efficiency
    # 0.05, relative effort 1.25), in every metric's Unknown Goal panel only.
    for row, value in (("error", 5.0), ("efficiency", 0.05), ("relative_effort", 1.25)):
        assert crosses(panel(fig, row, 0)).shape == (0, 2)
        assert crosses(panel(fig, row, 1))[:, 1].tolist() == pytest.approx([value])
    # 21 analysed trials (7 conditions x 3 participants); the 40 s limit is its duration.
    assert "1 of 21 trials ran out of time at 40 s, drawn as crosses" in texts(fig)
    assert "(Unknown Goal: PBA 1 of 3)" in texts(fig)
    assert "ran out of time" in [t.get_text() for t in fig.legends[0].get_texts()]


def test_objective_says_when_logs_do_not_give_their_time_limit():
    trials = make_trials()
    trials["timed_out"] = np.nan  # what trials.csv holds for logs without max_duration
    fig = objective_figure(trials)
    assert all(crosses(ax).size == 0 for ax in fig.axes)
    assert "The logs do not say their time limit" in texts(fig)
    # An older trials.csv without the column draws the same.
    older = objective_figure(trials.drop(columns="timed_out"))
    assert "do not say their time limit" in texts(older)


def test_objective_success_panel_shows_shares_wilson_intervals_and_counts():
    fig = objective_figure(make_trials())
    known, unknown = panel(fig, "success", 0), panel(fig, "success", 1)
    # Known Goal: NA 2 of 3 succeeded (P3 failed), PBA and CASA 3 of 3. Unknown Goal: PBA
    # 2 of 3 (the timed-out P3 failed), the other three conditions 3 of 3.
    assert [b.get_height() for b in bars(known)] == pytest.approx([2 / 3, 1.0, 1.0])
    assert [b.get_height() for b in bars(unknown)] == pytest.approx([1.0, 2 / 3, 1.0, 1.0])
    assert [t.get_text() for t in known.texts] == ["2/3", "3/3", "3/3"]
    # Wilson 95 % for 2 of 3, z = 1.96: centre (p + z^2/2n) / (1 + z^2/n) and half width
    # z / (1 + z^2/n) sqrt(p (1 - p) / n + z^2 / 4n^2) = 0.5731 -+ 0.3654.
    z, n, p = 1.959964, 3, 2 / 3
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z / (1 + z**2 / n) * math.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    assert (centre - half, centre + half) == pytest.approx((0.2077, 0.9385), abs=1e-4)
    bar = next(c for c in known.containers if c.__class__.__name__ == "ErrorbarContainer")
    (low, high) = bar.lines[2][0].get_segments()[0][:, 1]
    assert (low, high) == pytest.approx((centre - half, centre + half))
    # 3 of 3: the lower end is n / (n + z^2).
    full = next(c for c in unknown.containers if c.__class__.__name__ == "ErrorbarContainer")
    assert full.lines[2][0].get_segments()[0][0, 1] == pytest.approx(3 / (3 + z**2))
    assert "within 5 cm of the end of the intended trajectory" in texts(fig)
    assert "Wilson 95% interval" in texts(fig)


def test_objective_rejects_a_flag_that_is_not_true_or_false():
    trials = make_trials()
    trials["success"] = trials["success"].astype(object)
    trials.loc[4, "success"] = "maybe"
    with pytest.raises(ValueError, match="trials row 4: success 'maybe' is not true or false"):
        objective_figure(trials)


# --------------------------------------------------------------------------- setup


def test_each_figure_of_a_study_names_its_setup_on_the_captions_last_line():
    setup = "scene scene-original.yaml (teleop original)"
    drawn = {
        "objective": lambda **kw: objective_figure(make_trials(), **kw),
        "likert": lambda **kw: likert_figure(make_likert(), **kw),
        "arbitration": lambda **kw: arbitration_figure(make_arbitration(), **kw),
        "case_study": lambda **kw: case_study_figure(make_steps(), **kw),
    }
    for name, draw in drawn.items():
        caption = draw(setup=setup).texts[-1].get_text()  # the figure's own text: the caption
        assert " ".join(caption.split()).endswith(f"Setup: {setup}."), name
        assert "Setup:" not in texts(draw()), name
