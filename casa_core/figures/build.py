"""Read the processed tables, draw a figure and write it: what ``casa figure`` runs."""

from __future__ import annotations

from pathlib import Path

import yaml

from casa_core.datasets import read_table
from casa_core.figures import style

#: Figure name -> the input files it reads (keyword of :func:`build_figure`).
INPUTS: dict[str, tuple[str, ...]] = {
    "objective": ("trials", "stats"),
    "likert": ("likert",),
    "arbitration": ("arbitration",),
    "case_study": ("steps",),
    "scene": ("scene",),
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
        for ``objective``), plus the options ``epsilon`` (arbitration, case_study) and
        ``participant`` (case_study).

    Returns
    -------
    list of Path
        The files written.
    """
    from casa_core import figures

    if name not in INPUTS:
        raise ValueError(f"unknown figure {name!r}; expected one of {', '.join(INPUTS)}")
    epsilon = inputs.get("epsilon")
    if name == "objective":
        stats = inputs.get("stats")
        fig = figures.objective_figure(
            read_table(inputs["trials"]), read_table(stats) if stats else None
        )
    elif name == "likert":
        fig = figures.likert_figure(read_table(inputs["likert"]))
    elif name == "arbitration":
        fig = figures.arbitration_figure(read_table(inputs["arbitration"]), epsilon=epsilon)
    elif name == "case_study":
        fig = figures.case_study_figure(
            read_table(inputs["steps"]), participant=inputs.get("participant"), epsilon=epsilon
        )
    else:
        with open(inputs["scene"], encoding="utf-8") as handle:
            scene = yaml.safe_load(handle)
        return style.save_figure(figures.scene_figure(scene), out, formats=("png",))
    return style.save_figure(fig, out)
