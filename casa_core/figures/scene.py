"""The scene figure (``figures/scene.png``): a rendering of the arm and scene, with a legend.

The image comes in as an array: :func:`casa_core.robot.render.render_scene` draws it
(the arm at the start pose, the goals and the tasks' intended trajectories in the
colours of :data:`TASK_PATHS`), so that the figures know nothing of robots.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from casa_core.figures import style
from casa_core.vocabulary import TASK_LABELS

#: Tasks whose intended trajectories are drawn, with their colours: the colour of the
#: goal each one ends at (the pouring skill takes the first non-goal intent colour).
TASK_PATHS: dict[str, str] = {
    "known_goal": style.GOAL_COLOURS["green"],
    "unknown_goal": style.GOAL_COLOURS["red"],
    "unknown_skill": style.OTHER_INTENT_COLOURS[0],
}


def crop_background(image: np.ndarray, margin: int = 8) -> np.ndarray:
    """Cut off the rows and columns that show only the background (the top-left colour)."""
    background = image[0, 0].astype(int)
    content = np.any(np.abs(image.astype(int) - background) > 8, axis=2)
    rows, cols = np.flatnonzero(content.any(axis=1)), np.flatnonzero(content.any(axis=0))
    if rows.size == 0:
        return image
    top, bottom = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, image.shape[0])
    left, right = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, image.shape[1])
    return image[top:bottom, left:right]


def scene_figure(image: np.ndarray) -> Figure:
    """The rendered scene with a legend of goals and intended trajectories.

    Parameters
    ----------
    image : ndarray
        ``(height, width, 3)`` RGB rendering of the scene with the paths of
        :data:`TASK_PATHS` (:func:`casa_core.robot.render.render_scene`); its background
        margins are cropped (:func:`crop_background`).

    Returns
    -------
    Figure
        One axes showing the image, with a legend naming the goals and the tasks' paths.
    """
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
        fig.legend(handles, labels, loc="outside upper center", ncols=3, handlelength=1.5)
        style.add_caption(
            fig,
            "The simulated JACO arm at the start pose, the goals, the bowl of the pouring"
            " task and the tasks' intended trajectories; the cup is poured where the Unknown"
            " Skill path ends (pybullet software renderer).",
        )
    return fig
