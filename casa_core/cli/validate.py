"""``casa validate``: check trial logs and surveys against the casa-trial/1 contract."""

from __future__ import annotations

import sys
from pathlib import Path

from casa_core.cli._errors import cannot_write
from casa_core.cli._options import counted, example


def register(commands) -> None:
    """Add ``casa validate`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "validate",
        help="check trial logs and surveys against the casa-trial/1 contract",
        description="Check files and folders (recursively) against casa-trial/1; print every "
        "problem with file, row or key, and rule on standard output (so `> problems.txt` "
        "keeps them), then the counts on standard error; exit 1 if any (0 with "
        "--allow-invalid).",
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
        print(problem)
    # A path that does not exist, or a folder without logs, is a problem but not a file.
    files = [check for check in checks if check.kind not in ("missing", "folder")]
    verdict = "excluded" if args.allow_invalid else "invalid"
    bad_files = sum(not check.ok for check in files)
    for check in checks:
        if check.kind == "missing":
            print(f"casa validate: {check.file} does not exist")
    sys.stdout.flush()  # the problems before the counts, where both reach one log
    errors = [problem for problem in problems if problem.is_error]
    warned = f" ({len(problems) - len(errors)} warning(s))" if len(errors) < len(problems) else ""
    print(
        f"casa validate: {_checked(files)}, {bad_files} {verdict}, "
        f"{len(problems)} problem(s){warned}",
        file=sys.stderr,
    )
    return 1 if errors and not args.allow_invalid else 0


#: The kinds of file ``casa validate`` reads, and their words in its summary: a trial is
#: its .json and its .csv, counted once.
CHECKED_KINDS = (("trial", "trial(s)"), ("surveys", "survey file(s)"), ("scene", "scene file(s)"))
#: The kinds it lists but does not read, and their words.
UNREAD_KINDS = (("intent", "learned intent file(s)"), ("other", "other file(s)"))


def _checked(files) -> str:
    """``253 trial(s) and 11 survey file(s) checked (22 learned intent file(s) not read)``."""
    kinds = [check.kind for check in files]
    read = counted([(kinds.count(kind), word) for kind, word in CHECKED_KINDS])
    unread = [(kinds.count(kind), word) for kind, word in UNREAD_KINDS]
    if not any(count for count, _ in unread):
        return f"{read} checked"
    return f"{read} checked ({counted(unread)} not read)"
