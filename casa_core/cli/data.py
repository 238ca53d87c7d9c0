"""``casa validate``, ``casa process``, ``casa stats`` and ``casa import``: raw logs to tables."""

from __future__ import annotations

import sys
from pathlib import Path

from casa_core.cli._errors import cannot_write
from casa_core.cli._options import example
from casa_core.io import read_table


def register(commands) -> None:
    """Add this module's commands to the ``casa`` subcommands."""
    _add_validate(commands)
    _add_process(commands)
    _add_stats(commands)
    _add_import(commands)


def _add_validate(commands) -> None:
    command = commands.add_parser(
        "validate",
        help="check trial logs and surveys against the casa-trial/1 contract",
        description="Check files and folders (recursively) against casa-trial/1; print every "
        "problem with file, row or key, and rule; exit 1 if any (0 with --allow-invalid).",
        **example("casa validate data/raw/mine --report data/processed/mine/validation.csv"),
    )
    command.add_argument("paths", nargs="+", metavar="PATH", help="a log file or a folder")
    command.add_argument("--report", metavar="CSV", help="also write validation.csv here")
    command.add_argument(
        "--allow-invalid",
        action="store_true",
        help="report bad files as excluded and exit 0 (the DAG then leaves them out)",
    )
    command.set_defaults(func=_validate)


def _validate(args) -> int:
    from casa_core.analysis import datasets
    from casa_core.io import check_paths

    if args.report:
        try:
            checks = datasets.write_validation(
                args.paths, args.report, allow_invalid=args.allow_invalid
            )
        except OSError as error:
            return cannot_write("validate", Path(args.report).parent, error)
    else:
        checks = check_paths(args.paths)
    problems = [problem for check in checks for problem in check.problems]
    for problem in problems:
        print(problem, file=sys.stderr)
    # A path that does not exist, or a folder without logs, is a problem but not a file.
    files = [check for check in checks if check.kind not in ("missing", "folder")]
    verdict = "excluded" if args.allow_invalid else "invalid"
    bad_files = sum(not check.ok for check in files)
    for check in checks:
        if check.kind == "missing":
            print(f"casa validate: {check.file} does not exist", file=sys.stderr)
    errors = [problem for problem in problems if problem.is_error]
    warned = f" ({len(problems) - len(errors)} warning(s))" if len(errors) < len(problems) else ""
    print(
        f"casa validate: {len(files)} file(s) checked, {bad_files} {verdict}, "
        f"{len(problems)} problem(s){warned}",
        file=sys.stderr,
    )
    return 1 if errors and not args.allow_invalid else 0


def _add_process(commands) -> None:
    command = commands.add_parser(
        "process",
        help="turn one raw dataset folder into trials.csv, steps.csv and likert.csv",
        description="Read the trial logs and surveys below RAW_DIR and write trials.csv, "
        "steps.csv and likert.csv into --out; exit 1 if a file is bad (see casa validate).",
        **example("casa process data/raw/mine --out data/processed/mine --scene config/scene.yaml"),
    )
    command.add_argument("raw", metavar="RAW_DIR", help="the dataset folder, e.g. data/raw/mine")
    command.add_argument("--out", required=True, metavar="DIR", help="folder of the tables")
    command.add_argument("--scene", required=True, metavar="YAML", help="config/scene.yaml")
    command.add_argument("--dataset", help="dataset name in the tables (default: folder name)")
    command.add_argument(
        "--allow-invalid", action="store_true", help="exclude bad files instead of failing"
    )
    command.set_defaults(func=_process)


def _process(args) -> int:
    from casa_core.analysis import datasets
    from casa_core.scene import SceneError, load_scene

    try:
        scene = load_scene(args.scene)
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


def _add_stats(commands) -> None:
    command = commands.add_parser(
        "stats",
        help="the study's statistics (H1-H4): stats.csv and an APA-style Markdown report",
        description="Run the study's analyses on trials.csv (and likert.csv) and write "
        "stats.csv and its APA-style rendering.",
        **example(
            "casa stats --trials data/processed/mine/trials.csv "
            "--likert data/processed/mine/likert.csv \\",
            "    --out-csv data/processed/mine/stats.csv --out-md data/processed/mine/stats.md",
        ),
    )
    command.add_argument("--trials", required=True, metavar="CSV", help="trials.csv")
    command.add_argument("--likert", metavar="CSV", help="likert.csv (optional)")
    command.add_argument("--out-csv", required=True, metavar="CSV", help="stats.csv to write")
    command.add_argument("--out-md", required=True, metavar="MD", help="report to write")
    command.add_argument(
        "--margin",
        action="append",
        default=[],
        metavar="[TASK:]METRIC=VALUE",
        help="a non-inferiority margin in the metric's unit (repeatable; the workflow "
        "passes the config's statistics.noninferiority_margins)",
    )
    command.add_argument(
        "--margin-fraction",
        action="append",
        default=[],
        metavar="[TASK:]METRIC=VALUE",
        help="a margin as a fraction of the reference condition's mean (repeatable; "
        "statistics.noninferiority_fractions)",
    )
    command.set_defaults(func=_stats)


