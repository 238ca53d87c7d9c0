"""``casa import``: sessions recorded in another format into a casa-trial/1 dataset.

Named ``import_`` because ``import`` is a Python keyword.
"""

from __future__ import annotations

import sys

from casa_core.cli._options import example


def register(commands) -> None:
    """Add ``casa import`` to the ``casa`` subcommands."""
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
    from casa_core.cli.import_rosbag import register_rosbag

    register_rosbag(formats)


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
