"""``casa library``: inspect an intent library (the learned intents' files)."""

from __future__ import annotations

import sys

from casa_core.cli._options import example


def register(commands) -> None:
    """Add ``casa library`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "library",
        help="inspect an intent library",
        description="Inspect the learned intents (casa-intent files) of a library folder.",
        **example("casa library list data/raw/simulated"),
    )
    actions = command.add_subparsers(dest="action", metavar="ACTION", required=True)
    listing = actions.add_parser(
        "list",
        help="one line per learned intent; damaged files are reported, not fatal",
        description="Print one line per intent file of DIR; if DIR holds none, of every "
        "library below it (e.g. one folder per participant), with its folder. Report each "
        "unusable file on stderr with the rule it breaks; exit 1 if any file is unusable or "
        "no intent file is found. Each line: name, task, participant, seed, demonstrations; "
        "iterations run of the most (IRLConfig.max_iterations); stopped, converged if IRL's "
        "convergence criterion held at its last iteration (its cost gap, the movement and "
        "the end of its own trajectories all below tolerance), else budget: it ran all its "
        "iterations, as it usually does, which says nothing bad of the intent; kept, the "
        "iteration whose weights the file holds, chosen by planning; end_match_m, how far "
        "that intent's own optimum ends from the demonstrations' mean end (m, plus 0.1 m "
        "per radian of rot). What tells a good intent is where its optimum ends "
        "(the simulated study's learning.csv: endpoint_error_m, final_tilt_deg); "
        "docs/data-contracts.md, Intent library.",
        **example("casa library list data/raw/simulated"),
    )
    listing.add_argument("library", metavar="DIR", help="the intent library's folder")
    listing.set_defaults(func=_library_list)


def _library_list(args) -> int:
    from pathlib import Path

    from casa_core.learning import library

    root = Path(args.library)
    if not root.is_dir():
        _, problems = library.scan_library(root)  # the one "is not a folder" problem
        for problem in problems:
            print(f"casa library: {problem}", file=sys.stderr)
        return 1
    folders = library.find_libraries(root)
    if not folders:
        print(f"casa library: no *{library.SUFFIX} file in {root} or below", file=sys.stderr)
        return 1
    n_problems = 0
    for folder in folders:
        # Each folder is one library: names are unique within it, not across participants.
        entries, problems = library.scan_library(folder)
        where = "" if folder == root else f"\tlibrary={folder.relative_to(root).as_posix()}"
        for entry in entries:
            print(entry.summary() + where)
        for problem in problems:
            print(f"casa library: {problem}", file=sys.stderr)
        n_problems += len(problems)
    return 1 if n_problems else 0
