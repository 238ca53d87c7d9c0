"""The original implementation's session files: reading them and importing them as casa-trial/1.

The modules, each with one job:

- :mod:`~casa_core.io.original.sessions`: The original implementation's session files, read
  and checked.
- :mod:`~casa_core.io.original.conversion`: One session of the original implementation as a
  casa-trial/1 trial.
- :mod:`~casa_core.io.original.numerics`: What the original implementation computed at an
  inference step, its defects included.
- :mod:`~casa_core.io.original.importer`: A folder of the original implementation's session
  files as a casa-trial/1 dataset.
"""

from casa_core.io.original.conversion import (
    KEY_FRACTION,
    Converted,
    command_keys,
    convert_session,
    inference_steps,
)
from casa_core.io.original.importer import (
    METHOD_LETTERS,
    ORIGINAL_SCENE,
    TASK_NUMBERS,
    ImportResult,
    SessionName,
    describe,
    goal_names,
    import_original,
    parse_name,
)
from casa_core.io.original.numerics import OriginalStep, original_rows, original_step
from casa_core.io.original.sessions import (
    REFERENCE_ANGLES,
    REQUIRED_KEYS,
    Session,
    SessionError,
    read_session,
    reference_q,
    started_at,
    step_waypoints,
)

__all__ = [
    "Converted",
    "ImportResult",
    "KEY_FRACTION",
    "METHOD_LETTERS",
    "ORIGINAL_SCENE",
    "OriginalStep",
    "REFERENCE_ANGLES",
    "REQUIRED_KEYS",
    "Session",
    "SessionError",
    "SessionName",
    "TASK_NUMBERS",
    "command_keys",
    "convert_session",
    "describe",
    "goal_names",
    "import_original",
    "inference_steps",
    "original_rows",
    "original_step",
    "parse_name",
    "read_session",
    "reference_q",
    "started_at",
    "step_waypoints",
]
