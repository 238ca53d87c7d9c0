"""CI: every expected figure exists, is a valid, non-blank PDF or PNG, and has its panels.

Panels are counted on the figure objects rebuilt from the same processed tables.
"""

import sys
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.image import imread

from casa_core import figures
from casa_core.assist.tasks import intended_trajectory
from casa_core.cli._options import dataset_scene
from casa_core.figures.path import COLUMNS as PATH_COLUMNS
from casa_core.figures.path import path_figure
from casa_core.figures.replay import replay_figure
from casa_core.io import read_table, read_trial
from casa_core.scene import load_scene

PROCESSED, FIGS = Path("data/processed"), Path("figures")
problems = []
# `check_figures.py robustness` (or `power`): only that target's table and figure.
ROBUSTNESS = sys.argv[1:] == ["robustness"]
POWER = sys.argv[1:] == ["power"]


def check_file(path: Path) -> None:
    if not path.is_file() or path.stat().st_size == 0:
        problems.append(f"{path}: missing or empty")
    elif path.suffix == ".pdf" and not path.read_bytes().startswith(b"%PDF"):
        problems.append(f"{path}: not a PDF")
    elif path.suffix == ".png":
        image = imread(path)
        if image.ndim < 2 or float(np.std(image)) < 1e-3:
            problems.append(f"{path}: blank image")


def finish(done: str) -> None:
    for problem in problems:
        print(f"check_figures: {problem}", file=sys.stderr)
    print(f"check_figures: {'FAILED' if problems else done}")
    sys.exit(1 if problems else 0)


def check_panels(name: str, figure, expected: int) -> None:
    panels = [axis for axis in figure.axes if axis.has_data()]
    if len(panels) < expected:
        problems.append(f"{name}: {len(panels)} panel(s) with data, expected {expected}")


if ROBUSTNESS:
    from casa_core.figures.robustness import robustness_figure

    for ext in ("pdf", "png"):
        check_file(FIGS / f"robustness.{ext}")
    table = read_table(PROCESSED / "robustness" / "claims.csv")
    if table["variant"].nunique() < 2:
        problems.append("robustness/claims.csv: fewer than 2 variants")
    check_panels("robustness", robustness_figure(table), 1)
    finish("robustness table and figure complete")

if POWER:
    from casa_core.figures.power import power_figure
    from casa_core.stats.power import POWER_COLUMNS

    for ext in ("pdf", "png"):
        check_file(FIGS / f"power.{ext}")
    table = read_table(PROCESSED / "power" / "power.csv")
    # casa power table adds whom the participants were drawn from (docs/power.md).
    expected = [*POWER_COLUMNS, "population"]
    if list(table.columns) != expected:
        problems.append(f"power/power.csv: columns {list(table.columns)}, expected {expected}")
    else:
        print(f"check_figures: power drawn from {', '.join(sorted(set(table['population'])))}")
    # A panel per hypothesis (H1-H3) and metric (error, efficiency, relative effort).
    check_panels("power", power_figure(table), 9)
    finish("power table and figure complete")

for stem in ["arbitration", "case_study", "simulated/objective", "simulated/likert"]:
    for ext in ("pdf", "png"):
        check_file(FIGS / f"{stem}.{ext}")
check_file(FIGS / "scene.png")

read = read_table
simulated = PROCESSED / "simulated"
check_panels(
    "objective",
    figures.objective_figure(read(simulated / "trials.csv"), read(simulated / "stats.csv")),
    12,  # 4 rows (error, efficiency, effort, success) x 3 tasks
)
check_panels("likert", figures.likert_figure(read(simulated / "likert.csv")), 3)
check_panels(
    "arbitration", figures.arbitration_figure(read(PROCESSED / "case_study/arbitration.csv")), 2
)
check_panels("case_study", figures.case_study_figure(read(PROCESSED / "case_study/steps.csv")), 6)

# casa replay: a PNG per replayed trial; the first one's figure has its three panels.
replays = read(simulated / "replay" / "replay.csv")
replayed = replays[replays["status"] == "replayed"]["trial"].tolist()
if not replayed:
    problems.append("simulated/replay: no trial replayed")
# Every assisted trial, after learning included (with the intents each participant's
# folder keeps).
for _, row in replays[replays["status"] != "replayed"].iterrows():
    if row["method"] != "NA":
        problems.append(f"simulated/replay: {row['trial']} {row['status']}: {row['reason']}")
# Beside each replay figure, the trial's path over its task's intended path.
for trial in replayed:
    for figure in ("replay", "path"):
        check_file(FIGS / "simulated" / "replay" / f"{trial}.{figure}.png")
if replayed:
    first = read(simulated / "replay" / f"{replayed[0]}.replay.csv")
    meta, log = read_trial(Path("data/raw/simulated") / replayed[0])
    replay = replay_figure(first, logged=log)
    check_panels(f"replay {replayed[0]}", replay, 3)
    if len(replay.axes[2].lines) != 2:
        problems.append(f"replay {replayed[0]}: no logged alpha beside the replayed one")
    scene = load_scene(dataset_scene(Path("data/raw/simulated"), None))
    intended = pd.DataFrame(intended_trajectory(meta["task"], scene), columns=PATH_COLUMNS)
    check_panels(f"path {replayed[0]}", path_figure(log, intended), 4)

finish("all figures present and complete")
