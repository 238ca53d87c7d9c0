"""``casa case-study``: the expert case study and the arbitration comparison (one job)."""

from __future__ import annotations

import sys

from casa_core.cli._options import example
from casa_core.cli._workflow import add_config_option, load_workflow_config


def register(commands) -> None:
    """Add ``casa case-study`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "case-study",
        help="the expert case study and the arbitration comparison",
        description="Run the simulated expert through the tasks (learning included) and the "
        "three arbitrations along one trajectory; write steps.csv and arbitration.csv.",
        **example(
            "casa case-study --work data/interim/case_study "
            "--steps data/processed/case_study/steps.csv \\",
            "    --arbitration data/processed/case_study/arbitration.csv",
        ),
    )
    add_config_option(command)
    command.add_argument("--work", required=True, help="folder for the expert's logs and intents")
    command.add_argument("--steps", required=True, help="steps.csv to write")
    command.add_argument("--arbitration", required=True, help="arbitration.csv to write")
    command.set_defaults(func=_case_study)


def _case_study(args) -> int:
    from pathlib import Path

    from casa_core.io import LogError
    from casa_core.io.atomic import write_csv
    from casa_core.study import simulate
    from casa_core.study.settings import StudySettings

    config, scene = load_workflow_config(args)
    try:
        steps, arbitration = simulate.run_case_study(
            scene, StudySettings.from_case_study(config), work_dir=Path(args.work)
        )
    except (LogError, OSError, ValueError) as error:
        print(f"casa case-study: {error}", file=sys.stderr)
        return 2
    write_csv(args.steps, steps)
    write_csv(args.arbitration, arbitration)
    print(f"casa case-study: {len(steps)} step row(s), {len(arbitration)} arbitration row(s)")
    return 0
