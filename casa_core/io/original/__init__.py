"""The original implementation's session files: reading them and importing them as casa-trial/1.

The modules, each with one job:

- :mod:`~casa_core.io.original.sessions`: The original implementation's session files, read
  and converted to casa-trial/1 trials.
- :mod:`~casa_core.io.original.importer`: A folder of the original implementation's session
  files as a casa-trial/1 dataset.
"""

from casa_core.io.original.importer import (
    METHOD_LETTERS,
    ORIGINAL_SCENE,
    SCENE_NAME,
    TASK_NUMBERS,
    ImportResult,
    SessionName,
    describe,
    goal_names,
    import_original,
    parse_name,
)
from casa_core.io.original.sessions import (
    GOAL_NAMES,
    KEY_FRACTION,
    REFERENCE_ANGLES,
    REQUIRED_KEYS,
    UNKNOWN_GOAL_NAME,
    Converted,
    Session,
    SessionError,
    command_keys,
    convert_session,
    read_session,
    reference_q,
    started_at,
)

__all__ = [
    "Converted",
    "GOAL_NAMES",
    "ImportResult",
    "KEY_FRACTION",
    "METHOD_LETTERS",
    "ORIGINAL_SCENE",
    "REFERENCE_ANGLES",
    "REQUIRED_KEYS",
    "SCENE_NAME",
    "Session",
    "SessionError",
    "SessionName",
    "TASK_NUMBERS",
    "UNKNOWN_GOAL_NAME",
    "command_keys",
    "convert_session",
    "describe",
    "goal_names",
    "import_original",
    "parse_name",
    "read_session",
    "reference_q",
    "started_at",
]
