"""The scene figure (``figures/scene.png``): a rendering of the arm and scene, with a legend.

The image comes in as an array: :func:`casa_core.robot.render.render_scene` draws it
(the arm at the start pose with the cup in its hand, the goals, the cup tilted at the
pouring pose above the bowl and the tasks' intended trajectories in the colours of
:data:`TASK_PATHS`), so that the figures know nothing of robots. Where the cup, the
pouring pose and the bowl are in the image comes in too
(:func:`casa_core.robot.render.scene_landmarks`): the figure labels them.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from casa_core.figures import style
from casa_core.vocabulary import TASK_LABELS

#: The cup's colour in the rendering (:data:`casa_core.robot.scene.COLORS` ``"cup"``).
CUP_COLOUR = "#0059F2"

#: Labels of the landmarks: name -> (words, text offset from the point in points). The
#: offsets put each label on the table or the background, away from the arm.
LANDMARK_LABELS: dict[str, tuple[str, tuple[float, float]]] = {
    "cup": ("cup, held at the start", (-45.0, -75.0)),
    "pouring pose": ("pouring pose:\ncup tilted above the bowl", (-10.0, 50.0)),
    "bowl": ("bowl", (-45.0, -30.0)),
}

#: Tasks whose intended trajectories are drawn, with their colours: the colour of the
#: goal each one ends at (the pouring skill takes the first non-goal intent colour).
TASK_PATHS: dict[str, str] = {
    "known_goal": style.GOAL_COLOURS["green"],
    "unknown_goal": style.GOAL_COLOURS["red"],
    "unknown_skill": style.OTHER_INTENT_COLOURS[0],
}


def crop_box(image: np.ndarray, margin: int = 8) -> tuple[int, int, int, int]:
    """``(top, bottom, left, right)`` of the part of ``image`` that is not background.

    The background is the top-left pixel's colour; ``margin`` pixels of it are kept.
    """
    background = image[0, 0].astype(int)
    content = np.any(np.abs(image.astype(int) - background) > 8, axis=2)
    rows, cols = np.flatnonzero(content.any(axis=1)), np.flatnonzero(content.any(axis=0))
    if rows.size == 0:
        return 0, image.shape[0], 0, image.shape[1]
    top, bottom = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, image.shape[0])
    left, right = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, image.shape[1])
    return int(top), int(bottom), int(left), int(right)


def crop_background(image: np.ndarray, margin: int = 8) -> np.ndarray:
    """Cut off the rows and columns that show only the background (the top-left colour)."""
    top, bottom, left, right = crop_box(image, margin)
    return image[top:bottom, left:right]


def scene_figure(
    image: np.ndarray, landmarks: dict[str, tuple[float, float]] | None = None
) -> Figure:
    """The rendered scene with a legend of goals and intended trajectories.

    Parameters
    ----------
    image : ndarray
        ``(height, width, 3)`` RGB rendering of the scene with the paths of
        :data:`TASK_PATHS` (:func:`casa_core.robot.render.render_scene`); its background
        margins are cropped (:func:`crop_background`).
    landmarks : dict, optional
        Name -> ``(column, row)`` in ``image`` (before cropping) of the points to label,
        among :data:`LANDMARK_LABELS` (:func:`casa_core.robot.render.scene_landmarks`);
        other names are an error.

    Returns
    -------
    Figure
        One axes showing the image, with a legend naming the goals, the cup and the
        tasks' paths, and a labelled arrow to each landmark.
    """
    unknown = sorted(set(landmarks or {}) - set(LANDMARK_LABELS))
    if unknown:
        raise ValueError(
            f"scene landmarks: unknown name(s) {', '.join(unknown)}; "
            f"expected {', '.join(LANDMARK_LABELS)}"
        )
    top, _, left, _ = crop_box(image)
    image = crop_background(image)
    height, width = image.shape[:2]
    with style.context():
        fig = style.new_figure(4.5, 4.5 * height / width + 0.6)
        ax = fig.subplots()
        ax.imshow(image, interpolation="lanczos")
        ax.set_axis_off()
        goal_words = {"green": "known", "purple": "known", "red": "unknown"}
        handles = [
            Line2D([], [], ls="", marker="o", ms=6, color=style.GOAL_COLOURS[name])
            for name in goal_words
        ]
        labels = [f"{name} goal ({word})" for name, word in goal_words.items()]
        handles += [Line2D([], [], color=colour, lw=2) for colour in TASK_PATHS.values()]
        labels += [f"{TASK_LABELS[task]} path" for task in TASK_PATHS]
        handles += [
            Line2D([], [], ls="", marker="s", ms=6, color=CUP_COLOUR),
            Line2D([], [], color="0.15", ls="--", lw=1.2),
        ]
        labels += ["cup", "plumb line to the bowl"]
        fig.legend(handles, labels, loc="outside upper center", ncols=3, handlelength=1.5)
        for name, (x, y) in (landmarks or {}).items():
            words, offset = LANDMARK_LABELS[name]
            ax.annotate(
                words,
                (x - left, y - top),
                xytext=offset,
                textcoords="offset points",
                ha="center",
                va="center",
                fontsize=7,
                bbox={"boxstyle": "round,pad=0.25", "fc": "white", "ec": "0.5", "lw": 0.5},
                arrowprops={"arrowstyle": "-|>", "color": "0.1", "lw": 0.7, "shrinkB": 2},
            )
        style.add_caption(
            fig,
            "The simulated JACO arm at the start pose holding the cup (blue), the goals, the"
            " bowl of the pouring task and the tasks' intended trajectories. The Unknown"
            " Skill path ends at the pouring pose, where the cup is drawn tilted to pour;"
            " the dashed plumb line drops from it to the bowl (pybullet software renderer).",
        )
    return fig
