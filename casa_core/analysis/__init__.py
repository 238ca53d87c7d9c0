"""From trial logs to tables: a dataset's tables, the per-trial metrics, and replayed inference.

The modules, each with one job:

- :mod:`~casa_core.analysis.datasets`: One raw dataset folder in, its processed tables out.
- :mod:`~casa_core.analysis.effort`: The user's effort, per trial, for keys and for a
  continuous device alike.
- :mod:`~casa_core.analysis.metrics`: The user study's objective metrics (paper, Sec. V-B),
  per trial.
- :mod:`~casa_core.analysis.replay`: Replay: offline inference over a recorded casa-trial/1 log.
- :mod:`~casa_core.analysis.replay_intents`: The intents a replay uses: goals of the scene,
  learned intents by name, and where the files of a participant's learned intents are found.
- :mod:`~casa_core.analysis.replay_settings`: The settings a replay uses: preset, evidence,
  arbitration, the point it measures and the path its steps read.
"""

from casa_core.analysis.datasets import (
    LIKERT_COLUMNS,
    STEP_COLUMNS,
    TRIAL_COLUMNS,
    VALIDATION_COLUMNS,
    DatasetInvalid,
    DatasetTables,
    build_tables,
    check_dataset,
    validation_table,
    write_tables,
    write_validation,
)
from casa_core.analysis.effort import (
    command_integral,
    command_time,
    commanded,
    held_directions,
    held_keys,
    key_presses,
    key_ticks,
)
from casa_core.analysis.metrics import (
    REFERENCE_CONDITION,
    REFERENCE_METHOD,
    REFERENCE_PHASES,
    arrival_time,
    efficiency_cost,
    relative_effort,
    task_success,
    timed_out,
    trajectory_error,
    trial_metrics,
)
from casa_core.analysis.replay import COLUMNS, replay_differences, replay_trial
from casa_core.analysis.replay_intents import (
    goal_position,
    kept_intent_files,
    library_files,
    resolve_intents,
)
from casa_core.analysis.replay_settings import ReplayError, replay_path, trial_point, trial_settings

__all__ = [
    "COLUMNS",
    "DatasetInvalid",
    "DatasetTables",
    "LIKERT_COLUMNS",
    "REFERENCE_CONDITION",
    "REFERENCE_METHOD",
    "REFERENCE_PHASES",
    "ReplayError",
    "STEP_COLUMNS",
    "TRIAL_COLUMNS",
    "VALIDATION_COLUMNS",
    "arrival_time",
    "build_tables",
    "check_dataset",
    "command_integral",
    "command_time",
    "commanded",
    "efficiency_cost",
    "goal_position",
    "held_directions",
    "held_keys",
    "key_presses",
    "key_ticks",
    "kept_intent_files",
    "library_files",
    "relative_effort",
    "replay_differences",
    "replay_path",
    "replay_trial",
    "resolve_intents",
    "task_success",
    "timed_out",
    "trajectory_error",
    "trial_metrics",
    "trial_point",
    "trial_settings",
    "validation_table",
    "write_tables",
    "write_validation",
]
