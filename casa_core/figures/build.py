"""Read the processed tables, draw a figure and write it: what ``casa figure`` runs."""

from __future__ import annotations

from pathlib import Path

from casa_core.figures import style
from casa_core.io import read_table

#: Figure name -> its inputs (keywords of :func:`build_figure`): the paths of the tables it
#: reads; for the scene, the rendered image (an array).
INPUTS: dict[str, tuple[str, ...]] = {
    "objective": ("trials", "stats"),
    "likert": ("likert", "stats"),
    "arbitration": ("arbitration",),
    "case_study": ("steps",),
    "scene": ("image", "landmarks"),
}


def build_figure(name: str, out: str | Path, **inputs) -> list[Path]:
    """Draw figure ``name`` from its input files and write it next to ``out``.

    Parameters
    ----------
    name : str
        One of :data:`INPUTS`.
    out : path-like
        Output prefix: ``<out>.pdf`` and ``<out>.png`` are written; for ``scene`` only
        the PNG (a rendering has no vector form).
    **inputs
        Paths of the input tables by the names in :data:`INPUTS` (``stats`` is optional
        for ``objective`` and ``likert``), plus the options ``epsilon`` (arbitration,
        case_study), ``participant`` (case_study) and ``setup`` (every figure but the
        scene: the setup its data come from, on the caption's last line). The scene's ``image`` and
        ``landmarks`` (optional) come from the caller
        (:func:`casa_core.robot.render.render_scene` and
        :func:`~casa_core.robot.render.scene_landmarks`), since figures know no robots.

    Returns
    -------
    list of Path
        The files written.
    """
    from casa_core import figures

    if name not in INPUTS:
        raise ValueError(f"unknown figure {name!r}; expected one of {', '.join(INPUTS)}")
    epsilon, setup = inputs.get("epsilon"), inputs.get("setup")
    if name == "objective":
        stats = inputs.get("stats")
        fig = figures.objective_figure(
            read_table(inputs["trials"]), read_table(stats) if stats else None, setup=setup
        )
    elif name == "likert":
        stats = inputs.get("stats")
        fig = figures.likert_figure(
            read_table(inputs["likert"]), read_table(stats) if stats else None, setup=setup
        )
    elif name == "arbitration":
        fig = figures.arbitration_figure(
            read_table(inputs["arbitration"]), epsilon=epsilon, setup=setup
        )
    elif name == "case_study":
        fig = figures.case_study_figure(
            read_table(inputs["steps"]),
            participant=inputs.get("participant"),
            epsilon=epsilon,
            setup=setup,
        )
    else:
        fig = figures.scene_figure(inputs["image"], inputs.get("landmarks"))
        return style.save_figure(fig, out, formats=("png",))
    return style.save_figure(fig, out)
