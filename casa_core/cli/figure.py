"""``casa figure``: the paper's figures from the processed tables."""

from __future__ import annotations

import sys

from casa_core.cli._options import positive_float, scene_option


def register(commands) -> None:
    """Add this module's commands to the ``casa`` subcommands."""
    _add_figure(commands)


def _add_figure(commands) -> None:
    command = commands.add_parser(
        "figure",
        help="draw one of the paper's figures from the processed tables (PDF + 200 dpi PNG)",
        description="Write PREFIX.pdf and PREFIX.png (scene: the PNG only).",
    )
    figures = command.add_subparsers(dest="figure", metavar="NAME", required=True)
    objective = figures.add_parser("objective", help="error, efficiency and effort per task")
    objective.add_argument("--trials", required=True, metavar="CSV", help="trials.csv")
    objective.add_argument("--stats", metavar="CSV", help="stats.csv (Tukey brackets)")
    likert = figures.add_parser("likert", help="Likert scores per task and question")
    likert.add_argument("--likert", required=True, metavar="CSV", help="likert.csv")
    likert.add_argument(
        "--stats", metavar="CSV", help="stats.csv (Friedman and Holm-corrected Wilcoxon marks)"
    )
    arbitration = figures.add_parser("arbitration", help="belief, confidence and alpha")
    arbitration.add_argument(
        "--arbitration", required=True, metavar="CSV", help="the case study's arbitration.csv"
    )
    case_study = figures.add_parser("case_study", help="confidence and alpha per task")
    case_study.add_argument("--steps", required=True, metavar="CSV", help="steps.csv")
    case_study.add_argument("--participant", help="whose runs (default: the first)")
    for sub in (arbitration, case_study):
        sub.add_argument("--epsilon", type=positive_float, help="draw the confidence threshold")
    for sub in (objective, likert, arbitration, case_study):
        sub.add_argument(
            "--setup",
            metavar="TEXT",
            help="the setup the data come from, e.g. 'scene scene.yaml (teleop held)', "
            "on the caption's last line",
        )
    scene = figures.add_parser("scene", help="the arm and scene, pybullet-rendered")
    scene_option(scene)
    for sub in (objective, likert, arbitration, case_study, scene):
        sub.add_argument("--out", required=True, metavar="PREFIX", help="output path")
        sub.set_defaults(func=_figure)


def _figure(args) -> int:
    from casa_core.figures.build import INPUTS, build_figure

    options = ("epsilon", "participant", "setup")
    inputs = {k: getattr(args, k) for k in (*INPUTS[args.figure], *options) if hasattr(args, k)}
    try:
        if args.figure == "scene":
            # Figures know no robots: the robot package renders the image the figure shows.
            from casa_core.figures.scene import TASK_PATHS
            from casa_core.robot.render import render_scene, scene_landmarks
            from casa_core.scene import load_scene

            scene = load_scene(args.scene)
            inputs["image"] = render_scene(scene, TASK_PATHS)
            inputs["landmarks"] = scene_landmarks(scene)
        written = build_figure(args.figure, args.out, **inputs)
    except (OSError, ValueError) as error:
        print(f"casa figure {args.figure}: {error}", file=sys.stderr)
        return 1
    print(f"casa figure {args.figure}: " + ", ".join(str(path) for path in written))
    return 0