def _stats(args) -> int:
    from casa_core import stats
    from casa_core.io.atomic import atomic_paths, frame_to_csv_text
    from casa_core.stats.margins import Margins, parse_margin

    try:
        margins = Margins(
            absolute=dict(parse_margin(text, "--margin") for text in args.margin),
            fractions=dict(
                parse_margin(text, "--margin-fraction") for text in args.margin_fraction
            ),
        )
    except ValueError as error:
        print(f"casa stats: {error}", file=sys.stderr)
        return 2
    try:
        # read_table keeps the method "NA" as text (pandas' default would make it missing).
        trials = read_table(args.trials)
        likert = read_table(args.likert) if args.likert else None
        table = stats.analyze_study(trials, likert, margins=margins)
        report = stats.report_markdown(table, trials=trials)
    except (OSError, ValueError) as error:
        print(f"casa stats: {error}", file=sys.stderr)
        return 1
    texts = (frame_to_csv_text(table), report)
    try:
        # The table and its report belong together: both or neither are replaced.
        with atomic_paths(args.out_csv, args.out_md) as temporaries:
            for tmp, text in zip(temporaries, texts, strict=True):
                tmp.write_bytes(text.encode("utf-8"))
    except OSError as error:
        folder = Path(error.filename).parent if error.filename else Path(args.out_csv).parent
        return cannot_write("stats", folder, error)
    # A test that ran has a p-value or an estimate; a skipped one has neither.
    skipped = int((table["p"].isna() & table["estimate"].isna()).sum())
    print(f"casa stats: {len(table)} row(s) -> {args.out_csv}, {args.out_md}")
    if skipped:
        print(f"casa stats: {skipped} test(s) skipped, see their note", file=sys.stderr)
    return 0


def _add_import(commands) -> None:
    command = commands.add_parser(
        "import",
        help="convert sessions recorded in another format into a casa-trial/1 dataset",
        **example("casa import original sessions/P03 --out data/raw/original"),
    )
    formats = command.add_subparsers(dest="format", metavar="FORMAT", required=True)
    original = formats.add_parser(
        "original",
        help="the original implementation's task<N><letter>_data.npz session files",
        description="Convert one participant's session files of the original implementation "
        "(DIR, only read) into OUT/<participant>/<stem>.json and .csv, and copy the scene of "
        "the original's layout to OUT/scene.yaml; exit 2 naming the file and the key if a file "
        "cannot be converted (nothing is written then). Rules: docs/data-contracts.md.",
        **example("casa import original sessions/P03 --out data/raw/original --participant P03"),
    )
    original.add_argument("folder", metavar="DIR", help="one participant's session files")
    original.add_argument("--out", required=True, metavar="DIR", help="the dataset folder")
    original.add_argument("--participant", help="participant id (default: DIR's folder name)")
    original.add_argument(
        "--scene",
        metavar="YAML",
        help="scene copied to OUT/scene.yaml (default: the package's config/scene-original.yaml)",
    )
    original.add_argument("--force", action="store_true", help="replace trials already there")
    original.add_argument(
        "--skip-bad", action="store_true", help="leave out (and list) files that cannot be read"
    )
    original.set_defaults(func=_import_original)


def _import_original(args) -> int:
    from casa_core.io.original.importer import describe, import_original
    from casa_core.io.original.sessions import SessionError

    try:
        result = import_original(
            args.folder,
            args.out,
            participant=args.participant,
            scene=args.scene,
            force=args.force,
            skip_bad=args.skip_bad,
        )
    except SessionError as error:
        for problem in error.problems:
            print(problem, file=sys.stderr)
        files = len({problem.file for problem in error.problems})
        print(
            f"casa import original: {len(error.problems)} problem(s) in {files} file(s); "
            "nothing written",
            file=sys.stderr,
        )
        return 2
    print(describe(result, args.out))
    return 0
