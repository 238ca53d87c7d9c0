"""``casa process``: one raw dataset folder into trials.csv, steps.csv and likert.csv."""

from __future__ import annotations

import sys

from casa_core.cli._errors import cannot_write
from casa_core.cli._options import dataset_scene, dataset_scene_option, example


def register(commands) -> None:
    """Add ``casa process`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "process",
        help="turn one raw dataset folder into trials.csv, steps.csv and likert.csv",
        description="Read the trial logs and surveys below RAW_DIR and write trials.csv, "
        "steps.csv and likert.csv into --out; exit 1 if a file is bad (see casa validate).",
        **example("casa process data/raw/mine --out data/processed/mine"),
    )
    command.add_argument("raw", metavar="RAW_DIR", help="the dataset folder, e.g. data/raw/mine")
    command.add_argument("--out", required=True, metavar="DIR", help="folder of the tables")
    dataset_scene_option(command, "RAW_DIR")
    command.add_argument("--dataset", help="dataset name in the tables (default: folder name)")
    command.add_argument(
        "--allow-invalid", action="store_true", help="exclude bad files instead of failing"
    )
    command.set_defaults(func=_process)


def _process(args) -> int:
    from casa_core.analysis import datasets
    from casa_core.scene import SceneError, load_scene

    try:
        scene = load_scene(dataset_scene(args.raw, args.scene))
    except SceneError as error:
        print(f"casa process: {error}", file=sys.stderr)
        return 1
    try:
        tables = datasets.build_tables(
            args.raw, scene, dataset=args.dataset, allow_invalid=args.allow_invalid
        )
    except datasets.DatasetInvalid as error:
        print(f"casa process: {error}", file=sys.stderr)
        return 1
    try:
        datasets.write_tables(tables, args.out)
    except OSError as error:
        return cannot_write("process", args.out, error)
    print(
        f"casa process: {len(tables.trials)} trial(s), {len(tables.steps)} step row(s), "
        f"{len(tables.likert)} Likert answer(s) -> {args.out}"
    )
    return 0
