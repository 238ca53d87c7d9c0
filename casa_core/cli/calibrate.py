"""``casa calibrate``: the simulated operators' population fitted to a dataset's people."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from casa_core import vocabulary
from casa_core.cli._options import (
    dataset_scene,
    dataset_scene_option,
    example,
    nonnegative_int,
    positive_int,
)

EXAMPLE = "casa calibrate data/raw/mylab --out populations/mylab.json"


def register(commands) -> None:
    """Add ``casa calibrate`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "calibrate",
        help="fit the simulated operators to a dataset's people (simulation-based inference)",
        description="Simulate the human trials of DATASET (a folder of trial logs) with "
        "operators drawn from the prior, fit the population's medians by neural posterior "
        "estimation (sbi), and write the population FILE (JSON, docs/calibration.md), "
        "FILE's stem + _predictive.csv (people's summaries beside the fitted model's, per "
        "task and method, with 90% intervals) and + _predictive.png. Set "
        "simulation.operator_population: FILE to simulate the study and the power analysis "
        "with it. Nothing is written until everything is computed.",
        **example(EXAMPLE),
    )
    command.add_argument("dataset", metavar="DATASET", help="folder of trial logs (source human)")
    command.add_argument("--out", required=True, metavar="FILE", help="population file (.json)")
    command.add_argument(
        "--config",
        action="append",
        metavar="YAML",
        help="the study's config: operator model, population spreads, inference (default "
        "config/config.yaml); repeat to overlay files in order",
    )
    dataset_scene_option(command, "DATASET")
    command.add_argument(
        "--simulations",
        type=positive_int,
        default=1000,
        metavar="N",
        help="simulated datasets from the prior to train on (default 1000)",
    )
    command.add_argument(
        "--predictive",
        type=positive_int,
        default=100,
        metavar="N",
        help="posterior predictive simulated datasets (default 100)",
    )
    command.add_argument(
        "--fit-methods",
        nargs="+",
        choices=vocabulary.METHODS,
        default=list(vocabulary.METHODS),
        help="fit these methods' trials; the others are only predicted (default: all)",
    )
    command.add_argument(
        "--seed", type=nonnegative_int, default=0, help="seed of the fit (default 0)"
    )
    command.add_argument(
        "--cores",
        type=positive_int,
        default=os.cpu_count() or 1,
        help="processes to simulate in (default: every core)",
    )
    command.set_defaults(func=_calibrate)


def _calibrate(args) -> int:
    from casa_core.config import DEFAULT_CONFIG, load_config
    from casa_core.scene import load_scene
    from casa_core.study.settings import StudySettings

    out = Path(args.out)
    if out.suffix != ".json":
        print(
            f"casa calibrate: --out {out}: the population file must end in .json", file=sys.stderr
        )
        return 2
    config = load_config(*(args.config or [DEFAULT_CONFIG]))
    settings = StudySettings.from_config(config)
    scene_path = dataset_scene(args.dataset, args.scene)
    scene_name = scene_path or "config/scene.yaml (the package's)"
    scene = load_scene(scene_path)
    people = _read_people(args, scene, settings)
    if people is None:
        return 2
    result = _fit(args, people, scene, scene_name, settings)
    if result is None:
        return 2
    table, figure = _write(out, result, people, settings, args.seed)
    from casa_core.calibration.calibrate import beside

    predictive = result.predictive
    print(
        f"casa calibrate: {predictive['inside'].mean():.0%} of the people's cell summaries "
        f"inside the fitted model's 90% interval -> {out}, {table}, {figure}"
    )
    for row in predictive[~predictive["inside"]].itertuples():
        where = (row.task, row.method, row.summary, row.people)
        print(
            "  outside: " + beside(*where, row.simulated_low, row.simulated_high, whose="fitted ")
        )
    return 0


def _read_people(args, scene, settings):
    """The dataset's people, their warnings said; None (said why) if they cannot be read."""
    from casa_core.calibration.design import CalibrationInputError, read_people

    try:
        people = read_people(args.dataset, scene, max_duration=settings.max_duration)
    except CalibrationInputError as error:
        print(f"casa calibrate: {error}", file=sys.stderr)
        return None
    for warning in people.warnings:
        print(f"casa calibrate: warning: {warning}", file=sys.stderr)
    return people


def _fit(args, people, scene, scene_name, settings):
    """The fitted population, with a progress bar; None (said why) if the fit fails."""
    from tqdm import tqdm

    from casa_core.calibration.calibrate import calibrate
    from casa_core.calibration.simulator import Simulator

    design = people.design
    print(
        f"casa calibrate: {len(design.trials)} human trial(s) of {len(design.participants)} "
        f"participant(s) in {len(design.cells)} task-method cell(s); "
        f"{args.simulations} + {args.predictive} simulated datasets on {args.cores} core(s)",
        file=sys.stderr,
    )
    assert settings.population is not None  # the simulated study always has one
    simulator = Simulator(
        scene, design, settings.population, settings.operator, settings.inference, args.seed
    )
    with tqdm(total=args.simulations + args.predictive, unit="dataset", file=sys.stderr) as bar:
        try:
            return calibrate(
                people,
                simulator,
                simulations=args.simulations,
                predictive=args.predictive,
                seed=args.seed,
                cores=args.cores,
                fit_methods=args.fit_methods,
                progress=bar.update,
            )
        except ValueError as error:
            print(
                f"casa calibrate: dataset {args.dataset} in scene {scene_name}: {error}",
                file=sys.stderr,
            )
            return None


def _write(out: Path, result, people, settings, seed: int) -> tuple[Path, Path]:
    """Write the population file, its predictive table and figure together; their paths."""
    from casa_core.calibration.calibrate import population_document
    from casa_core.figures.calibration import plot_predictive
    from casa_core.io.atomic import atomic_paths, frame_to_csv_text
    from casa_core.io.population import write_population

    document = population_document(result, operator=settings.operator, seed=seed)
    table = out.with_name(f"{out.stem}_predictive.csv")
    figure = out.with_name(f"{out.stem}_predictive.png")
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_paths(out, table, figure) as (out_tmp, table_tmp, figure_tmp):
        write_population(out_tmp, document)
        table_tmp.write_text(frame_to_csv_text(result.predictive), encoding="utf-8")
        plot_predictive(
            result.predictive, figure_tmp, title=f"{people.dataset}: posterior predictive"
        )
    return table, figure
