"""The paper's figures, drawn by matplotlib from the processed tables.

Each module draws one figure from pandas DataFrames (the processed tables) and returns
a :class:`matplotlib.figure.Figure`; :func:`save_figure` writes it as vector PDF plus a
200 dpi PNG, atomically. :mod:`.style` holds the colours, words and layout they share.

- :func:`objective_figure` -- ``trials.csv`` (+ ``stats.csv``): error, efficiency, effort
- :func:`likert_figure` -- ``likert.csv`` (+ ``stats.csv``): the three questions per task
- :func:`arbitration_figure` -- ``arbitration.csv``: belief, confidence and three alphas
- :func:`case_study_figure` -- ``steps.csv``: confidence and alpha over time per task
- :func:`scene_figure` -- a rendering of the arm and scene
  (:func:`casa_core.robot.render.render_scene`), with its legend
"""

from casa_core.figures.arbitration import arbitration_figure
from casa_core.figures.case_study import case_study_figure
from casa_core.figures.likert import likert_figure
from casa_core.figures.objective import objective_figure
from casa_core.figures.scene import scene_figure
from casa_core.figures.style import save_figure

__all__ = [
    "arbitration_figure",
    "case_study_figure",
    "likert_figure",
    "objective_figure",
    "save_figure",
    "scene_figure",
]
