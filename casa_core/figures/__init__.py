"""The paper's figures, drawn by matplotlib from the processed tables.

Each module draws one figure from pandas DataFrames (the processed tables) and returns
a :class:`matplotlib.figure.Figure`; :func:`save_figure` writes it as vector PDF plus a
200 dpi PNG, atomically. :mod:`.style` holds the colours, words and layout they share.

- :mod:`~casa_core.figures.objective`: ``trials.csv`` (+ ``stats.csv``): error,
  efficiency, effort (:func:`objective_figure`)
- :mod:`~casa_core.figures.likert`: ``likert.csv`` (+ ``stats.csv``): the three questions
  per task (:func:`likert_figure`)
- :mod:`~casa_core.figures.arbitration`: ``arbitration.csv``: belief, confidence and three
  alphas (:func:`arbitration_figure`)
- :mod:`~casa_core.figures.case_study`: ``steps.csv``: confidence and alpha over time per
  task (:func:`case_study_figure`)
- :mod:`~casa_core.figures.scene`: a rendering of the arm and scene, with its legend
  (:func:`scene_figure`)
- :mod:`~casa_core.figures.replay`: a replayed trial: belief, confidence and alpha over time
- :mod:`~casa_core.figures.path`: a trial's logged path against its task's intended path
- :mod:`~casa_core.figures.robustness`: the claims under each modelling variant
- :mod:`~casa_core.figures.power`: power against the number of participants
- :mod:`~casa_core.figures.calibration`: `casa calibrate`'s posterior predictive check and
  the parameter recovery
- :mod:`~casa_core.figures.build`: the tables read, a figure drawn and written (``casa figure``)
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
